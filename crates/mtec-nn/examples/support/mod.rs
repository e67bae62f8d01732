//! Shared by the rotary CNN-LSTM examples: their command-line flags and the dataset export
//! that `bench/cnn_lstm.sh` reads, and the real-data example's flags.
#![allow(dead_code)] // each example uses its own part of this module

use mtec_nn::thermal_fit::{target_metrics, NeuralThermalModel, Training};
use mtec_nn::{CnnLstmReport, NeuralFit, Quiet};
use mtec_thermal::validate::rows_of_experiments;
use mtec_thermal::{Fit, Metrics, ThermalData};

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

/// Writes the data as `DIR/rotary.csv` (the bench's exchange format), the inputs and targets
/// as `fit` trains on them.
pub fn export(data: &ThermalData, fit: &NeuralFit, dir: &str) {
    std::fs::create_dir_all(dir).expect("create export dir");
    let csv = fit.exchange_csv(data).expect("export");
    std::fs::write(format!("{dir}/rotary.csv"), csv).expect("write export");
}

/// The rows of the experiments `ids`.
pub fn rows_of(data: &ThermalData, ids: &[u32]) -> Vec<usize> {
    let ids: Vec<String> = ids.iter().map(|e| e.to_string()).collect();
    rows_of_experiments(data, &ids).expect("experiments")
}

/// Every target of every row of `d` (rows × targets).
pub fn targets(d: &ThermalData) -> Vec<Vec<f64>> {
    let t = d.targets();
    (0..d.len())
        .map(|i| t.iter().map(|(_, y)| y[i]).collect())
        .collect()
}

/// RMSE over all channels together (√ of the mean of the squared per-channel RMSEs).
pub fn overall_rmse(m: &[(String, Metrics)]) -> f64 {
    (m.iter().map(|(_, m)| m.rmse_um.powi(2)).sum::<f64>() / m.len().max(1) as f64).sqrt()
}

/// Both networks trained on the same experiments and scored on the same held-out ones.
pub struct Comparison {
    pub cnn_lstm: NeuralThermalModel,
    pub bpnn: NeuralThermalModel,
    pub cnn_lstm_training: CnnLstmReport,
    /// mtec-thermal's metrics per target on the held-out rows, and each target's range there.
    pub cnn_lstm_metrics: Vec<(String, Metrics)>,
    pub bpnn_metrics: Vec<(String, Metrics)>,
    pub ranges: Vec<f64>,
    /// The held-out rows.
    pub test: ThermalData,
}

/// Trains `cnn` and `bpnn` on the experiments `train` of `data` and scores both on `test`.
pub fn compare(
    data: &ThermalData,
    train: &[u32],
    test: &[u32],
    cnn: &NeuralFit,
    bpnn: &NeuralFit,
) -> Comparison {
    let train = rows_of(data, train);
    let test = data.rows(&rows_of(data, test));
    let (cnn_lstm, training) =
        (cnn.fit_rows_monitored(data, &train, &mut Quiet)).expect("cnn-lstm");
    let Training::CnnLstm(cnn_lstm_training) = training else {
        panic!("a CNN-LSTM")
    };
    let bpnn = bpnn.fit_rows(data, &train).expect("bpnn");
    let score = |m: &NeuralThermalModel| {
        let p = m.predict_targets(&test).expect("predict");
        target_metrics(&test, &p, m.input_names().len()).expect("metrics")
    };
    let ranges = (test.targets().iter())
        .map(|(_, y)| {
            let hi = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            hi - y.iter().copied().fold(f64::INFINITY, f64::min)
        })
        .collect();
    Comparison {
        cnn_lstm_metrics: score(&cnn_lstm),
        bpnn_metrics: score(&bpnn),
        cnn_lstm,
        bpnn,
        cnn_lstm_training,
        ranges,
        test,
    }
}

/// Both models' test metrics per channel and overall (ratio: max residual over the range).
pub fn print_comparison(cmp: &Comparison) {
    println!("channel    CNN-LSTM rmse  mae  ratio | BPNN rmse  mae  ratio | range");
    for (((name, m), (_, n)), r) in cmp
        .cnn_lstm_metrics
        .iter()
        .zip(&cmp.bpnn_metrics)
        .zip(&cmp.ranges)
    {
        println!(
            "{:9} {:8.3} {:6.3} {:6.3} | {:8.3} {:6.3} {:6.3} | {:6.2}",
            name,
            m.rmse_um,
            m.mae_um,
            m.max_abs_residual_um / r,
            n.rmse_um,
            n.mae_um,
            n.max_abs_residual_um / r,
            r
        );
    }
    println!(
        "overall test RMSE: CNN-LSTM {:.4}, BPNN {:.4}",
        overall_rmse(&cmp.cnn_lstm_metrics),
        overall_rmse(&cmp.bpnn_metrics)
    );
}

/// The lines `bench/cnn_lstm.sh` reads: seconds per epoch and the overall test RMSE.
pub fn print_bench_lines(cmp: &Comparison) {
    let r = &cmp.cnn_lstm_training;
    println!("MTEC_SECONDS_PER_EPOCH={:.6}", r.seconds_per_epoch);
    println!("MTEC_TEST_RMSE={:.6}", overall_rmse(&cmp.cnn_lstm_metrics));
}
