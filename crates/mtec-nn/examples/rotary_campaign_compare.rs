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
//!         --ensemble K --train-count N --bpnn-harmonics H --hidden N --bpnn-iters N
//!         --cnn-harmonics H --epochs N --window W --conv C --lstm H --lr X --rises --changes
//!         --decay L --components R --decays L1,L2,.. --hiddens H1,H2,..]
//!
//! Every model is fitted on the rows of its training experiments of the campaign as
//! mtec-thermal's `ThermalData` (`mtec_nn::rotary::rotary_data`): the networks as `NeuralFit`s
//! (`Fit::fit_rows`), the linear model by `LaggedLinear::fit_rows`; RMSE by mtec-thermal's
//! `Metrics`.
//! - `--ensemble K`: every network is the average of K networks from seeds 100·seed + k.
//! - `--train-count N` (learning curve): train on every N-subset of the other experiments and
//!   score each fit on the held-out one.
//! - `--rises`: the sensors as rises over the first row of each (experiment, angle) sequence.
//! - `--changes`: the networks learn each motion's change since the experiment's first
//!   (static, t = 0) measurement, which is known before the run; the predicted motion is that
//!   measurement plus the predicted change (`NnFitOptions::changes`).
//! - `--decay L`: the weight decay of the pointwise networks (`NnFitOptions::weight_decay`).
//! - Models with the output's structure (`mtec_nn::harmonic_net`, docs/methods.md §10.4): the
//!   lagged linear model's Fourier stage, reduced to `--components R` (default 3) principal
//!   directions, then `linear-pc` (least squares), `bpnn-harmonic` (a BPNN of `--hidden` units,
//!   or each of `--hiddens`, with weight decay) or `cnn-lstm-harmonic` (a CNN-LSTM over each
//!   training experiment, `--window`/`--conv`/`--lstm`/`--epochs`/`--lr`, AdamW weight decay)
//!   from the lagged sensors to the scores; `bpnn-residual` and `cnn-lstm-residual` are the
//!   hybrids (`Stage2::Residual`): least squares, then the network on its residual scores.
//!   The networks' decay among `--decays` (and the
//!   hidden size among `--hiddens`) is chosen nested: each training experiment left out in
//!   turn, scored by the same criterion; `--ensemble K` averages K networks there too.
//!
//! The studies of docs/methods.md §10.4 with a whole validation experiment (`--validation
//! experiment`, `--refit`) and with lagged sensors as network inputs (`--bpnn-lags`,
//! `--cnn-lags`) were run with this example before the networks were trained through
//! `NeuralFit` only (commit 0ed717e and earlier); `NeuralFit` has neither option, so those
//! flags are refused here.

mod support;

use mtec_identify::ballbar::{identify, Measurements, Setup};
use mtec_io::Table;
use mtec_nn::harmonic_net::{HarmonicNet, Stage2};
use mtec_nn::lagged_linear::LaggedLinear;
use mtec_nn::rotary::{compare_readings, motion_rows, rotary_data, AngleEncoding, TemperatureLog};
use mtec_nn::thermal_fit::target_metrics;
use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_nn::NeuralFit;
use mtec_thermal::Fit;
use std::path::Path;
use std::time::Instant;
use support::{overall_rmse, rows_of, ExampleArgs};

/// The average of several harmonic-output networks' predictions.
struct Averaged(Vec<HarmonicNet>);

impl Averaged {
    fn predict_targets(
        &self,
        d: &mtec_thermal::ThermalData,
    ) -> mtec_nn::error::Result<Vec<Vec<f64>>> {
        let p: mtec_nn::error::Result<Vec<_>> =
            self.0.iter().map(|m| m.predict_targets(d)).collect();
        Ok(average(p?))
    }
}

/// The mean of several models' predictions (rows × targets), all of one shape.
fn average(predictions: Vec<Vec<Vec<f64>>>) -> Vec<Vec<f64>> {
    let n = predictions.len() as f64;
    let mut it = predictions.into_iter();
    let mut sum = it.next().expect("at least one model");
    sum.iter_mut().flatten().for_each(|x| *x /= n);
    for p in it {
        assert_eq!(p.len(), sum.len(), "predictions of one shape");
        for (a, b) in sum.iter_mut().zip(&p) {
            assert_eq!(a.len(), b.len(), "predictions of one shape");
            for (x, y) in a.iter_mut().zip(b) {
                *x += y / n;
            }
        }
    }
    sum
}

