//! The honest comparison of issue #21 on the realistic rotary campaign (`dbb-rotary-realistic`):
//! CNN-LSTM against BPNN against the lagged linear model (`mtec_nn::lagged_linear`), for every
//! scenario seed (machine, noise and air differ; the same seed initialises the networks) and
//! every held-out experiment (train on the other three). Per fit: the test RMSE of the motions
//! against the identified ones and the source's readings criterion — the max residual of the
//! predicted bar-length change against the max measured change (`compare_readings`,
//! `change_residual_ratio`). Prints a Markdown table per model and the summary quoted in
//! docs/methods.md §10.4; not run in CI (minutes of training).
//!
//!     cargo run --release -p mtec-nn --example rotary_campaign_compare [-- --seeds 1,2,3,4,5
//!         --tests 1,2,3,4 --models linear,bpnn,cnn-lstm --lags L --linear-harmonics H
//!         --validation tail|experiment --refit --ensemble K --train-count N
//!         --bpnn-lags L --bpnn-harmonics H --hidden N --bpnn-iters N
//!         --cnn-lags L --cnn-harmonics H --epochs N --window W --conv C --lstm H --lr X --rises
//!         --changes]
//!
//! - `--validation experiment`: early stopping watches one whole training experiment (the one
//!   after the held-out experiment, cyclically: 1 → 2, 2 → 3, 3 → 4, 4 → 1) instead of the last
//!   15 % of every training sequence; `--refit` then trains again on all training experiments
//!   for the best epoch count found (no early stopping).
//! - `--ensemble K`: every network is the average of K networks from seeds 100·seed + k.
//! - `--train-count N` (learning curve): train on every N-subset of the other experiments and
//!   score each fit on the held-out one.
//! - `--changes`: the networks learn each motion's change since the experiment's first
//!   (static, t = 0) measurement, which is known before the run; the predicted motion is that
//!   measurement plus the predicted change (`ThermalDataset::target_changes`).
//! - `--bpnn-lags L`: the BPNN also sees the sensors L rows (20 min each) earlier
//!   (`ThermalDataset::lagged`), the lagged linear model's inputs.

mod support;

use mtec_identify::ballbar::{identify, Measurements, Setup};
use mtec_io::Table;
use mtec_nn::lagged_linear::LaggedLinear;
use mtec_nn::metrics::channel_metrics;
use mtec_nn::rotary::{compare_readings, AngleEncoding, RotaryDataset, TemperatureLog};
use mtec_nn::{
    train_bpnn_baseline, train_cnn_lstm, BpnnTrainConfig, CnnLstmConfig, SplitComparison,
    ThermalDataset,
};
use std::path::Path;
use std::time::Instant;
use support::ExampleArgs;

/// The command line's settings for the networks.
struct Settings {
    validation_experiment: bool,
    refit: bool,
    bpnn_hidden: usize,
    bpnn_iters: usize,
    cnn: CnnLstmConfig,
}

/// One network's predictions on `test`, trained on `train` (seed `seed`; validation
/// experiment `val`).
fn fit_predict(
    model: &str,
    train: &ThermalDataset,
    test: &ThermalDataset,
    val: Option<u32>,
    seed: u64,
    s: &Settings,
) -> Vec<Vec<f64>> {
    let val = val.filter(|_| s.validation_experiment);
    match model {
        "bpnn" => {
            let mut cfg = BpnnTrainConfig {
                hidden: s.bpnn_hidden,
                max_epochs: s.bpnn_iters,
                validation_experiment: val,
                seed,
                ..BpnnTrainConfig::default()
            };
            let (mut net, report) = train_bpnn_baseline(train, &cfg).expect("bpnn");
            if s.refit && val.is_some() {
                cfg.validation_experiment = None;
                cfg.validation_fraction = 0.0;
                cfg.max_epochs = report.best_epoch.max(1);
                net = train_bpnn_baseline(train, &cfg).expect("bpnn").0;
            }
            let (xt, _) = test.rows();
            xt.iter().map(|x| net.predict(x).expect("bpnn")).collect()
        }
        "cnn-lstm" => {
            let mut cfg = CnnLstmConfig {
                validation_experiment: val,
                seed,
                ..s.cnn.clone()
            };
            let (mut net, report) = train_cnn_lstm(train, &cfg).expect("cnn-lstm");
            if s.refit && val.is_some() {
                cfg.validation_experiment = None;
                cfg.validation_fraction = 0.0;
                cfg.max_epochs = report.best_epoch.max(1);
                net = train_cnn_lstm(train, &cfg).expect("cnn-lstm").0;
            }
            net.predict(test).expect("cnn-lstm")
        }
        other => panic!("unknown model {other}"),
    }
}

