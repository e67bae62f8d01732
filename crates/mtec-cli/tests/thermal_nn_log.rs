//! `mtec thermal fit|predict --model bpnn|cnn-lstm` on a thermal log of one target, and `--model
//! auto --with-networks` (issue 18 build 2, issue 17 item 2): the networks are split by time,
//! validated forward and scored by mtec-thermal's own code, their file is the same from the CLI
//! and from Rust, and `predict` gives the library's numbers. Tiny networks, few epochs.
#![cfg(feature = "neural")]

mod support;

use mtec_io::Table;
use mtec_nn::thermal_fit::{NeuralFit, NeuralThermalModel};
use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_thermal::heat_input::with_input;
use mtec_thermal::model_file::SplitBy;
use mtec_thermal::options::BlockSpec;
use mtec_thermal::validate::{duty_cycle_blocks, forward_cv, forward_folds, split_at_time};
use mtec_thermal::{Fit, Predict, ThermalData};
use std::path::{Path, PathBuf};
use support::{mtec, text};

/// A spindle that runs a duty cycle (rpm steps) heats three bodies in a row, sensed by T1-T3;
/// an unsensed body between T2 and T3 lags behind; the drift is 2·ΔT1 + 3·Δlag µm. One
/// experiment, a row every 2 min for 600 min.
fn write_log(dir: &Path) -> PathBuf {
    let mut csv = String::from("experiment,time_min,spindle_rpm,T1_c,T2_c,T3_c,ez_um\n");
    let (mut s1, mut s2, mut lag, mut s3) = (20.0, 20.0, 20.0, 20.0);
    for k in 0..300 {
        let t = k as f64 * 2.0;
        let rpm: f64 = match t {
            t if t < 60.0 => 0.0,
            t if t < 200.0 => 6000.0,
            t if t < 260.0 => 0.0,
            t if t < 420.0 => 3000.0,
            t if t < 500.0 => 8000.0,
            _ => 0.0,
        };
        s1 += 0.2 * (20.0 + rpm / 1000.0 - s1);
        s2 += 0.05 * (s1 - s2);
        lag += 0.1 * (s2 - lag);
        s3 += 0.03 * (lag - s3);
        let ez = 2.0 * (s1 - 20.0) + 3.0 * (lag - 20.0);
        csv.push_str(&format!("1,{t},{rpm},{s1:.4},{s2:.4},{s3:.4},{ez:.4}\n"));
    }
    let p = dir.join("log.csv");
    std::fs::write(&p, csv).unwrap();
    p
}

/// The log as the workflow reads it (the spindle column attached: it cuts the blocks).
fn read(path: &Path) -> ThermalData {
    let t = Table::read(path).unwrap();
    let d = ThermalData::from_table(&t, Some("ez_um"), true).unwrap();
    with_input(&d, "spindle_rpm", &t.f64_column("spindle_rpm").unwrap()).unwrap()
}

/// `--hidden 3 --epochs 30 --rises`.
fn bpnn() -> NnFitOptions {
    let mut o = NnFitOptions::new(NnKind::Bpnn);
    (o.hidden, o.epochs, o.rises) = (Some(3), Some(30), true);
    o
}

const BPNN: [&str; 7] = [
    "--hidden",
    "3",
    "--epochs",
    "30",
    "--rises",
    "--quiet",
    "--seed=42",
];

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// serde_json reads a float back to within one unit in the last place (no `float_roundtrip`).
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(1.0)
}

/// `mtec thermal fit --model MODEL --data LOG --target ez_um --train-until 460 -o OUT EXTRA…`.
fn fit_cli(model: &str, log: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "thermal",
        "fit",
        "--model",
        model,
        "--data",
        log.to_str().unwrap(),
        "--target",
        "ez_um",
        "--train-until",
        "460",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    mtec(&args)
}

