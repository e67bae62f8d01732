//! Shared by the rotary CNN-LSTM examples: their command-line flags and the dataset export
//! that `bench/cnn_lstm.sh` reads, and the real-data example's flags.
#![allow(dead_code)] // each example uses its own part of this module

use mtec_nn::ThermalDataset;

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
