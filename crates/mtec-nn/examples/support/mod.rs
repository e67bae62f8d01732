//! Shared by the rotary CNN-LSTM examples: their command-line flags and the dataset export
//! that `bench/cnn_lstm.sh` reads, and the real-data example's flags.
#![allow(dead_code)] // each example uses its own part of this module

use mtec_nn::{SplitComparison, ThermalDataset};

/// The example's command line.
pub struct ExampleArgs(Vec<String>);

impl ExampleArgs {
    pub fn from_env() -> ExampleArgs {
        ExampleArgs(std::env::args().collect())
    }
    /// The value after `--name`, if given.
    pub fn value(&self, name: &str) -> Option<String> {
        self.0
            .iter()
            .position(|a| a == name)
            .and_then(|i| self.0.get(i + 1))
            .cloned()
    }
    /// Whether the flag `--name` is given.
    pub fn flag(&self, name: &str) -> bool {
        self.0.iter().any(|a| a == name)
    }
}

/// Writes the dataset as `DIR/rotary.csv` (the bench's exchange format).
pub fn export(d: &ThermalDataset, dir: &str) {
    std::fs::create_dir_all(dir).expect("create export dir");
    std::fs::write(format!("{dir}/rotary.csv"), d.to_csv()).expect("write export");
}

/// Both models' test metrics per channel and overall.
pub fn print_comparison(cmp: &SplitComparison) {
    println!("channel    CNN-LSTM rmse  mae  ratio | BPNN rmse  mae  ratio | range");
    for (m, n) in cmp.cnn_lstm.iter().zip(&cmp.bpnn) {
        println!(
            "{:9} {:8.3} {:6.3} {:6.3} | {:8.3} {:6.3} {:6.3} | {:6.2}",
            m.channel, m.rmse, m.mae, m.residual_ratio, n.rmse, n.mae, n.residual_ratio, m.range
        );
    }
    println!(
        "overall test RMSE: CNN-LSTM {:.4}, BPNN {:.4}",
        SplitComparison::overall_rmse(&cmp.cnn_lstm),
        SplitComparison::overall_rmse(&cmp.bpnn)
    );
}

/// The lines `bench/cnn_lstm.sh` reads: seconds per epoch and the overall test RMSE.
pub fn print_bench_lines(cmp: &SplitComparison) {
    let r = &cmp.cnn_lstm_training;
    println!("MTEC_SECONDS_PER_EPOCH={:.6}", r.seconds_per_epoch);
    println!(
        "MTEC_TEST_RMSE={:.6}",
        SplitComparison::overall_rmse(&cmp.cnn_lstm)
    );
}
