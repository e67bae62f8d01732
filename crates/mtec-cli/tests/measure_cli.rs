//! `mtec iso230-2` and `mtec circular` end to end: simulated files in, reports out, exit codes.

mod support;

use std::path::Path;

fn mtec(args: &[&str]) -> (i32, String, String) {
    let out = support::mtec(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn write_scenario(name: &str, dir: &Path) {
    support::write_scenario(name, 11, dir);
}

#[test]
fn iso230_2_json_has_the_promised_keys() {
    let dir = tempfile::tempdir().unwrap();
    write_scenario("iso230-2", dir.path());
    let run = dir.path().join("iso230-2.csv");
    let (code, stdout, stderr) = mtec(&["iso230-2", run.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["format"], "mtec.iso230-2/1");
    for k in [
        "A_um",
        "E_um",
        "R_um",
        "B_um",
        "M_um",
        "mean_B_um",
        "A_up_um",
        "A_down_um",
        "E_up_um",
        "E_down_um",
        "R_up_um",
        "R_down_um",
    ] {
        assert!(v[k].as_f64().is_some(), "missing {k}");
    }
    assert!(v["vdi3441"]["P_um"].as_f64().unwrap() > 0.0);
    let (code, stdout, _) = mtec(&["iso230-2", run.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(stdout.contains("VDI/DGQ 3441"), "{stdout}");
}

#[test]
fn bad_input_exits_2_with_a_location() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.csv");
    std::fs::write(
        &p,
        "target_mm,run,direction,deviation_um\n0,1,+,1\n0,1,up,2\n",
    )
    .unwrap();
    let (code, _, stderr) = mtec(&["iso230-2", p.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(stderr.contains("bad.csv:3:3"), "{stderr}");

    std::fs::write(&p, "angle_deg,direction,dl_um\n0,cw,1\n").unwrap();
    let (code, _, stderr) = mtec(&["circular", p.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(stderr.contains("radius is unknown"), "{stderr}");
    let (code, _, stderr) = mtec(&["circular", p.to_str().unwrap(), "--plane", "QQ"]);
    assert_eq!(code, 2, "{stderr}");
}

#[test]
fn circular_reports_ranked_diagnostics_and_writes_a_polar_plot() {
    let dir = tempfile::tempdir().unwrap();
    write_scenario("circular-test", dir.path());
    let run = dir.path().join("circular.csv");
    let out = dir.path().join("result");
    let (code, stdout, stderr) = mtec(&[
        "circular",
        run.to_str().unwrap(),
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["format"], "mtec.circular/1");
    assert!(v["iso230_4"]["G_bidirectional_um"].as_f64().unwrap() > 0.0);
    let faults = v["diagnostics"]["faults"].as_array().unwrap();
    // ranked: contributions never increase down the list; the servo mismatch dominates
    let c: Vec<f64> = faults
        .iter()
        .map(|f| f["contribution_um"].as_f64().unwrap())
        .collect();
    assert!(c.windows(2).all(|w| w[0] >= w[1]));
    assert_eq!(faults[0]["id"], "servo_mismatch");
    let svg = std::fs::read_to_string(out.join("polar.svg")).unwrap();
    assert!(svg.starts_with("<svg"));
    assert!(out.join("circular.json").exists());
    let (code, stdout, _) = mtec(&["circular", run.to_str().unwrap()]);
    assert_eq!(code, 0);
    assert!(stdout.contains("circular hysteresis H"), "{stdout}");
}
