//! `mtec machine build|replay`, `--state` for `compensate gcode|table`, and `mtec run` on the
//! production-day scenario, end to end through the binary.

mod support;

use std::path::{Path, PathBuf};
use support::{mtec, stderr, text};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Three experiments of a made-up log: t1 rises with the time, t2 falls, drift = 2·t1 − 40.
/// Returns the file and, per experiment, the t1 and t2 values.
fn log(dir: &Path, name: &str, rows_per_exp: usize) -> PathBuf {
    let mut csv = String::from("experiment,time_min,t1_c,t2_c,drift_um\n");
    for (e, base) in [("e1", 20.0), ("e2", 23.0), ("e3", 30.0)] {
        for k in 0..rows_per_exp {
            let t1 = base + 0.5 * k as f64;
            let t2 = 22.0 - 0.25 * k as f64 + if e == "e3" { 5.0 } else { 0.0 };
            csv.push_str(&format!(
                "{e},{},{t1},{t2},{}\n",
                10 * k,
                2.0 * t1 - 40.0 + 0.01 * ((k * 7) % 3) as f64
            ));
        }
    }
    let p = dir.join(name);
    std::fs::write(&p, csv).unwrap();
    p
}

fn fit(data: &Path, out: &Path, split: &[&str]) {
    let mut args = vec![
        "thermal",
        "fit",
        "--data",
        s(data),
        "--target",
        "drift_um",
        "--model",
        "mlr",
        "--sensors",
        "t1",
        "-o",
        s(out),
    ];
    args.extend(split);
    let o = mtec(&args);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn build_takes_the_envelope_from_the_training_rows_and_writes_relative_paths() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = log(d, "log.csv", 6);
    let model = d.join("m.json");
    fit(&data, &model, &["--train", "e1,e2", "--test", "e3"]);
    let machine = d.join("sub").join("machine.json");
    let o = mtec(&[
        "machine",
        "build",
        "--thermal",
        &format!("z={}", s(&model)),
        "--data",
        s(&data),
        "--guard",
        "t2_c",
        "-o",
        s(&machine),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&machine).unwrap()).unwrap();
    assert_eq!(m["format"], "mtec.machine-error/1");
    let part = &m["thermal"][0];
    assert_eq!(part["model"], "../m.json");
    assert_eq!(part["axis"], "z");
    // e1 and e2 only: t1 from 20 to 23 + 2.5, t2 from 22 − 1.25 to 22 (e3 is left out)
    assert_eq!(part["envelope"]["t1_c"], serde_json::json!([20.0, 25.5]));
    assert_eq!(part["envelope"]["t2_c"], serde_json::json!([20.75, 22.0]));

    // a model split by time: rows with time_min ≤ 20 of every experiment
    let model_t = d.join("mt.json");
    fit(&data, &model_t, &["--train-until", "20"]);
    let machine_t = d.join("machine-t.json");
    let o = mtec(&[
        "machine",
        "build",
        "--thermal",
        &format!("y={},sign=-1", s(&model_t)),
        "--data",
        s(&data),
        "-o",
        s(&machine_t),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&machine_t).unwrap()).unwrap();
    assert_eq!(m["thermal"][0]["model"], "mt.json");
    assert_eq!(m["thermal"][0]["sign"], -1.0);
    assert_eq!(
        m["thermal"][0]["envelope"]["t1_c"],
        serde_json::json!([20.0, 31.0])
    );

    // other data than the model was fitted on: refused, nothing written
    let other = log(d, "other.csv", 8);
    let refused = d.join("refused.json");
    let o = mtec(&[
        "machine",
        "build",
        "--thermal",
        &format!("z={}", s(&model)),
        "--data",
        s(&other),
        "-o",
        s(&refused),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        stderr(&o).contains("16 training rows here") && stderr(&o).contains("fitted on 12"),
        "{}",
        stderr(&o)
    );
    assert!(!refused.exists());
    // a bad --thermal value, and a guard the data lacks
    for (bad, want) in [
        (format!("w={}", s(&model)), "the axis is x, y or z"),
        (format!("z={},sign=2", s(&model)), "sign=1 or sign=-1"),
    ] {
        let o = mtec(&[
            "machine",
            "build",
            "--thermal",
            &bad,
            "--data",
            s(&data),
            "-o",
            s(&refused),
        ]);
        assert_eq!(o.status.code(), Some(2));
        assert!(stderr(&o).contains(want), "{}", stderr(&o));
    }
    let o = mtec(&[
        "machine",
        "build",
        "--thermal",
        &format!("z={}", s(&model)),
        "--data",
        s(&data),
        "--guard",
        "air_c",
        "-o",
        s(&refused),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("missing column `air_c`"),
        "{}",
        stderr(&o)
    );
}

/// A machine model over a linear thermal model δ = b0 + b1·t1 (µm), and its coefficients.
fn machine_model(d: &Path) -> (PathBuf, f64, f64) {
    let data = log(d, "log.csv", 6);
    let model = d.join("m.json");
    fit(&data, &model, &["--train", "e1,e2", "--test", "e3"]);
    let machine = d.join("machine.json");
    let o = mtec(&[
        "machine",
        "build",
        "--thermal",
        &format!("z={}", s(&model)),
        "--data",
        s(&data),
        "-o",
        s(&machine),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let b0 = m["model"]["intercept_um"].as_f64().unwrap();
    let b1 = m["model"]["coefficients"][0].as_f64().unwrap();
    (machine, b0, b1)
}

#[test]
fn a_stateful_model_needs_a_state_log_and_uses_its_last_row() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (machine, b0, b1) = machine_model(d);
    let prog = d.join("p.ngc");
    std::fs::write(&prog, "G21 G90\nG0 X0 Y0 Z10\nG1 Z50 F100\n").unwrap();
    let out = d.join("out.ngc");
    let table = d.join("z.comp");

    // without --state: refused with what to do, nothing written
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&machine),
        s(&prog),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        stderr(&o).contains("has a state (inputs: t1_c)") && stderr(&o).contains("--state LOG.csv"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    let o = mtec(&[
        "compensate",
        "table",
        "--model",
        s(&machine),
        "--format",
        "linuxcnc",
        "--axis",
        "Z",
        "--range=0:100:50",
        "-o",
        s(&table),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(!table.exists());

    // with a log: the state after its last row (t1 = 24 °C)
    let state = d.join("state.csv");
    std::fs::write(&state, "time_min,t1_c\n0,21\n5,22.5\n10,24\n").unwrap();
    let o = mtec(&[
        "compensate",
        "table",
        "--model",
        s(&machine),
        "--state",
        s(&state),
        "--format",
        "linuxcnc",
        "--axis",
        "Z",
        "--range=0:100:50",
        "-o",
        s(&table),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        stderr(&o).contains("state after") && stderr(&o).contains("3 readings"),
        "{}",
        stderr(&o)
    );
    let delta_mm = (b0 + b1 * 24.0) / 1000.0;
    let t = std::fs::read_to_string(&table).unwrap();
    assert_eq!(t.lines().count(), 3);
    for line in t.lines() {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        // LinuxCNC COMP_FILE_TYPE 1: nominal, trim forward, trim reverse; the trim is −δ
        assert!((v[1] + delta_mm).abs() < 1e-6, "{line} vs {delta_mm}");
        assert!((v[2] + delta_mm).abs() < 1e-6, "{line} vs {delta_mm}");
    }
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&machine),
        "--state",
        s(&state),
        s(&prog),
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let g = std::fs::read_to_string(&out).unwrap();
    assert!(g.contains("state after"), "{g}");
    // G1 Z50 → Z = 50 − δ (mm, 4 decimals)
    let want = format!("Z{:.4}", 50.0 - delta_mm);
    assert!(g.contains(want.trim_end_matches('0')), "{g} vs {want}");

    // a static model refuses --state; a log going back in time or lacking a column is refused
    // at its line and column
    let zero = d.join("zero.json");
    std::fs::write(&zero, r#"{"format": "mtec.zero-model/1"}"#).unwrap();
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&zero),
        "--state",
        s(&state),
        s(&prog),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("static model"), "{}", stderr(&o));
    let back = d.join("back.csv");
    std::fs::write(&back, "time_min,t1_c\n0,21\n5,22.5\n4,24\n").unwrap();
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&machine),
        "--state",
        s(&back),
        s(&prog),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("back.csv:4:1") && stderr(&o).contains("time goes back"),
        "{}",
        stderr(&o)
    );
    let lacking = d.join("lacking.csv");
    std::fs::write(&lacking, "time_min,t2_c\n0,21\n").unwrap();
    let o = mtec(&[
        "compensate",
        "gcode",
        "--model",
        s(&machine),
        "--state",
        s(&lacking),
        s(&prog),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("missing column `t1_c`"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn replay_compensates_each_probe_reading_with_the_state_up_to_its_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (machine, b0, b1) = machine_model(d);
    let state = d.join("state.csv");
    std::fs::write(&state, "time_min,t1_c\n0,21\n10,23\n20,25\n").unwrap();
    // probes at 5 and 20 min: the state then is t1 = 21 and 25 °C; measured errors equal to
    // the model at 20 min, twice it at 5 min
    let d21 = b0 + b1 * 21.0;
    let d25 = b0 + b1 * 25.0;
    let probes = d.join("probes.csv");
    std::fs::write(
        &probes,
        format!(
            "time_min,probe,x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n5,a,0,0,0,1,0,{}\n20,a,0,0,0,0,0,{d25}\n",
            2.0 * d21
        ),
    )
    .unwrap();
    let out = d.join("replay.csv");
    let o = mtec(&[
        "machine",
        "replay",
        "--model",
        s(&machine),
        "--state",
        s(&state),
        "--probes",
        s(&probes),
        "-o",
        s(&out),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["format"], "mtec.machine-replay/1");
    assert_eq!(v["readings"], 2);
    // after: ez = d21 (5 min), 0 (20 min); ex untouched
    let rms_after = (d21 * d21 / 2.0).sqrt();
    let rms_before = ((4.0 * d21 * d21 + d25 * d25) / 2.0).sqrt();
    assert!(
        (v["z"]["rms_after_um"].as_f64().unwrap() - rms_after).abs() < 1e-6,
        "{v}"
    );
    assert!((v["z"]["rms_before_um"].as_f64().unwrap() - rms_before).abs() < 1e-9);
    assert_eq!(v["x"]["rms_after_um"], v["x"]["rms_before_um"]);
    let rows = std::fs::read_to_string(&out).unwrap();
    assert_eq!(rows.lines().filter(|l| !l.starts_with('#')).count(), 3);

    // a probe reading before the first state reading has no state to use
    std::fs::write(&state, "time_min,t1_c\n6,21\n").unwrap();
    let o = mtec(&[
        "machine",
        "replay",
        "--model",
        s(&machine),
        "--state",
        s(&state),
        "--probes",
        s(&probes),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("probes.csv:2:1") && stderr(&o).contains("no state yet"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn run_fits_builds_and_compensates_the_production_day() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    support::write_scenario("production-day", 2, d);
    let out = d.join("results");
    let o = mtec(&[
        "run",
        s(&d.join("project.toml")),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
    };
    let day = read("replay-day-probes.json");
    let v = &day["vector"];
    assert!(v["compensation_rate"].as_f64().unwrap() >= 0.85, "{day}");
    assert!(v["worst_reduction"].as_f64().unwrap() >= 0.70, "{day}");
    let hot = read("replay-day-hot-probes.json");
    assert_eq!(hot["worse"], 0, "{hot}");
    assert_eq!(hot["faded"], hot["readings"], "{hot}");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("Compensation replay: unseen day"));
    assert!(html.contains("Error at the tool tip, worst probe point"));
    assert!(html.contains("Thermal weight (envelope rule)"));
    assert!(out.join("machine.json").exists());
}