/// The same fit as [`fit_cli`] from Rust, in-process (the workflow's `neural_log::fit`).
fn fit_rust(model: &str, log: &Path, out: &Path, options: &NnFitOptions) {
    let opts = mtec_workflow::ops::thermal::FitOptions {
        data: log.to_path_buf(),
        target: "ez_um".into(),
        model: model.into(),
        fit: mtec_thermal::FitOptions::default(),
        split: SplitBy::Until(460.0),
        output: out.to_path_buf(),
    };
    let mut obs = mtec_workflow::Collect::default();
    mtec_workflow::ops::thermal::neural_log::fit(&opts, options, &mut obs).unwrap();
}

#[test]
fn bpnn_with_train_until_is_validated_forward_by_the_regression_models_code() {
    let dir = tempfile::tempdir().unwrap();
    let log = write_log(dir.path());
    let model = dir.path().join("bpnn.json");
    let (l, m) = (log.to_str().unwrap(), model.to_str().unwrap());
    let mut args = vec![
        "thermal",
        "fit",
        "--model",
        "bpnn",
        "--data",
        l,
        "--target",
        "ez_um",
        "--train-until",
        "460",
        "-o",
        m,
    ];
    args.extend(BPNN);
    let o = mtec(&args);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(
        out.contains("forward validation on the training rows"),
        "{out}"
    );
    let file = json(&model);
    assert_eq!(file["format"], "mtec.bpnn/1");
    let p = &file["provenance"];
    assert_eq!(p["thermal_data"], true);
    assert_eq!(p["split"]["train_until_min"], 460.0);
    // the library: the same rows, the same blocks, the same folds, the same fitter
    let data = read(&log);
    let (train, test) = split_at_time(&data, 460.0);
    assert_eq!(p["split"]["train_rows"], train.len());
    assert_eq!(p["split"]["test_rows"], test.len());
    let spec = BlockSpec {
        block_min: None,
        input: Some("spindle_rpm".into()),
    };
    let folds = forward_folds(&duty_cycle_blocks(&data, &train, &spec));
    assert!(folds.len() >= 2, "{} folds", folds.len());
    let fitter = NeuralFit {
        options: bpnn(),
        sensors: vec![],
        inputs: vec![],
    };
    let cv = forward_cv(&fitter, &data, &folds).unwrap();
    let v = &p["validation"];
    assert_eq!(v["folds"].as_array().unwrap().len(), cv.folds.len());
    assert!(same(
        v["pooled_rmse_um"].as_f64().unwrap(),
        cv.pooled_rmse_um
    ));
    for (f, c) in v["folds"].as_array().unwrap().iter().zip(&cv.folds) {
        assert!(same(
            f["metrics"]["rmse_um"].as_f64().unwrap(),
            c.metrics.rmse_um
        ));
    }
    // the test metrics: the model refitted on every training row, on the later rows
    let fitted = fitter.fit_rows(&data, &train).unwrap();
    let pred = fitted.predict(&data).unwrap();
    let y = data.target_um().unwrap();
    let rmse =
        (test.iter().map(|&i| (y[i] - pred[i]).powi(2)).sum::<f64>() / test.len() as f64).sqrt();
    assert!(same(p["test_metrics"]["rmse_um"].as_f64().unwrap(), rmse));
    // a BPNN of the sensors' rises learns this drift well: far below the raw drift (~40 um)
    assert!(
        cv.pooled_rmse_um < 5.0,
        "forward RMSE {}",
        cv.pooled_rmse_um
    );
    // `thermal cv` of the network: the regression models' folds over the whole log, the
    // library's numbers fold by fold
    let mut args = vec![
        "thermal", "cv", "--model", "bpnn", "--data", l, "--target", "ez_um", "--json",
    ];
    args.extend(BPNN);
    let o = mtec(&args);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let all: Vec<usize> = (0..data.len()).collect();
    let whole = forward_cv(
        &fitter,
        &data,
        &forward_folds(&duty_cycle_blocks(&data, &all, &spec)),
    );
    let whole = whole.unwrap();
    assert_eq!(v["protocol"], "forward");
    assert_eq!(v["folds"].as_array().unwrap().len(), whole.folds.len());
    assert!(whole.folds.len() >= 2, "{} folds", whole.folds.len());
    for (f, c) in v["folds"].as_array().unwrap().iter().zip(&whole.folds) {
        assert!(same(
            f["metrics"]["rmse_um"].as_f64().unwrap(),
            c.metrics.rmse_um
        ));
    }
    assert!(same(
        v["pooled_rmse_um"].as_f64().unwrap(),
        whole.pooled_rmse_um
    ));
}

