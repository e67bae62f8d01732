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
//! default 8: 15 s → 2 min); targets ch1..ch5 (µm). Both networks are `NeuralFit`s on the
//! record as mtec-thermal's `ThermalData`, fitted on the rows of the other folds
//! (`Fit::fit_rows`) and scored with `Metrics`. The CNN-LSTM's window covers 30 min; the
//! training windows after a left-out fold see its features as history, never its displacement,
//! and its own windows see the 30 min before it.

mod support;

use mtec_io::Table;
use mtec_nn::thermal_fit::{target_metrics, Training};
use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_nn::{NeuralFit, Quiet};
use mtec_thermal::{Fit, ThermalData};
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
    let n = rows.len();
    let mut targets = chans.iter().zip(&ccols).map(|(name, c)| {
        let y: Vec<f64> = rows.iter().map(|&r| c[r]).collect();
        (name.clone(), y)
    });
    let data = ThermalData {
        experiment: vec!["1".into(); n],
        time_min: rows.iter().map(|&r| time[r]).collect(),
        sensor_names: inputs.clone(),
        temps_c: DMatrix::from_fn(n, inputs.len(), |i, j| icols[j][rows[i]]),
        ambient_c: None,
        position_mm: None,
        target: targets.next(),
        more_targets: targets.collect(),
        sequence: None,
        source: None,
        lines: rows.iter().map(|&r| r + 2).collect(),
    };
    let fit = |options| NeuralFit {
        options,
        sensors: inputs.clone(),
        inputs: vec![],
    };
    let mut cnn = NnFitOptions::new(NnKind::CnnLstm);
    (cnn.window, cnn.conv_channels, cnn.lstm_hidden) = (Some(window), Some(8), Some(24));
    (cnn.epochs, cnn.batch_size, cnn.learning_rate) = (Some(25), Some(64), Some(3e-3));
    cnn.patience = Some(6);
    let mut bpnn = NnFitOptions::new(NnKind::Bpnn);
    (bpnn.hidden, bpnn.epochs) = (Some(10), Some(30));
    let (cnn, bpnn) = (fit(cnn), fit(bpnn));
    let mut sq = [[0.0f64; 5]; 3];
    let mut n_total = 0usize;
    for c in 0..n_cycles {
        let span = starts[c]..starts[c + 1];
        let fold: Vec<usize> = span.clone().collect();
        let train: Vec<usize> = (0..n).filter(|k| !span.contains(k)).collect();
        let test = data.rows(&fold);
        let (m, training) = cnn
            .fit_rows_monitored(&data, &train, &mut Quiet)
            .expect("cnn-lstm");
        let Training::CnnLstm(rep) = training else {
            panic!("a CNN-LSTM")
        };
        // the fold's windows see the rows before it: predict the whole record, score the fold
        let score = |pred: Vec<Vec<f64>>| {
            let p: Vec<Vec<f64>> = fold.iter().map(|&k| pred[k].clone()).collect();
            target_metrics(&test, &p, inputs.len()).expect("metrics")
        };
        let m_cnn = score(m.predict_targets(&data).expect("cnn-lstm"));
        let bp = bpnn.fit_rows(&data, &train).expect("bpnn");
        let m_bp = score(bp.predict_targets(&data).expect("bpnn"));
        let m_mlr = mlr(&data, &train, &fold);
        let nf = fold.len();
        n_total += nf;
        println!(
            "left out fold {} ({nf} rows; CNN-LSTM {} epochs, {:.1} s):",
            c + 1,
            rep.epochs,
            rep.seconds
        );
        for ch in 0..5 {
            let (a, b) = (m_cnn[ch].1.rmse_um, m_bp[ch].1.rmse_um);
            println!(
                "  {}  CNN-LSTM {a:6.3}  BPNN {b:6.3}  MLR {:6.3} µm RMSE",
                chans[ch], m_mlr[ch]
            );
            sq[0][ch] += a.powi(2) * nf as f64;
            sq[1][ch] += b.powi(2) * nf as f64;
            sq[2][ch] += m_mlr[ch].powi(2) * nf as f64;
        }
    }
    println!("pooled over the {n_cycles} left-out folds (RMSE µm):");
    println!("  channel  CNN-LSTM   BPNN   MLR");
    for ch in 0..5 {
        let f = |m: usize| (sq[m][ch] / n_total as f64).sqrt();
        println!("  {}  {:8.3} {:7.3} {:8.3}", chans[ch], f(0), f(1), f(2));
    }
}

/// Multiple linear regression with intercept on every column of `data` (least squares by SVD),
/// fitted on the rows `train`: RMSE per target on the rows `test`.
fn mlr(data: &ThermalData, train: &[usize], test: &[usize]) -> Vec<f64> {
    let design = |rows: &[usize]| {
        DMatrix::from_fn(rows.len(), data.temps_c.ncols() + 1, |i, j| {
            if j == 0 {
                1.0
            } else {
                data.temps_c[(rows[i], j - 1)]
            }
        })
    };
    let svd = design(train).svd(true, true);
    let at = design(test);
    (data.targets().iter())
        .map(|(_, y)| {
            let b = DVector::from_iterator(train.len(), train.iter().map(|&r| y[r]));
            let coef = svd.solve(&b, 1e-12).expect("svd solve");
            let pred = &at * coef;
            let se: f64 = (test.iter().enumerate())
                .map(|(i, &r)| (pred[i] - y[r]).powi(2))
                .sum();
            (se / test.len() as f64).sqrt()
        })
        .collect()
}
