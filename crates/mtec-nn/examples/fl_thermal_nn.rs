//! CNN-LSTM on the real thermal-drift record `../shared/data/fl-thermal/train.csv` with
//! block-wise validation, compared on the same folds with the BPNN baseline and an all-sensor
//! MLR (the thermal issue's reference: least squares with intercept on the 16 temperatures).
//!
//!     cargo run --release -p mtec-nn --example fl_thermal_nn -- [PATH.csv] [--step N]
//!         [--block-min M] [--rpm]
//!
//! Folds: by default the record is cut into its four 8-hour run+rest cycles and each cycle in
//! turn is left out whole; with `--block-min M` into blocks of M minutes of `time_min` — the
//! thermal issue's `--block-min 240` on `examples/fl-thermal/train_1min.csv` gives its eight
//! folds, so the numbers compare with `thermal cv` and the heat-input model directly (the MLR
//! column reproduces that all-sensor MLR). The models train on the other folds and
//! score the left-out one.
//!
//! Features: the 16 temperatures (and `spindle_rpm` with `--rpm`), every N-th row (`--step`,
//! default 8: 15 s → 2 min); targets ch1..ch5 (µm). The CNN-LSTM's window covers 30 min; a
//! left-out fold's windows see the features of the 30 min before it (`warmup`), never a
//! displacement of the fold.

mod support;

use mtec_io::Table;
use mtec_nn::cnn_lstm::Architecture;
use mtec_nn::{
    evaluate_bpnn, train_bpnn_baseline, train_cnn_lstm, BpnnTrainConfig, CnnLstmConfig, Experiment,
    Sequence, ThermalDataset,
};
use nalgebra::{DMatrix, DVector};
use std::path::Path;
use support::ExampleArgs;

/// History the CNN-LSTM sees (min).
const WINDOW_MIN: f64 = 30.0;

