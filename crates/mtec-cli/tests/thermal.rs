//! `mtec thermal` end to end: select, fit, predict on simulated logs, and bad input (exit 2).

mod support;

use std::path::{Path, PathBuf};
use support::{mtec, stderr};

fn scenario(dir: &Path, name: &str) -> PathBuf {
    let out = mtec_sim::run_scenario(name, 1).unwrap();
    let p = dir.join(format!("{name}.csv"));
    std::fs::write(&p, &out.files[0].contents).unwrap();
    p
}

#[test]
fn select_fit_predict_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let data = scenario(dir.path(), "spindle-sensors");
    let d = data.to_str().unwrap();
    let o = mtec(&[
        "thermal",
        "select",
        "--data",
        d,
        "--target",
        "radial_um",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let sel: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(sel["format"], "mtec.thermal-selection/1");
    assert!(sel["selected"].as_array().unwrap().len() <= 4);
    assert_eq!(sel["trace"]["k"].as_array().unwrap().len(), 100);
    assert_eq!(sel["comparison"].as_array().unwrap().len(), 3);

    let out = dir.path().join("sel");
    let o = mtec(&[
        "thermal",
        "select",
        "--data",
        d,
        "--target",
        "radial",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("Comparison") && text.contains("De-standardised equation"),
        "{text}"
    );
    assert!(std::fs::read_to_string(out.join("ridge_trace.svg"))
        .unwrap()
        .contains("<svg"));
    assert_eq!(
        std::fs::read_to_string(out.join("ridge_trace.csv"))
            .unwrap()
            .lines()
            .count(),
        101
    );

    let model = dir.path().join("m.json");
    let m = model.to_str().unwrap();
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        d,
        "--target",
        "radial_um",
        "--model",
        "ridge-select",
        "--train",
        "1",
        "--test",
        "2",
        "-o",
        m,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(file["format"], "mtec.thermal-model/1");
    let test_rmse = file["test_metrics"]["rmse_um"].as_f64().unwrap();

    let o = mtec(&["thermal", "predict", "--model", m, "--data", d, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let p: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "rmse_um",
        "mae_um",
        "max_abs_residual_um",
        "n",
        "predictions",
    ] {
        assert!(p.get(key).is_some(), "missing {key}");
    }
    assert_eq!(
        p["n"].as_u64().unwrap() as usize,
        p["predictions"].as_array().unwrap().len()
    );
    assert!(p["rmse_um"].as_f64().unwrap() > 0.0 && test_rmse > 0.0);

    // without the target column: predictions only
    let text = std::fs::read_to_string(&data).unwrap();
    let no_target: String = text
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                l.to_string()
            } else {
                l.rsplit_once(',').unwrap().0.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let nt = dir.path().join("nt.csv");
    std::fs::write(&nt, no_target).unwrap();
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        m,
        "--data",
        nt.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let p: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(p.get("rmse_um").is_none() && p["predictions"].as_array().unwrap().len() == 242);
}

#[test]
fn exp_ambient_fit_and_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let data = scenario(dir.path(), "feed-axis-ambient");
    let d = data.to_str().unwrap();
    let m = dir.path().join("z.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        d,
        "--target",
        "ez_um",
        "--model",
        "exp-ambient",
        "--sensors",
        "up,nut",
        "--train",
        "1,2,4",
        "--test",
        "3",
        "-o",
        m.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&m).unwrap()).unwrap();
    assert!(file["test_metrics"]["rmse_um"].as_f64().unwrap() < 2.0);
    assert_eq!(file["model"]["kind"], "exp-ambient");

    // b_b, k_b positive; the linear-limit warning goes to stderr
    for l in file["model"]["identifiability"].as_array().unwrap() {
        assert!(l["b_b_c"].as_f64().unwrap() > 0.0 && l["k_b_c"].as_f64().unwrap() > 0.0);
    }
    assert!(
        stderr(&o).contains("b_a and b_b are not separately determined"),
        "{}",
        stderr(&o)
    );

    // ΔT_up, ΔT_nut from sensor groups (first principal component of each)
    let g = dir.path().join("zg.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        d,
        "--target",
        "ez_um",
        "--model",
        "exp-ambient",
        "--up-sensors",
        "up,column",
        "--nut-sensors",
        "nut,up",
        "--train",
        "1,2,4",
        "--test",
        "3",
        "-o",
        g.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let gf: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&g).unwrap()).unwrap();
    let up = gf["model"]["up_group"].as_array().unwrap();
    assert_eq!(up.len(), 2);
    assert_eq!(up[1]["sensor"], "column_c");
    assert!(String::from_utf8_lossy(&o.stdout).contains("first principal component"));
    assert!(
        gf["test_metrics"]["rmse_um"].as_f64().unwrap()
            < file["test_metrics"]["rmse_um"].as_f64().unwrap()
    );
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        g.to_str().unwrap(),
        "--data",
        d,
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // groups go with exp-ambient only
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        d,
        "--target",
        "ez_um",
        "--model",
        "mlr",
        "--up-sensors",
        "up",
        "--nut-sensors",
        "nut",
        "-o",
        dir.path().join("w.json").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));

    // one ambient level: refused, exit 2, message says why
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        d,
        "--target",
        "ez_um",
        "--model",
        "exp-ambient",
        "--sensors",
        "up,nut",
        "--train",
        "2",
        "-o",
        dir.path().join("x.json").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("one level"), "{}", stderr(&o));

    // no position spread: the spindle log has no position_mm column
    let sp = scenario(dir.path(), "spindle-sensors");
    let o = mtec(&[
        "thermal",
        "fit",
        "--data",
        sp.to_str().unwrap(),
        "--target",
        "radial_um",
        "--model",
        "exp-ambient",
        "--sensors",
        "s1,s3",
        "-o",
        dir.path().join("y.json").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("position_mm"), "{}", stderr(&o));
}