/// The command line's settings for the networks.
struct Settings {
    bpnn_hidden: usize,
    bpnn_iters: usize,
    cnn: NnFitOptions,
    rises: bool,
    changes: bool,
    /// `--decay`: the pointwise networks' weight decay (fixed, not chosen nested).
    weight_decay: f64,
}

/// The options of network `model` (seed `seed`).
fn options(model: &str, seed: u64, s: &Settings) -> NnFitOptions {
    let mut o = match model {
        "bpnn" => {
            let mut o = NnFitOptions::new(NnKind::Bpnn);
            (o.hidden, o.epochs) = (Some(s.bpnn_hidden), Some(s.bpnn_iters));
            o
        }
        "cnn-lstm" => s.cnn.clone(),
        other => panic!("unknown model {other}"),
    };
    (o.seed, o.rises, o.changes, o.weight_decay) = (seed, s.rises, s.changes, s.weight_decay);
    o
}

fn main() {
    for (var, value) in mtec_nn::threads::single_thread_settings() {
        std::env::set_var(var, value);
    }
    let args = ExampleArgs::from_env();
    for gone in ["--validation", "--refit", "--bpnn-lags", "--cnn-lags"] {
        if args.flag(gone) {
            eprintln!("{gone}: not an option of NeuralFit (see the example's docs)");
            std::process::exit(2);
        }
    }
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
    let bpnn_h = num("--bpnn-harmonics", 3) as u8;
    let cnn_h = num("--cnn-harmonics", 3) as u8;
    let mut cnn = NnFitOptions::new(NnKind::CnnLstm);
    cnn.final_lr_fraction = Some(0.05);
    cnn.epochs = args.value("--epochs").map(|_| num("--epochs", 0));
    cnn.window = args.value("--window").map(|_| num("--window", 0));
    cnn.conv_channels = args.value("--conv").map(|_| num("--conv", 0));
    cnn.lstm_hidden = args.value("--lstm").map(|_| num("--lstm", 0));
    cnn.learning_rate = args.value("--lr").map(|x| x.parse().expect("--lr"));
    let settings = Settings {
        bpnn_hidden: num("--hidden", 10),
        bpnn_iters: num("--bpnn-iters", 200),
        cnn,
        rises: args.flag("--rises"),
        changes: args.flag("--changes"),
        weight_decay: args
            .value("--decay")
            .map_or(0.0, |d| d.parse().expect("--decay")),
    };
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
        // every harmonic any model uses as columns; each model takes its own
        let h = lin_h.max(bpnn_h).max(cnn_h);
        let data = rotary_data(&temps, &id.rows, AngleEncoding::Harmonics(h)).expect("dataset");
        let sensors = temps.sensor_names.clone();
        // the linear model's angle basis: every harmonic the static motions hold (1-6), which a
        // network builds from three by its non-linearity and a linear model cannot
        let harmonics = |h: u8| AngleEncoding::Harmonics(h).feature_names();
        // each network's inputs: T1..T9 and the angle's harmonics
        let network = |model: &str, seed: u64| NeuralFit {
            options: options(model, seed, &settings),
            sensors: sensors.clone(),
            inputs: harmonics(if model == "bpnn" { bpnn_h } else { cnn_h }),
        };
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
                let train = rows_of(&data, &train_ids);
                let test = data.rows(&rows_of(&data, &[test_id]));
                for model in &models {
                    let t0 = Instant::now();
                    let pred: Vec<Vec<f64>> = match model.as_str() {
                        "linear" => {
                            LaggedLinear::fit_rows(&data, &train, &sensors, &harmonics(lin_h), lags)
                                .and_then(|m| m.predict_targets(&test))
                                .expect("linear")
                        }
                        "linear-pc" => HarmonicNet::fit_rows(
                            &data,
                            &train,
                            (&sensors, &harmonics(lin_h)),
                            lags,
                            num("--components", 3),
                            &Stage2::Linear,
                        )
                        .and_then(|m| m.predict_targets(&test))
                        .expect("linear-pc"),
                        kind @ ("bpnn-harmonic" | "cnn-lstm-harmonic" | "bpnn-residual"
                        | "cnn-lstm-residual") => {
                            // the average of `ensemble` networks (seeds as for the others)
                            let fit = |rows: &[usize], (hidden, decay): (usize, f64)| {
                                let nets: Vec<HarmonicNet> = (0..ensemble as u64)
                                    .map(|k| {
                                        let s = if ensemble == 1 { seed } else { 100 * seed + k };
                                        let stage = if kind.starts_with("bpnn") {
                                            Stage2::Bpnn(mtec_nn::BpnnTrainConfig {
                                                hidden,
                                                max_epochs: settings.bpnn_iters,
                                                seed: s,
                                                weight_decay: decay,
                                                // no early stopping: the decay regularises
                                                validation_fraction: 0.0,
                                                ..Default::default()
                                            })
                                        } else {
                                            let mut c = mtec_nn::CnnLstmConfig::default();
                                            let o = &settings.cnn;
                                            let a = &mut c.architecture;
                                            a.window = o.window.unwrap_or(a.window);
                                            a.conv_channels =
                                                o.conv_channels.unwrap_or(a.conv_channels);
                                            a.lstm_hidden = o.lstm_hidden.unwrap_or(a.lstm_hidden);
                                            c.max_epochs = o.epochs.unwrap_or(c.max_epochs);
                                            c.learning_rate =
                                                o.learning_rate.unwrap_or(c.learning_rate);
                                            c.final_learning_rate_fraction = 0.05;
                                            (c.weight_decay, c.seed) = (decay, s);
                                            c.validation_fraction = 0.0;
                                            Stage2::CnnLstm(c)
                                        };
                                        // the hybrids: least squares, the network on its
                                        // residual scores
                                        let stage = if kind.ends_with("-residual") {
                                            Stage2::Residual(Box::new(stage))
                                        } else {
                                            stage
                                        };
                                        HarmonicNet::fit_rows(
                                            &data,
                                            rows,
                                            (&sensors, &harmonics(lin_h)),
                                            lags,
                                            num("--components", 3),
                                            &stage,
                                        )
                                        .expect(kind)
                                    })
                                    .collect();
                                Averaged(nets)
                            };
                            // λ by leaving out each training experiment in turn (nested: the
                            // held-out experiment is never seen), scored by the same criterion
                            let decays: Vec<f64> = list("--decays", "0.003,0.01,0.03,0.1,0.3")
                                .iter()
                                .map(|d| d.parse().expect("--decays"))
                                .collect();
                            // and the hidden size among --hiddens (default: --hidden alone)
                            let hiddens: Vec<usize> = args
                                .value("--hiddens")
                                .unwrap_or_else(|| settings.bpnn_hidden.to_string())
                                .split(',')
                                .map(|h| h.parse().expect("--hiddens"))
                                .collect();
                            let inner = |choice: (usize, f64)| -> f64 {
                                let mut worst = 0.0f64;
                                for &v in &train_ids {
                                    let fit_ids: Vec<u32> =
                                        train_ids.iter().copied().filter(|&e| e != v).collect();
                                    let m = fit(&rows_of(&data, &fit_ids), choice);
                                    let vd = data.rows(&rows_of(&data, &[v]));
                                    let p = m.predict_targets(&vd).expect("inner");
                                    let r = motion_rows(&vd, &p).expect("labels");
                                    let c = compare_readings(&setup, &measurements, v, &r)
                                        .expect("readings");
                                    worst = worst.max(c.change_residual_ratio);
                                }
                                worst
                            };
                            let scores: Vec<((usize, f64), f64)> = (hiddens.iter())
                                .flat_map(|&h| decays.iter().map(move |&d| (h, d)))
                                .map(|c| (c, inner(c)))
                                .collect();
                            let best = scores
                                .iter()
                                .min_by(|a, b| a.1.total_cmp(&b.1))
                                .expect("a choice")
                                .0;
                            println!(
                                "  inner (worst ratio by hidden, decay): {scores:.3?} -> {best:?}"
                            );
                            fit(&train, best).predict_targets(&test).expect(kind)
                        }
                        net => {
                            // the average of `ensemble` networks from different seeds
                            let p = (0..ensemble as u64).map(|k| {
                                let s = if ensemble == 1 { seed } else { 100 * seed + k };
                                let m = network(net, s).fit_rows(&data, &train).expect(net);
                                m.predict_targets(&test).expect(net)
                            });
                            average(p.collect())
                        }
                    };
                    let secs = t0.elapsed().as_secs_f64();
                    let rmse = overall_rmse(&target_metrics(&test, &pred, 0).expect("metrics"));
                    let rows = motion_rows(&test, &pred).expect("labels");
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
