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
use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_nn::NeuralFit;
use support::{compare, export, print_bench_lines, print_comparison, ExampleArgs};

fn main() {
    for (var, value) in mtec_nn::threads::single_thread_settings() {
        std::env::set_var(var, value);
    }
    let args = ExampleArgs::from_env();
    let arg = |name: &str| args.value(name);
    let spec = RotaryThermalSpec {
        angles: 24,
        ..RotaryThermalSpec::default()
    };
    let data = rotary_thermal(&spec);
    // T1..T9 (every `_c` column) and the angle as cos and sin; the source-sized CNN-LSTM
    let fit = |options| NeuralFit {
        options,
        sensors: vec![],
        inputs: vec!["cos_angle".into(), "sin_angle".into()],
    };
    let mut cnn = NnFitOptions::new(NnKind::CnnLstm);
    cnn.epochs = arg("--epochs").map(|n| n.parse().expect("--epochs N"));
    if args.flag("--fixed") {
        cnn.patience = Some(usize::MAX / 2);
    }
    let mut bpnn = NnFitOptions::new(NnKind::Bpnn);
    (bpnn.hidden, bpnn.epochs) = (Some(10), Some(200));
    let (cnn, bpnn) = (fit(cnn), fit(bpnn));
    if let Some(dir) = arg("--export") {
        export(&data, &cnn, &dir);
    }
    let cmp = compare(&data, &[1, 2, 4], &[3], &cnn, &bpnn);
    let r = &cmp.cnn_lstm_training;
    println!(
        "CNN-LSTM: {} parameters, {} train windows, {} epochs (best {}), {:.2} s, {:.4} s/epoch",
        r.parameters, r.train_windows, r.epochs, r.best_epoch, r.seconds, r.seconds_per_epoch
    );
    print_comparison(&cmp);
    print_bench_lines(&cmp);
}