#[test]
fn bad_input_is_located_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.csv");
    std::fs::write(
        &f,
        "experiment,time_min,a_c,b_c,drift_um\n1,0,20,20,0\n1,1,21,x,1\n1,2,22,21,2\n",
    )
    .unwrap();
    let o = mtec(&[
        "thermal",
        "select",
        "--data",
        f.to_str().unwrap(),
        "--target",
        "drift_um",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("bad.csv:3:4"), "{}", stderr(&o));

    std::fs::write(
        &f,
        "experiment,time_min,a_c,b_c,drift_um\n1,0,20,20,0\n1,1,21,20.5,1\n",
    )
    .unwrap();
    let o = mtec(&[
        "thermal",
        "select",
        "--data",
        f.to_str().unwrap(),
        "--target",
        "ez_um",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("bad.csv:1") && stderr(&o).contains("ez_um"),
        "{}",
        stderr(&o)
    );

    std::fs::write(&f, "experiment,time_min,a_c,drift_um\n1,5,20,0\n1,1,21,1\n").unwrap();
    let o = mtec(&[
        "thermal",
        "select",
        "--data",
        f.to_str().unwrap(),
        "--target",
        "drift_um",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("bad.csv:3:2") && stderr(&o).contains("time goes back"),
        "{}",
        stderr(&o)
    );

    // a logger's error code for a failed sensor is refused where it stands, in fit and select
    // alike (columns: experiment, time_min, spindle_rpm, a_c, b_c, ambient_c, drift_um)
    let m_out = dir.path().join("out.json");
    for (row, col) in [
        ("1,2,0,-9999,20.1,22,0.7", 4),
        ("1,2,0,20.3,1372,22,0.7", 5),
        ("1,2,0,20.3,20.1,-273.2,0.7", 6),
    ] {
        std::fs::write(
            &f,
            format!("experiment,time_min,spindle_rpm,a_c,b_c,ambient_c,drift_um\n1,0,0,20,20,22,0\n1,1,0,20.2,20,22,0.5\n{row}\n"),
        )
        .unwrap();
        let data = f.to_str().unwrap();
        for args in [
            vec![
                "thermal",
                "fit",
                "--model",
                "mlr",
                "--target",
                "drift_um",
                "--data",
                data,
                "-o",
                m_out.to_str().unwrap(),
            ],
            vec!["thermal", "select", "--target", "drift_um", "--data", data],
        ] {
            let o = mtec(&args);
            assert_eq!(o.status.code(), Some(2), "{row}: {}", stderr(&o));
            assert!(
                stderr(&o).contains(&format!("bad.csv:4:{col}"))
                    && stderr(&o).contains("no machine tool is at that temperature"),
                "{row}: {}",
                stderr(&o)
            );
        }
    }
    assert!(!m_out.exists());
    // the limits themselves are temperatures
    let rows: String = (0..40)
        .map(|i| {
            let t = if i == 3 {
                -60.0
            } else if i == 7 {
                300.0
            } else {
                20.0 + 0.1 * i as f64
            };
            format!("1,{i},{t},{}\n", 0.5 * i as f64)
        })
        .collect();
    std::fs::write(&f, format!("experiment,time_min,a_c,drift_um\n{rows}")).unwrap();
    let o = mtec(&[
        "thermal",
        "select",
        "--target",
        "drift_um",
        "--data",
        f.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let m = dir.path().join("m.json");
    std::fs::write(&m, "{\"format\": \"mtec.errors/1\"}").unwrap();
    let o = mtec(&[
        "thermal",
        "predict",
        "--model",
        m.to_str().unwrap(),
        "--data",
        f.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn auto_says_why_the_heat_input_families_are_absent_and_has_no_error_bar_from_one_fold() {
    // spindle-sensors: eight sensors, no spindle speed column, one forward fold
    let dir = tempfile::tempdir().unwrap();
    let data = scenario(dir.path(), "spindle-sensors");
    let out = dir.path().join("m.json");
    let o = mtec(&[
        "thermal",
        "fit",
        "--model",
        "auto",
        "--data",
        data.to_str().unwrap(),
        "--target",
        "radial_um",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
    assert!(
        text.contains("heat-input, dynamic: not candidates: the log has no heat-input column"),
        "{text}"
    );
    let ridge = text
        .lines()
        .find(|l| l.trim_start().starts_with("ridge "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(ridge.contains("± n/a"), "{ridge}");
}