/// `--weight-decay` reaches the trainer as the library's option (the CLI's file is the one Rust
/// writes with `weight_decay` set, and differs from the undecayed fit), and a negative decay or
/// learning rate is refused with exit 2 before any training.
#[test]
fn weight_decay_reaches_the_network_and_bad_training_settings_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let log = write_log(dir.path());
    let fit = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let args: Vec<&str> = BPNN.iter().chain(extra).copied().collect();
        (fit_cli("bpnn", &log, &out, &args), out)
    };
    let (o, decayed) = fit("decayed.json", &["--weight-decay", "0.05"]);
    assert!(o.status.success(), "{}", text(&o));
    let rust = dir.path().join("rust.json");
    let mut with_decay = bpnn();
    with_decay.weight_decay = 0.05;
    fit_rust("bpnn", &log, &rust, &with_decay);
    assert_eq!(
        std::fs::read(&decayed).unwrap(),
        std::fs::read(&rust).unwrap()
    );
    let (o, plain) = fit("plain.json", &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert_ne!(
        std::fs::read(&decayed).unwrap(),
        std::fs::read(&plain).unwrap()
    );
    for (bad, says) in [
        (
            "--weight-decay=-0.1",
            "weight decay -0.1: must be finite and ≥ 0",
        ),
        (
            "--weight-decay=nan",
            "weight decay NaN: must be finite and ≥ 0",
        ),
    ] {
        let (o, out) = fit("bad.json", &[bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", text(&o));
        assert!(text(&o).contains(says), "{bad}: {}", text(&o));
        assert!(!out.exists(), "{bad}");
    }
    // the CNN-LSTM's step size: before this check a negative one trained away from the data
    let out = dir.path().join("bad-lr.json");
    let o = fit_cli(
        "cnn-lstm",
        &log,
        &out,
        &[
            "--window",
            "4",
            "--epochs",
            "2",
            "--learning-rate=-0.01",
            "--quiet",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("learning rate -0.01: must be > 0 and at most 1"),
        "{}",
        text(&o)
    );
    assert!(!out.exists());
    // a network option auto's networks do not read is refused, as with a regression model
    let out = dir.path().join("auto-window.json");
    let o = fit_cli(
        "auto",
        &log,
        &out,
        &["--with-networks", "bpnn", "--window", "4"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("--window is read by cnn-lstm only; --model auto does not use it"),
        "{}",
        text(&o)
    );
    assert!(!out.exists());
    // a slip of 10⁹ epochs is refused, not trained for years (both networks)
    for (model, extra) in [
        ("bpnn", &["--hidden", "3"][..]),
        ("cnn-lstm", &["--window", "4"][..]),
    ] {
        let out = dir.path().join(format!("{model}-epochs.json"));
        let args: Vec<&str> = extra
            .iter()
            .chain(&["--epochs", "1000000000", "--quiet"])
            .copied()
            .collect();
        let o = fit_cli(model, &log, &out, &args);
        assert_eq!(o.status.code(), Some(2), "{model}: {}", text(&o));
        assert!(text(&o).contains("1000000000"), "{model}: {}", text(&o));
        assert!(text(&o).contains("1 to 1000000"), "{model}: {}", text(&o));
        assert!(!out.exists(), "{model}");
    }
}

#[test]
fn the_cli_and_rust_write_the_same_file_and_predict_gives_the_librarys_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let log = write_log(dir.path());
    let model = dir.path().join("cli.json");
    let (l, m) = (log.to_str().unwrap(), model.to_str().unwrap());
    let o = fit_cli("bpnn", &log, &model, &BPNN);
    assert!(o.status.success(), "{}", text(&o));
    // the same fit from Rust, in-process
    let rust = dir.path().join("rust.json");
    fit_rust("bpnn", &log, &rust, &bpnn());
    assert_eq!(
        std::fs::read(&model).unwrap(),
        std::fs::read(&rust).unwrap()
    );
    // predict reads the file back: the library's model, to the CSV's 4 decimals
    let pred = dir.path().join("pred.csv");
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        m,
        "--data",
        l,
        "-o",
        pred.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let data = read(&log);
    let (train, _) = split_at_time(&data, 460.0);
    let fitted: NeuralThermalModel = NeuralFit {
        options: bpnn(),
        sensors: vec![],
        inputs: vec![],
    }
    .fit_rows(&data, &train)
    .unwrap();
    let lib = fitted.predict(&data).unwrap();
    let csv = std::fs::read_to_string(&pred).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("experiment,time_min,pred_ez_um,ez_um,res_ez_um")
    );
    let got: Vec<String> = lines
        .map(|r| r.split(',').nth(2).unwrap().to_string())
        .collect();
    let want: Vec<String> = lib.iter().map(|p| format!("{p:.4}")).collect();
    assert_eq!(got, want);
}

#[test]
fn auto_with_networks_scores_them_on_the_same_forward_folds() {
    let dir = tempfile::tempdir().unwrap();
    let log = write_log(dir.path());
    let model = dir.path().join("auto.json");
    let (l, m) = (log.to_str().unwrap(), model.to_str().unwrap());
    let mut args = vec![
        "thermal",
        "fit",
        "--model",
        "auto",
        "--with-networks",
        "bpnn",
        "--data",
        l,
        "--target",
        "ez_um",
        "--train-until",
        "460",
        "-o",
        m,
    ];
    args.extend(BPNN);
    let o = mtec(&args);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(
        out.contains("auto: forward score of every candidate"),
        "{out}"
    );
    assert!(
        out.lines().any(|l| l.trim_start().starts_with("bpnn ")),
        "{out}"
    );
    // the chosen model's file: a regression model's, or the network's own
    let file = json(&model);
    let candidates = match file["format"].as_str().unwrap() {
        "mtec.thermal-model/1" => file["candidates"].clone(),
        "mtec.bpnn/1" => file["provenance"]["candidates"].clone(),
        other => panic!("format {other}"),
    };
    let of = |name: &str| {
        candidates
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["family"] == name)
            .unwrap_or_else(|| panic!("no candidate {name}: {candidates}"))
            .clone()
    };
    let (mlr, net) = (of("mlr"), of("bpnn"));
    assert_eq!(net["complexity"], 6);
    // the same folds: the same test blocks, one score each
    let blocks = |c: &serde_json::Value| -> Vec<(f64, f64)> {
        c["forward"]["folds"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                (
                    f["test_from_min"].as_f64().unwrap(),
                    f["test_to_min"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(blocks(&mlr), blocks(&net));
    assert!(net["forward"]["pooled_rmse_um"].as_f64().unwrap() > 0.0);
    // the network's score is the one forward_cv gives it on those folds
    let data = read(&log);
    let (train, _) = split_at_time(&data, 460.0);
    let spec = BlockSpec {
        block_min: None,
        input: Some("spindle_rpm".into()),
    };
    let folds = forward_folds(&duty_cycle_blocks(&data, &train, &spec));
    let cv = forward_cv(
        &NeuralFit {
            options: bpnn(),
            sensors: vec![],
            inputs: vec![],
        },
        &data,
        &folds,
    )
    .unwrap();
    assert!(same(
        net["forward"]["pooled_rmse_um"].as_f64().unwrap(),
        cv.pooled_rmse_um
    ));
    // within auto's sensor budget only: three sensors are more than --max-sensors 2
    let mut args = vec![
        "thermal",
        "fit",
        "--model",
        "auto",
        "--with-networks",
        "bpnn",
        "--max-sensors",
        "2",
        "--data",
        l,
        "--target",
        "ez_um",
        "--train-until",
        "460",
        "-o",
        m,
    ];
    args.extend(BPNN);
    let o = mtec(&args);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("bpnn          not fitted: a network takes all its 3 sensors, more than --max-sensors 2"),
        "{}",
        text(&o)
    );
    // and --with-networks goes with auto only
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "mlr",
        "--with-networks",
        "bpnn",
        "--data",
        l,
        "--target",
        "ez_um",
        "-o",
        m,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}

#[test]
fn a_cnn_lstm_fits_by_time_and_predict_reads_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let log = write_log(dir.path());
    let model = dir.path().join("cnn.json");
    let (l, m) = (log.to_str().unwrap(), model.to_str().unwrap());
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "cnn-lstm",
        "--data",
        l,
        "--target",
        "ez_um",
        "--train-until",
        "460",
        "--window",
        "4",
        "--conv-channels",
        "2",
        "--lstm-hidden",
        "4",
        "--epochs",
        "2",
        "--rises",
        "--quiet",
        "-o",
        m,
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let file = json(&model);
    assert_eq!(file["format"], "mtec.cnn-lstm/1");
    assert_eq!(file["provenance"]["sample_interval_min"], 2.0);
    assert!(
        file["provenance"]["validation"]["folds"]
            .as_array()
            .unwrap()
            .len()
            >= 2
    );
    let pred = dir.path().join("pred.csv");
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        m,
        "--data",
        l,
        "-o",
        pred.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(std::fs::read_to_string(&pred).unwrap().lines().count(), 301);
    // a log sampled every 3 min is refused at its first row off the interval
    let csv = std::fs::read_to_string(&log).unwrap().replace(",2,", ",3,");
    let other = dir.path().join("other.csv");
    std::fs::write(&other, csv).unwrap();
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        m,
        "--data",
        other.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("other.csv:3:2")
            && text(&o).contains("trained on data sampled every 2 min"),
        "{}",
        text(&o)
    );
}

/// A drift quadratic in the fast sensor's rise (0.4·ΔT1² − 2·ΔT2), no spindle column: every
/// linear candidate is worse than no compensation on some fold, the BPNN is not, so auto
/// chooses it and writes the network's own file, which predict reads.
#[test]
fn auto_that_chooses_a_network_writes_the_networks_file() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("experiment,time_min,T1_c,T2_c,T3_c,ez_um\n");
    let (mut s1, mut s2, mut s3) = (20.0, 20.0, 20.0);
    for k in 0..300 {
        let t = k as f64 * 2.0;
        let q = [0.0, 9.0, 3.0, 12.0, 6.0, 0.0, 10.0, 4.0][(t / 75.0) as usize];
        s1 += 0.2 * (20.0 + q - s1);
        s2 += 0.05 * (s1 - s2);
        s3 += 0.02 * (s1 - s3);
        let ez = 0.4 * (s1 - 20.0_f64).powi(2) - 2.0 * (s2 - 20.0);
        csv.push_str(&format!("1,{t},{s1:.4},{s2:.4},{s3:.4},{ez:.4}\n"));
    }
    let log = dir.path().join("quad.csv");
    std::fs::write(&log, csv).unwrap();
    let model = dir.path().join("auto.json");
    let (l, m) = (log.to_str().unwrap(), model.to_str().unwrap());
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "auto",
        "--with-networks",
        "bpnn",
        "--hidden",
        "4",
        "--epochs",
        "60",
        "--quiet",
        "--data",
        l,
        "--target",
        "ez_um",
        "--train-until",
        "460",
        "-o",
        m,
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let file = json(&model);
    assert_eq!(file["format"], "mtec.bpnn/1", "{}", text(&o));
    let p = &file["provenance"];
    let cands = p["candidates"].as_array().unwrap();
    let chosen: Vec<&serde_json::Value> = cands.iter().filter(|c| c["chosen"] == true).collect();
    assert_eq!(chosen.len(), 1);
    assert_eq!(chosen[0]["family"], "bpnn");
    assert_eq!(chosen[0]["forward"], p["validation"]);
    // every regression candidate was worse than no compensation on a fold
    for c in cands.iter().filter(|c| c["family"] != "bpnn") {
        assert!(
            !c["worse_than_uncompensated"].as_array().unwrap().is_empty(),
            "{c}"
        );
    }
    let o = mtec(&["thermal", "predict", "--model", m, "--data", l, "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["n"], 300);
    // every row, the test rows after 460 min too, within 1 um of a drift spanning ~50 um
    assert!(v["metrics"][0]["rmse_um"].as_f64().unwrap() < 1.0, "{v}");
}