fn main() {
    if let Some((var, value)) = mtec_nn::threads::single_thread_setting() {
        std::env::set_var(var, value);
    }
    let args = ExampleArgs::from_env();
    let list = |name: &str, default: &str| -> Vec<String> {
        args.value(name)
            .unwrap_or_else(|| default.into())
            .split(',')
            .map(String::from)
            .collect()
    };
    let seeds: Vec<u64> = list("--seeds", "1,2,3,4,5")
        .iter()
        .map(|s| s.parse().expect("--seeds"))
        .collect();
    let models = list("--models", "linear,bpnn,cnn-lstm");
    let lags: usize = args
        .value("--lags")
        .map_or(2, |s| s.parse().expect("--lags"));
    let lin_h: u8 = args
        .value("--linear-harmonics")
        .map_or(6, |s| s.parse().expect("--linear-harmonics"));
    let num = |name: &str, default: usize| -> usize {
        args.value(name)
            .map_or(default, |s| s.parse().unwrap_or_else(|_| panic!("{name}")))
    };
    let tests: Vec<u32> = list("--tests", "1,2,3,4")
        .iter()
        .map(|s| s.parse().expect("--tests"))
        .collect();
    let ensemble = num("--ensemble", 1);
    let train_count = num("--train-count", 3);
    let bpnn_lags = num("--bpnn-lags", 0);
    let bpnn_h = num("--bpnn-harmonics", 3) as u8;
    let cnn_lags = num("--cnn-lags", 0);
    let cnn_h = num("--cnn-harmonics", 3) as u8;
    let mut cnn = CnnLstmConfig {
        final_learning_rate_fraction: 0.05,
        ..CnnLstmConfig::default()
    };
    cnn.max_epochs = num("--epochs", cnn.max_epochs);
    cnn.architecture.window = num("--window", cnn.architecture.window);
    cnn.architecture.conv_channels = num("--conv", cnn.architecture.conv_channels);
    cnn.architecture.lstm_hidden = num("--lstm", cnn.architecture.lstm_hidden);
    if let Some(x) = args.value("--lr") {
        cnn.learning_rate = x.parse().expect("--lr");
    }
    let settings = Settings {
        validation_experiment: args.value("--validation").as_deref() == Some("experiment"),
        refit: args.flag("--refit"),
        bpnn_hidden: num("--hidden", 10),
        bpnn_iters: num("--bpnn-iters", 200),
        cnn,
    };
    let rises = args.flag("--rises");
    let changes = args.flag("--changes");
    // per model: (seed, held-out, test RMSE, change ratio, reading ratio, seconds)
    let mut results: Vec<(String, u64, u32, f64, f64, f64, f64)> = Vec::new();
    for &seed in &seeds {
        let out = mtec_sim::run_scenario("dbb-rotary-realistic", seed).expect("scenario");
        let file = |n: &str| &out.files.iter().find(|f| f.name == n).expect(n).contents;
        let setup = Setup::parse(Path::new("setup.toml"), file("setup.toml")).expect("setup");
        let dbb = Table::parse(Path::new("dbb.csv"), file("dbb.csv")).expect("dbb.csv");
        let measurements = Measurements::from_table(&dbb, &setup).expect("measurements");
        let id = identify(&setup, &measurements).expect("identification");
        let temps = Table::parse(Path::new("temps.csv"), file("temps.csv")).expect("temps");
        let temps = TemperatureLog::from_table(&temps).expect("temperatures");
        let n_sensors = temps.sensor_names.len();
        let rotary =
            RotaryDataset::build(&temps, &id.rows, AngleEncoding::Harmonics(3)).expect("dataset");
        // the linear model's angle basis: every harmonic the static motions hold (1-6), which a
        // network builds from three by its non-linearity and a linear model cannot
        let rotary6 = RotaryDataset::build(&temps, &id.rows, AngleEncoding::Harmonics(lin_h))
            .expect("dataset");
        // each network's inputs: T1..T9 (and, if asked, the same sensors 20 and 40 min
        // earlier) and the angle's harmonics; optionally the sensors as rises
        let inputs = |h: u8, lags: usize| {
            let d = RotaryDataset::build(&temps, &id.rows, AngleEncoding::Harmonics(h))
                .expect("dataset")
                .data
                .lagged(n_sensors, lags);
            if rises {
                d.rises(n_sensors * (lags + 1))
            } else {
                d
            }
        };
        let bpnn_data = inputs(bpnn_h, bpnn_lags);
        let cnn_data = inputs(cnn_h, cnn_lags);
        for &test_id in &tests {
            let others: Vec<u32> = (1..=4).filter(|&e| e != test_id).collect();
            // the training sets: the other three, or every train_count-subset of them
            let subsets: Vec<Vec<u32>> = match train_count {
                3 => vec![others.clone()],
                2 => (0..3)
                    .map(|k| {
                        others
                            .iter()
                            .enumerate()
                            .filter(|(i, _)| *i != k)
                            .map(|(_, e)| *e)
                            .collect()
                    })
                    .collect(),
                1 => others.iter().map(|&e| vec![e]).collect(),
                n => panic!("--train-count {n}: 1, 2 or 3"),
            };
            for train_ids in subsets {
                // the validation experiment: the next training one after the held-out one
                let val = (1..4)
                    .map(|k| (test_id - 1 + k) % 4 + 1)
                    .find(|e| train_ids.contains(e))
                    .filter(|_| train_ids.len() > 1);
                let (train6, test6) = rotary6.data.split(&train_ids, &[test_id]).expect("split");
                let (_, yt) = rotary
                    .data
                    .split(&train_ids, &[test_id])
                    .expect("split")
                    .1
                    .rows();
                let (_, test) = rotary.data.split(&train_ids, &[test_id]).expect("split");
                for model in &models {
                    let t0 = Instant::now();
                    let pred: Vec<Vec<f64>> = match model.as_str() {
                        "linear" => LaggedLinear::fit(&train6, n_sensors, lags)
                            .expect("linear")
                            .predict(&test6),
                        net => {
                            let data = if net == "bpnn" { &bpnn_data } else { &cnn_data };
                            let (tr, te) = data.split(&train_ids, &[test_id]).expect("split");
                            // --changes: trained on the change since the static measurement
                            // at t = 0; the motion is that measurement plus the prediction
                            let offset = if changes {
                                te.first_targets()
                            } else {
                                vec![vec![0.0; yt[0].len()]; yt.len()]
                            };
                            let (tr, te) = if changes {
                                (tr.target_changes(), te.target_changes())
                            } else {
                                (tr, te)
                            };
                            // the average of `ensemble` networks from different seeds
                            let mut sum = offset;
                            for k in 0..ensemble as u64 {
                                let s = if ensemble == 1 { seed } else { 100 * seed + k };
                                let p = fit_predict(net, &tr, &te, val, s, &settings);
                                for (a, b) in sum.iter_mut().zip(&p) {
                                    for (x, y) in a.iter_mut().zip(b) {
                                        *x += y / ensemble as f64;
                                    }
                                }
                            }
                            sum
                        }
                    };
                    let secs = t0.elapsed().as_secs_f64();
                    let rmse = SplitComparison::overall_rmse(&channel_metrics(
                        &rotary.data.target_names,
                        &pred,
                        &yt,
                    ));
                    let rows = rotary.label(&test, &pred).expect("labels");
                    let c =
                        compare_readings(&setup, &measurements, test_id, &rows).expect("readings");
                    println!(
                        "seed {seed} test {test_id} train {train_ids:?} {model:8}: RMSE {rmse:.3}, change max residual {:.2} of {:.2} um ({:.1} %), readings {:.1} %, {secs:.1} s",
                        c.change_max_abs_residual_um,
                        c.change_max_abs_measured_um,
                        100.0 * c.change_residual_ratio,
                        100.0 * c.residual_ratio
                    );
                    results.push((
                        model.clone(),
                        seed,
                        test_id,
                        rmse,
                        c.change_residual_ratio,
                        c.residual_ratio,
                        secs,
                    ));
                }
            }
        }
    }
    println!("\n| model | seed | held out 1 | 2 | 3 | 4 | worst | mean RMSE | time/fit (s) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for model in &models {
        for &seed in &seeds {
            let r: Vec<_> = results
                .iter()
                .filter(|r| &r.0 == model && r.1 == seed)
                .collect();
            let cells: Vec<String> = r.iter().map(|r| format!("{:.1} %", 100.0 * r.4)).collect();
            let worst = r.iter().map(|r| r.4).fold(0.0, f64::max);
            let rmse = r.iter().map(|r| r.3).sum::<f64>() / r.len() as f64;
            let secs = r.iter().map(|r| r.6).sum::<f64>() / r.len() as f64;
            println!(
                "| {model} | {seed} | {} | {:.1} % | {rmse:.3} | {secs:.1} |",
                cells.join(" | "),
                100.0 * worst
            );
        }
    }
    println!("\nsummary (change ratio = max |residual of predicted bar-length change| / max |measured change|):");
    for model in &models {
        let r: Vec<_> = results.iter().filter(|r| &r.0 == model).collect();
        let worst = r.iter().map(|r| r.4).fold(0.0, f64::max);
        let mean = r.iter().map(|r| r.4).sum::<f64>() / r.len() as f64;
        let rmse = r.iter().map(|r| r.3).sum::<f64>() / r.len() as f64;
        let below = r.iter().filter(|r| r.4 < 0.4).count();
        println!(
            "  {model:8}: mean ratio {:.1} %, worst {:.1} %, {below}/{} fits below 40 %, mean test RMSE {rmse:.3}",
            100.0 * mean,
            100.0 * worst,
            r.len()
        );
    }
}
