//! Issue 17 end to end: `thermal fit --model auto`, forward `thermal cv`, the guard rails of
//! `thermal predict` (uncertainty, training range, filter start, --history) and the output checks.

mod support;

use std::path::{Path, PathBuf};
use support::{mtec, stderr};

/// A duty-cycle log (2-min samples): `speeds[b]` rpm for 120 min each; sensor a follows the
/// spindle power through a 40-min lag, b through 200 min; the drift lags a by 120 min.
fn log(dir: &Path, name: &str, speeds: &[f64], t0: f64) -> PathBuf {
    let dt = 2.0;
    let n = (speeds.len() as f64 * 120.0 / dt) as usize;
    let step = |tau: f64| 1.0 - f64::exp(-dt / tau);
    let (mut la, mut lb, mut ly) = (0.0, 0.0, 22.0);
    let mut csv = String::from("time_min,spindle_rpm,a_c,b_c,room_c,drift_um\n");
    for i in 0..n {
        let t = i as f64 * dt;
        let rpm = speeds[(t / 120.0) as usize];
        let p = (rpm / 1000.0f64).powf(1.5);
        if i > 0 {
            la += step(40.0) * (p - la);
            lb += step(200.0) * (p - lb);
        }
        let a = 22.0 + 3.0 * la;
        if i > 0 {
            ly += step(120.0) * (a - ly);
        }
        let b = 21.0 + 2.0 * lb;
        let room = 20.0 + 0.5 * ((t0 + t) / 900.0).sin();
        let y = 4.0 * (ly - 22.0) + 2.0 * (b - 21.0) + 0.05 * (i as f64 * 0.7).sin();
        csv.push_str(&format!(
            "{},{rpm},{a:.5},{b:.5},{room:.5},{y:.5}\n",
            t0 + t
        ));
    }
    let p = dir.join(name);
    std::fs::write(&p, csv).unwrap();
    p
}

fn train(dir: &Path) -> PathBuf {
    log(
        dir,
        "train.csv",
        &[0.0, 1000.0, 0.0, 2000.0, 0.0, 3000.0, 0.0, 1500.0, 0.0],
        0.0,
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn auto_fit_keeps_candidates_validation_and_envelope_and_predict_uses_them() {
    let dir = tempfile::tempdir().unwrap();
    let data = train(dir.path());
    let model = dir.path().join("m.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        s(&data),
        "--target",
        "drift",
        "--model",
        "auto",
        "--max-sensors",
        "2",
        "-o",
        s(&model),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("<- chosen") && out.contains("heat-input") && out.contains("dynamic"),
        "{out}"
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(
        m["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["chosen"] == true)
            .count(),
        1
    );
    let u = m["validation"]["pooled_rmse_um"].as_f64().unwrap();
    assert!(u > 0.0 && u < 1.0, "{u}");
    assert!(!m["envelope"].as_array().unwrap().is_empty());

    // predict: the uncertainty column, the filter-start statement, no row outside the range
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&data),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = String::from_utf8_lossy(&o.stdout);
    let header = csv.lines().next().unwrap();
    assert_eq!(
        header,
        "experiment,time_min,predicted_um,measured_um,residual_um,uncertainty_um,outside_training_range"
    );
    assert!(
        csv.lines().nth(1).unwrap().ends_with(&format!(",{u:.4},")),
        "{csv}"
    );
    if m["model"]["kind"] != "linear"
        || m["model"]["features"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["kind"] != "temp")
    {
        assert!(
            stderr(&o).contains("filters start in equilibrium"),
            "{}",
            stderr(&o)
        );
    }
    assert!(!stderr(&o).contains("outside the training range"));

    // made-up extrapolation: a speed and temperatures never trained on are flagged
    let hot = log(dir.path(), "hot.csv", &[0.0, 6000.0, 0.0], 0.0);
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&hot),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("outside the training range"),
        "{}",
        stderr(&o)
    );
    let flagged = String::from_utf8_lossy(&o.stdout)
        .lines()
        .skip(1)
        .filter(|l| !l.ends_with(','))
        .count();
    assert!(flagged > 10, "{flagged}");
}

#[test]
fn predict_with_history_continues_the_filters_of_the_record() {
    let dir = tempfile::tempdir().unwrap();
    let data = train(dir.path());
    let model = dir.path().join("m.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        s(&data),
        "--target",
        "drift",
        "--model",
        "heat-input",
        "-o",
        s(&model),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // split the record at 600 min into history and data
    let text = std::fs::read_to_string(&data).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    let (h, d) = rows.split_at(300);
    let hist = dir.path().join("hist.csv");
    let tail = dir.path().join("tail.csv");
    std::fs::write(&hist, format!("{header}\n{}\n", h.join("\n"))).unwrap();
    std::fs::write(&tail, format!("{header}\n{}\n", d.join("\n"))).unwrap();
    let pred = |args: &[&str]| -> Vec<f64> {
        let o = mtec(args);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
            .collect()
    };
    let whole = pred(&[
        "thermal",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&data),
    ]);
    let cont = pred(&[
        "thermal",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&tail),
        "--history",
        s(&hist),
    ]);
    assert_eq!(
        &whole[300..],
        &cont[..],
        "with its history the tail predicts as in the whole record"
    );
    // without it, the tail starts mid-record, and predict says how the filters started
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&tail),
    ]);
    assert!(
        stderr(&o).contains("mid-record") && stderr(&o).contains("--history"),
        "{}",
        stderr(&o)
    );
    // a history that does not end before the data is refused
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        s(&model),
        "--data",
        s(&hist),
        "--history",
        s(&tail),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn cv_is_forward_by_default_and_leave_one_block_out_says_it_is_optimistic() {
    let dir = tempfile::tempdir().unwrap();
    let data = train(dir.path());
    let o = mtec(&[
        "thermal",
        "cv",
        "--data",
        s(&data),
        "--target",
        "drift",
        "--model",
        "mlr",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("forward validation") && out.contains("uncompensated"),
        "{out}"
    );
    // blocks at the spindle steps: 9 of 120 min; folds train on at least half of the rows (the
    // first 5 blocks, 600 of 1080 min) and score blocks 6..9
    assert_eq!(
        out.lines().filter(|l| l.starts_with("fold")).count(),
        4,
        "{out}"
    );
    let o = mtec(&[
        "thermal",
        "cv",
        "--data",
        s(&data),
        "--target",
        "drift",
        "--model",
        "mlr",
        "--loo",
        "--block-min",
        "120",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("optimistic"), "{}", stderr(&o));
}

#[test]
fn outputs_are_checked_before_work_and_select_writes_only_with_out() {
    let dir = tempfile::tempdir().unwrap();
    let data = train(dir.path());
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        s(&data),
        "--target",
        "drift",
        "--model",
        "auto",
        "-o",
        s(&data),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = mtec(&[
        "thermal",
        "select",
        "--data",
        s(&data),
        "--target",
        "drift",
        "--out",
        s(&data),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let before: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    let o = mtec(&["thermal", "select", "--data", s(&data), "--target", "drift"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        before.len(),
        "select wrote beside the data"
    );
}