fn main() {
    let args = ExampleArgs::from_env();
    let path = std::env::args()
        .nth(1)
        .filter(|a| !a.starts_with("--"))
        .unwrap_or_else(|| "/work/shared/data/fl-thermal/train.csv".into());
    let step: usize = args
        .value("--step")
        .map_or(8, |s| s.parse().expect("--step N"));
    let block_min: Option<f64> = args
        .value("--block-min")
        .map(|s| s.parse().expect("--block-min M"));
    let table = Table::read(Path::new(&path)).unwrap_or_else(|e| panic!("{e}"));
    let mut inputs: Vec<String> = (1..=16).map(|i| format!("t{i}_c")).collect();
    if args.flag("--rpm") {
        inputs.push("spindle_rpm".into());
    }
    let chans: Vec<String> = (1..=5).map(|i| format!("ch{i}_um")).collect();
    let col = |n: &str| table.f64_column(n).unwrap_or_else(|e| panic!("{e}"));
    let rpm = col("spindle_rpm");
    let time = col("time_min");
    let icols: Vec<Vec<f64>> = inputs.iter().map(|n| col(n)).collect();
    let ccols: Vec<Vec<f64>> = chans.iter().map(|n| col(n)).collect();
    let rows: Vec<usize> = (0..rpm.len()).step_by(step.max(1)).collect();
    let dt = time[rows[1]] - time[rows[0]];
    let window = ((WINDOW_MIN / dt).round() as usize).max(2);
    let feat = |r: usize| icols.iter().map(|c| c[r]).collect::<Vec<f64>>();
    let targ = |r: usize| ccols.iter().map(|c| c[r]).collect::<Vec<f64>>();
    // fold starts (indices into `rows`)
    let mut starts = vec![0usize];
    match block_min {
        // as `mtec_thermal::validate::time_blocks`: a trailing block shorter than half a block
        // joins the one before it
        Some(m) => {
            for (k, w) in rows.windows(2).enumerate() {
                if (time[w[1]] / m).floor() > (time[w[0]] / m).floor() {
                    starts.push(k + 1);
                }
            }
            let last = *starts.last().expect("a start");
            if starts.len() > 1 && time[rows[rows.len() - 1]] - time[rows[last]] < 0.5 * m {
                starts.pop();
            }
        }
        // a cycle starts where the spindle starts after a rest of more than an hour
        None => {
            for (k, w) in rows.windows(2).enumerate() {
                if rpm[w[0]] == 0.0 && rpm[w[1]] > 0.0 && (k + 1) as f64 * dt > 60.0 {
                    starts.push(k + 1);
                }
            }
        }
    }
    starts.push(rows.len());
    println!(
        "{} rows at {dt} min, window {window} rows; folds start at rows {:?}",
        rows.len(),
        &starts[..starts.len() - 1]
    );
    let n_cycles = starts.len() - 1;
    let cycle = |c: usize| -> Experiment {
        let (a, b) = (starts[c], starts[c + 1]);
        let w0 = a.saturating_sub(window - 1);
        let idx: Vec<usize> = (w0..b).map(|k| rows[k]).collect();
        Experiment {
            id: c as u32 + 1,
            sequences: vec![Sequence {
                features: idx.iter().map(|&r| feat(r)).collect(),
                targets: idx.iter().map(|&r| targ(r)).collect(),
                warmup: a - w0,
            }],
        }
    };
    let data = ThermalDataset {
        feature_names: inputs.clone(),
        target_names: chans.clone(),
        experiments: (0..n_cycles).map(cycle).collect(),
    };
    let cfg = CnnLstmConfig {
        architecture: Architecture {
            window,
            conv_channels: 8,
            kernel: 3,
            lstm_hidden: 24,
        },
        max_epochs: 25,
        batch_size: 64,
        learning_rate: 3e-3,
        patience: 6,
        ..CnnLstmConfig::default()
    };
    let bpnn_cfg = BpnnTrainConfig {
        hidden: 10,
        max_epochs: 30,
        ..BpnnTrainConfig::default()
    };
    let mut sq = [[0.0f64; 5]; 3];
    let mut n_total = 0usize;
    for c in 1..=n_cycles as u32 {
        let train_ids: Vec<u32> = (1..=n_cycles as u32).filter(|&k| k != c).collect();
        let (train, test) = data.split(&train_ids, &[c]).expect("split");
        let (cnn, rep) = train_cnn_lstm(&train, &cfg).expect("cnn-lstm");
        let m_cnn = cnn.evaluate(&test).expect("eval");
        let (bp, _) = train_bpnn_baseline(&train, &bpnn_cfg).expect("bpnn");
        let m_bp = evaluate_bpnn(&bp, &test).expect("eval");
        let m_mlr = mlr(&train, &test);
        let n = m_cnn[0].n;
        n_total += n;
        println!(
            "left out fold {c} ({n} rows; CNN-LSTM {} epochs, {:.1} s):",
            rep.epochs, rep.seconds
        );
        for ch in 0..5 {
            println!(
                "  {}  CNN-LSTM {:6.3}  BPNN {:6.3}  MLR {:6.3} µm RMSE",
                chans[ch], m_cnn[ch].rmse, m_bp[ch].rmse, m_mlr[ch]
            );
            sq[0][ch] += m_cnn[ch].rmse.powi(2) * n as f64;
            sq[1][ch] += m_bp[ch].rmse.powi(2) * n as f64;
            sq[2][ch] += m_mlr[ch].powi(2) * n as f64;
        }
    }
    println!("pooled over the {n_cycles} left-out folds (RMSE µm):");
    println!("  channel  CNN-LSTM   BPNN   MLR");
    for ch in 0..5 {
        let f = |m: usize| (sq[m][ch] / n_total as f64).sqrt();
        println!("  {}  {:8.3} {:7.3} {:8.3}", chans[ch], f(0), f(1), f(2));
    }
}

/// Multiple linear regression with intercept on every feature (least squares by SVD), RMSE per
/// channel.
fn mlr(train: &ThermalDataset, test: &ThermalDataset) -> Vec<f64> {
    let (x, y) = train.rows();
    let (xt, yt) = test.rows();
    let design = |x: &[Vec<f64>]| {
        DMatrix::from_fn(x.len(), x[0].len() + 1, |i, j| {
            if j == 0 {
                1.0
            } else {
                x[i][j - 1]
            }
        })
    };
    let a = design(&x);
    let at = design(&xt);
    let svd = a.svd(true, true);
    (0..y[0].len())
        .map(|ch| {
            let b = DVector::from_iterator(y.len(), y.iter().map(|r| r[ch]));
            let coef = svd.solve(&b, 1e-12).expect("svd solve");
            let pred = &at * coef;
            let se: f64 = yt
                .iter()
                .enumerate()
                .map(|(i, r)| (pred[i] - r[ch]).powi(2))
                .sum();
            (se / yt.len() as f64).sqrt()
        })
        .collect()
}
