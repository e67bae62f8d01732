//! The source-sized CNN-LSTM on rotary-axis thermal data of the `dbb-rotary` shape (synthetic,
//! see `mtec_nn::synthetic`): trained on experiments 1, 2, 4, tested on 3, against the BPNN
//! baseline. Prints the training time (goal: < 60 s on 2 cores in release).
//!
//!     cargo run --release -p mtec-nn --example rotary_cnn_lstm [-- --epochs N --fixed --export DIR]
//!
//! `--fixed` trains exactly N epochs (no early stopping) for timing against PyTorch;
//! `--export DIR` writes the data as CSV for `bench/cnn_lstm.sh`.

mod support;

use mtec_nn::synthetic::{rotary_thermal, RotaryThermalSpec};
use mtec_nn::{compare_on_split, BpnnTrainConfig, CnnLstmConfig};
use support::{export, print_bench_lines, print_comparison, ExampleArgs};

fn main() {
    if let Some((var, value)) = mtec_nn::threads::single_thread_setting() {
        std::env::set_var(var, value);
    }
    let args = ExampleArgs::from_env();
    let arg = |name: &str| args.value(name);
    let fixed = args.flag("--fixed");
    let spec = RotaryThermalSpec {
        angles: 24,
        ..RotaryThermalSpec::default()
    };
    let data = rotary_thermal(&spec);
    if let Some(dir) = arg("--export") {
        export(&data, &dir);
    }
    let mut cfg = CnnLstmConfig {
        ..CnnLstmConfig::default()
    };
    if let Some(n) = arg("--epochs") {
        cfg.max_epochs = n.parse().expect("--epochs N");
    }
    if fixed {
        cfg.patience = usize::MAX / 2;
    }
    let bpnn_cfg = BpnnTrainConfig {
        hidden: 10,
        max_epochs: 200,
        ..BpnnTrainConfig::default()
    };
    let (_, _, cmp) = compare_on_split(&data, &[1, 2, 4], &[3], &cfg, &bpnn_cfg).expect("training");
    let r = &cmp.cnn_lstm_training;
    println!(
        "CNN-LSTM: {} parameters, {} train windows, {} epochs (best {}), {:.2} s, {:.4} s/epoch",
        r.parameters, r.train_windows, r.epochs, r.best_epoch, r.seconds, r.seconds_per_epoch
    );
    print_comparison(&cmp);
    print_bench_lines(&cmp);
}
