//! `mtec thermal fit|predict --model cnn-lstm|bpnn` end to end on the `dbb-rotary` campaign:
//! simulate, identify the error motions with `mtec identify ballbar --temps`, train on
//! experiments 1, 2, 4 (few epochs), predict, and bad input (exit 2).
//!
//! They need the cargo feature `neural` (`cargo test --workspace --all-features`); without it
//! `tests/outputs.rs` checks that the neural commands are refused with exit 2.
#![cfg(feature = "neural")]

mod support;

use std::path::{Path, PathBuf};
use support::{identify_ballbar, mtec, text, write_scenario};

/// `motions.csv` (identified motions + T1..T9) of `dbb-rotary` seed 1.
fn motions(dir: &Path) -> PathBuf {
    write_scenario("dbb-rotary", 1, dir);
    let o = identify_ballbar(dir);
    assert!(o.status.success(), "{}", text(&o));
    dir.join("id").join("motions.csv")
}

const TARGETS: &str = "EXC_um,EYC_um,EZC_um,EAC_urad,EBC_urad";

#[test]
fn cnn_lstm_and_bpnn_fit_and_predict_rotary_motions() {
    let dir = tempfile::tempdir().unwrap();
    let data = motions(dir.path());
    let d = data.to_str().unwrap();
    let model = dir.path().join("cnn.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "cnn-lstm",
        "--data",
        d,
        "--target",
        TARGETS,
        "--sequence-by",
        "angle_deg",
        "--features",
        "angle_deg",
        "--window",
        "4",
        "--conv-channels",
        "4",
        "--lstm-hidden",
        "8",
        "--epochs",
        "3",
        "--train",
        "1,2,4",
        "--test",
        "3",
        "--quiet",
        "-o",
        model.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(
        out.contains("CNN-LSTM") && out.contains("test") && out.contains("EBC_urad"),
        "{out}"
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(m["format"], "mtec.cnn-lstm/1");
    assert_eq!(m["architecture"]["window"], 4);
    assert_eq!(m["provenance"]["sequence_by"], "angle_deg");
    assert_eq!(
        m["provenance"]["train_experiments"],
        serde_json::json!([1, 2, 4])
    );
    assert_eq!(m["provenance"]["test_metrics"].as_array().unwrap().len(), 5);
    assert_eq!(m["provenance"]["training"]["report"]["epochs"], 3);
    // T1..T9 then the angle
    let f = m["feature_names"].as_array().unwrap();
    assert_eq!(f.len(), 10);
    assert_eq!(f[9], "angle_deg");

    // predict: one row per experiment, time and angle, metrics against the motions in the file
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        model.to_str().unwrap(),
        "--data",
        d,
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let p: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(p["n"], 4 * 13 * 72);
    assert_eq!(p["predictions"][0].as_array().unwrap().len(), 5);
    let rmse = p["metrics"][0]["rmse_um"].as_f64().unwrap();
    assert!(rmse.is_finite() && rmse > 0.0);

    // the window is rows of the interval the model was trained on (every 20 min here): a log
    // sampled every 40 min is refused at its first 40-min step, not predicted with a window
    // that spans twice the minutes
    assert_eq!(m["provenance"]["sample_interval_min"], 20.0);
    let csv = std::fs::read_to_string(&data).unwrap();
    let mut header_seen = false;
    let thinned: String = csv
        .lines()
        .filter(|l| {
            if l.starts_with('#') || !header_seen {
                header_seen |= !l.starts_with('#');
                return true;
            }
            let t: f64 = l.split(',').nth(1).unwrap().parse().unwrap();
            (t / 20.0).round() as i64 % 2 == 0
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let slow = dir.path().join("every40.csv");
    std::fs::write(&slow, thinned).unwrap();
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        model.to_str().unwrap(),
        "--data",
        slow.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = text(&o);
    assert!(
        err.contains("every40.csv:")
            && err.contains("a time step of 40 min")
            && err.contains("trained on data sampled every 20 min"),
        "{err}"
    );

    // BPNN on the same split, predictions as CSV
    let bp = dir.path().join("bpnn.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "bpnn",
        "--data",
        d,
        "--target",
        TARGETS,
        "--features",
        "angle_deg",
        "--angle-harmonics",
        "2",
        "--rises",
        "--hidden",
        "4",
        "--epochs",
        "3",
        "--train",
        "1,2,4",
        "--test",
        "3",
        "--quiet",
        "-o",
        bp.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&bp).unwrap()).unwrap();
    assert_eq!(b["format"], "mtec.bpnn/1");
    assert_eq!(b["w1"].as_array().unwrap().len(), 4);
    // T1..T9 then the angle's first two harmonics, which predict computes from angle_deg
    let names: Vec<&str> = b["input_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(
        names[9..],
        [
            "cos_1(angle_deg)",
            "sin_1(angle_deg)",
            "cos_2(angle_deg)",
            "sin_2(angle_deg)"
        ]
    );
    let csv_path = dir.path().join("pred.csv");
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        bp.to_str().unwrap(),
        "--data",
        d,
        "-o",
        csv_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = std::fs::read_to_string(&csv_path).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(
        header.starts_with("experiment,time_min,pred_EXC_um") && header.contains("res_EBC_urad"),
        "{header}"
    );
    assert_eq!(csv.lines().count(), 1 + 4 * 13 * 72);
    // fitted on rises of the nine sensors: predict applies them again, so its residuals on
    // the test experiment give the RMSE the fit reported
    assert_eq!(b["provenance"]["rises"], 9);
    let cols: Vec<&str> = header.split(',').collect();
    let res = cols.iter().position(|c| *c == "res_EXC_um").unwrap();
    let r: Vec<f64> = csv
        .lines()
        .skip(1)
        .filter(|l| l.starts_with("3,"))
        .map(|l| l.split(',').nth(res).unwrap().parse().unwrap())
        .collect();
    let rmse = (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt();
    let fit_rmse = b["provenance"]["test_metrics"][0]["rmse_um"]
        .as_f64()
        .unwrap();
    assert!(
        (rmse - fit_rmse).abs() < 1e-3 * fit_rmse.max(1e-3),
        "{rmse} vs {fit_rmse}"
    );
}

/// `--changes`: the BPNN learns each motion's change since the angle's first measurement;
/// predict adds that measurement back, so its residuals on the test experiment (motion minus
/// first measurement minus predicted change) have the RMSE the fit reported on the changes.
#[test]
fn bpnn_on_changes_predicts_motions_from_the_first_measurement() {
    let dir = tempfile::tempdir().unwrap();
    let data = motions(dir.path());
    let d = data.to_str().unwrap();
    let bp = dir.path().join("bpnn.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "bpnn",
        "--data",
        d,
        "--target",
        TARGETS,
        "--sequence-by",
        "angle_deg",
        "--features",
        "angle_deg",
        "--angle-harmonics",
        "2",
        "--rises",
        "--changes",
        "--hidden",
        "4",
        "--epochs",
        "3",
        "--train",
        "1,2,4",
        "--test",
        "3",
        "--quiet",
        "-o",
        bp.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&bp).unwrap()).unwrap();
    assert_eq!(b["provenance"]["changes"], true);
    let csv_path = dir.path().join("pred.csv");
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        bp.to_str().unwrap(),
        "--data",
        d,
        "-o",
        csv_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = std::fs::read_to_string(&csv_path).unwrap();
    let cols: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let (pred, meas) = (
        cols.iter().position(|c| *c == "pred_EXC_um").unwrap(),
        cols.iter().position(|c| *c == "EXC_um").unwrap(),
    );
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .filter(|l| l.starts_with("3,"))
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let rmse = (rows
        .iter()
        .map(|r| (r[meas] - r[pred]).powi(2))
        .sum::<f64>()
        / rows.len() as f64)
        .sqrt();
    let fit_rmse = b["provenance"]["test_metrics"][0]["rmse_um"]
        .as_f64()
        .unwrap();
    assert!(
        (rmse - fit_rmse).abs() < 1e-3 * fit_rmse,
        "{rmse} vs {fit_rmse}"
    );
    // the motions themselves: predictions near the measured static pattern (tens of µm),
    // which the change model alone (without the first measurement) could not give
    let spread = rows.iter().map(|r| r[meas].abs()).fold(0.0, f64::max);
    assert!(rmse < 0.2 * spread, "{rmse} of {spread}");
    // data without the targets lack the first measurement: refused, naming the data file
    let bare = dir.path().join("temps_only.csv");
    let text_in = std::fs::read_to_string(&data).unwrap();
    let keep = |l: &str| -> String {
        let f: Vec<&str> = l.split(',').collect();
        [&f[..3], &f[8..]].concat().join(",")
    };
    let lines: Vec<String> = text_in.lines().map(keep).collect();
    assert!(lines[0].starts_with("experiment,time_min,angle_deg,T1_c"));
    std::fs::write(&bare, lines.join("\n") + "\n").unwrap();
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        bp.to_str().unwrap(),
        "--data",
        bare.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("temps_only.csv") && text(&o).contains("first row"),
        "{}",
        text(&o)
    );
}

#[test]
fn bad_neural_fits_exit_2_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let data = motions(dir.path());
    let d = data.to_str().unwrap();
    let out = dir.path().join("m.json");
    let o_ = out.to_str().unwrap();
    let fit = |extra: &[&str]| {
        let mut a = vec![
            "thermal", "fit", "--data", d, "--quiet", "--epochs", "1", "-o", o_,
        ];
        a.extend_from_slice(extra);
        mtec(&a)
    };
    // a refused fit: exit 2, and the message holds every needle
    let refused = |extra: &[&str], needles: &[&str]| {
        let o = fit(extra);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", text(&o));
        for n in needles {
            assert!(text(&o).contains(n), "{extra:?}: no `{n}` in {}", text(&o));
        }
    };
    // unknown target: named, at the header line
    refused(
        &["--model", "cnn-lstm", "--target", "EXC_um,EQC_um"],
        &["EQC_um", "motions.csv:1:"],
    );
    // an experiment the file does not hold
    refused(
        &[
            "--model", "bpnn", "--target", TARGETS, "--train", "1,9", "--test", "3",
        ],
        &["no experiment 9"],
    );
    // options of the regression models
    refused(&["--model", "cnn-lstm", "--target", TARGETS, "--lag"], &[]);
    // a sequence model needs one row per time in a sequence: without --sequence-by the 72
    // angles of one measurement share their time, located at the first repeat
    refused(
        &["--model", "cnn-lstm", "--target", TARGETS],
        &["motions.csv:3:2", "appears twice"],
    );
    // a window of 0
    refused(
        &[
            "--model",
            "cnn-lstm",
            "--target",
            TARGETS,
            "--sequence-by",
            "angle_deg",
            "--window",
            "0",
        ],
        &["window"],
    );
    // a harmonic of a column the file does not have; no harmonic at all; harmonics asked for
    // but no angle column among the features
    refused(
        &[
            "--model",
            "bpnn",
            "--target",
            TARGETS,
            "--features",
            "cos_2(table_deg)",
        ],
        &["table_deg", "motions.csv:1:"],
    );
    refused(
        &[
            "--model",
            "bpnn",
            "--target",
            TARGETS,
            "--features",
            "angle_deg",
            "--angle-harmonics",
            "0",
        ],
        &["--angle-harmonics"],
    );
    refused(
        &[
            "--model",
            "bpnn",
            "--target",
            TARGETS,
            "--angle-harmonics",
            "3",
        ],
        &["_deg"],
    );
    // thermal cv validates a network of one target and its sensors (the rotary options split
    // by experiments in thermal fit)
    let o = mtec(&[
        "thermal",
        "cv",
        "--data",
        d,
        "--target",
        "EXC_um",
        "--model",
        "bpnn",
        "--sequence-by",
        "angle_deg",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("one target and its sensors"),
        "{}",
        text(&o)
    );
    assert!(!out.exists());

    // a damaged model file: right format, a weight missing
    let o = fit(&[
        "--model",
        "cnn-lstm",
        "--target",
        TARGETS,
        "--sequence-by",
        "angle_deg",
        "--window",
        "2",
        "--conv-channels",
        "2",
        "--lstm-hidden",
        "2",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    m["weights"].as_object_mut().unwrap().remove("fc.bias");
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, m.to_string()).unwrap();
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        broken.to_str().unwrap(),
        "--data",
        d,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("broken.json") && text(&o).contains("fc.bias"),
        "{}",
        text(&o)
    );
}

/// `thermal predict --setup --dbb --readings` on the realistic campaign (issue #21): a small
/// BPNN's error motions become predicted readings of every mode, scored like the source (RMSE,
/// MAE, max |residual| against max |measured|); the CSV agrees with the printed metrics; bad
/// input exits 2 naming the file (and line and column where there is one).
#[test]
fn rotary_model_predicts_ballbar_readings() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    write_scenario("dbb-rotary-realistic", 1, dir.path());
    let o = identify_ballbar(dir.path());
    assert!(o.status.success(), "{}", text(&o));
    let d = p("id/motions.csv");
    let model = p("bpnn.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "bpnn",
        "--data",
        &d,
        "--target",
        TARGETS,
        "--sequence-by",
        "angle_deg",
        "--features",
        "angle_deg",
        "--angle-harmonics",
        "3",
        "--hidden",
        "4",
        "--epochs",
        "4",
        "--train",
        "1,2,4",
        "--test",
        "3",
        "--quiet",
        "-o",
        &model,
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let (setup, dbb, readings) = (p("setup.toml"), p("dbb.csv"), p("readings.csv"));
    let predict = |model: &str, dbb: &str, extra: &[&str]| {
        let mut a = vec![
            "thermal", "predict", "--model", model, "--data", &d, "--setup", &setup, "--dbb", dbb,
        ];
        a.extend_from_slice(extra);
        mtec(&a)
    };
    let o = predict(
        &model,
        &dbb,
        &["--readings", &readings, "--json", "-o", &p("pred.csv")],
    );
    assert!(o.status.success(), "{}", text(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let m = j["readings"]["metrics"].as_array().unwrap();
    assert_eq!(m.len(), 4);
    let csv = std::fs::read_to_string(&readings).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "experiment,time_min,mode,angle_deg,predicted_um,measured_um,residual_um,\
         predicted_change_um,measured_change_um,change_residual_um"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 4 * 19 * 5 * 72);
    // experiment 3 (held out): the metrics recomputed from the CSV (4 decimals)
    let e3: Vec<&Vec<f64>> = rows.iter().filter(|r| r[0] == 3.0).collect();
    let n = e3.len() as f64;
    let rmse = (e3.iter().map(|r| r[9] * r[9]).sum::<f64>() / n).sqrt();
    let mae = e3.iter().map(|r| r[9].abs()).sum::<f64>() / n;
    let max_r = e3.iter().map(|r| r[9].abs()).fold(0.0, f64::max);
    let max_y = e3.iter().map(|r| r[8].abs()).fold(0.0, f64::max);
    let m3 = &m[2];
    assert_eq!(m3["experiment"], 3);
    for (k, v) in [
        ("change_rmse_um", rmse),
        ("change_mae_um", mae),
        ("change_max_abs_residual_um", max_r),
        ("change_max_abs_measured_um", max_y),
    ] {
        assert!(
            (m3[k].as_f64().unwrap() - v).abs() < 2e-4,
            "{k}: {} vs {v}",
            m3[k]
        );
    }
    // the campaign changes the cleaned readings by a few µm (docs/methods.md §10.2)
    assert!(max_y > 2.0, "{max_y}");
    // the table beside the CSV
    let o = predict(&model, &dbb, &["-o", &p("pred.csv")]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("ballbar readings") && text(&o).contains("3 change"),
        "{}",
        text(&o)
    );

    // the project report's section: metrics table, one figure per experiment, method and source
    std::fs::write(
        p("project.toml"),
        "name = \"rotary\"\n[ballbar]\nsetup = \"setup.toml\"\ndata = \"dbb.csv\"\n\
         temps = \"temps.csv\"\nmodel = \"bpnn.json\"\n",
    )
    .unwrap();
    let o = mtec(&["run", &p("project.toml"), "--out", &p("res"), "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let html = std::fs::read_to_string(p("res/report.html")).unwrap();
    let sec = &html[html.find("predicted ballbar readings").expect("section")..];
    assert!(sec.contains("Experiment 3: the bar-length change") && sec.contains("<svg"));
    assert!(sec.contains("7.4 µm against 19.3 µm") && sec.contains("max |residual|"));
    assert_eq!(
        std::fs::read_to_string(p("res/ballbar/readings.csv")).unwrap(),
        csv,
        "the project writes what thermal predict --readings does"
    );

    // bad input: a damaged reading (file, line, column), a model without angle sequences,
    // --setup without --dbb, the readings onto an input
    let bad = p("bad.csv");
    let mut t: Vec<String> = std::fs::read_to_string(&dbb)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    t[5] = t[5]
        .rsplit_once(',')
        .map(|(a, _)| format!("{a},1.2.3"))
        .unwrap();
    std::fs::write(&bad, t.join("\n")).unwrap();
    let o = predict(&model, &bad, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("bad.csv:6:5"), "{}", text(&o));
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    j["provenance"]["sequence_by"] = serde_json::Value::Null;
    let flat = p("flat.json");
    std::fs::write(&flat, j.to_string()).unwrap();
    let o = predict(&flat, &dbb, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("flat.json") && text(&o).contains("--sequence-by angle_deg"),
        "{}",
        text(&o)
    );
    let o = mtec(&[
        "thermal", "predict", "--model", &model, "--data", &d, "--setup", &setup,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = predict(&model, &dbb, &["--readings", &dbb]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(std::fs::read_to_string(&dbb).unwrap().len() > 1000);
}
