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
//!         --models linear,bpnn,cnn-lstm --epochs N --lags L
//!         --linear-harmonics H --window W --conv C --lstm H --rises]

mod support;

use mtec_identify::ballbar::{identify, Measurements, Setup};
use mtec_io::Table;
use mtec_nn::lagged_linear::LaggedLinear;
use mtec_nn::metrics::channel_metrics;
use mtec_nn::rotary::{compare_readings, AngleEncoding, RotaryDataset, TemperatureLog};
use mtec_nn::{
    train_bpnn_baseline, train_cnn_lstm, BpnnTrainConfig, CnnLstmConfig, SplitComparison,
};
use std::path::Path;
use std::time::Instant;
use support::ExampleArgs;

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
        for test_id in 1..=4u32 {
            let train_ids: Vec<u32> = (1..=4).filter(|&e| e != test_id).collect();
            let (train, test) = rotary.data.split(&train_ids, &[test_id]).expect("split");
            let (train6, test6) = rotary6.data.split(&train_ids, &[test_id]).expect("split");
            let (_, yt) = test.rows();
            for model in &models {
                let t0 = Instant::now();
                let pred: Vec<Vec<f64>> = match model.as_str() {
                    "linear" => LaggedLinear::fit(&train6, n_sensors, lags)
                        .expect("linear")
                        .predict(&test6),
                    "bpnn" => {
                        let cfg = BpnnTrainConfig {
                            hidden: 10,
                            max_epochs: 200,
                            seed,
                            ..BpnnTrainConfig::default()
                        };
                        let (net, _) = train_bpnn_baseline(&train, &cfg).expect("bpnn");
                        let (xt, _) = test.rows();
                        xt.iter().map(|x| net.predict(x).expect("bpnn")).collect()
                    }
                    "cnn-lstm" => {
                        let mut cfg = CnnLstmConfig {
                            final_learning_rate_fraction: 0.05,
                            seed,
                            ..CnnLstmConfig::default()
                        };
                        if let Some(n) = args.value("--epochs") {
                            cfg.max_epochs = n.parse().expect("--epochs");
                        }
                        if let Some(n) = args.value("--window") {
                            cfg.architecture.window = n.parse().expect("--window");
                        }
                        if let Some(n) = args.value("--conv") {
                            cfg.architecture.conv_channels = n.parse().expect("--conv");
                        }
                        if let Some(n) = args.value("--lstm") {
                            cfg.architecture.lstm_hidden = n.parse().expect("--lstm");
                        }
                        if args.flag("--rises") {
                            // the sensors as rises over each sequence's first row
                            let (tr, te) = (train.rises(n_sensors), test.rises(n_sensors));
                            let (net, _) = train_cnn_lstm(&tr, &cfg).expect("cnn-lstm");
                            net.predict(&te).expect("cnn-lstm")
                        } else {
                            let (net, _) = train_cnn_lstm(&train, &cfg).expect("cnn-lstm");
                            net.predict(&test).expect("cnn-lstm")
                        }
                    }
                    other => panic!("unknown model {other}"),
                };
                let secs = t0.elapsed().as_secs_f64();
                let rmse = SplitComparison::overall_rmse(&channel_metrics(
                    &rotary.data.target_names,
                    &pred,
                    &yt,
                ));
                let rows = rotary.label(&test, &pred).expect("labels");
                let c = compare_readings(&setup, &measurements, test_id, &rows).expect("readings");
                println!(
                    "seed {seed} test {test_id} {model:8}: RMSE {rmse:.3}, change max residual {:.2} of {:.2} um ({:.1} %), readings {:.1} %, {secs:.1} s",
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
