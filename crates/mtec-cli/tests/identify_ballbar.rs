//! `mtec identify ballbar` end to end: scenario files in, motions and conditioning out; bad input
//! exits 2 with a located message.

mod support;

use support::mtec;

fn write_scenario(dir: &std::path::Path) {
    support::write_scenario("dbb-rotary", 2, dir);
}

#[test]
fn identifies_and_joins_temperatures() {
    let dir = tempfile::tempdir().unwrap();
    write_scenario(dir.path());
    let o = support::identify_ballbar(dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.path().join("id/motions.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "experiment,time_min,angle_deg,EXC_um,EYC_um,EZC_um,EAC_urad,EBC_urad,T1_c,T2_c,T3_c,T4_c,T5_c,T6_c,T7_c,T8_c,T9_c"
    );
    assert_eq!(lines.count(), 4 * 13 * 72);
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("id/conditioning.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(report["format"], "mtec.ballbar-conditioning/1");
    assert_eq!(report["rank"], 5);
    assert_eq!(report["per_angle"].as_array().unwrap().len(), 72);
    let polar = std::fs::read_to_string(dir.path().join("id/polar_EAC.svg")).unwrap();
    assert!(polar.starts_with("<svg") && polar.contains("exp 4, 240 min"));
    assert!(dir.path().join("id/time_EBC.svg").exists());

    // --json prints the same rows
    let p = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let o = mtec(&[
        "identify",
        "ballbar",
        "--setup",
        &p("setup.toml"),
        "--data",
        &p("dbb.csv"),
        "--json",
    ]);
    assert!(o.status.success());
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(doc["format"], "mtec.ballbar-identification/1");
    assert_eq!(doc["motions"].as_array().unwrap().len(), 4 * 13 * 72);
}

#[test]
fn bad_input_exits_2_with_location() {
    let dir = tempfile::tempdir().unwrap();
    write_scenario(dir.path());
    let p = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    // a rank-deficient mode set: mode 5's ball moved onto mode 3's mount
    let setup = std::fs::read_to_string(dir.path().join("setup.toml")).unwrap();
    let m3 = setup.find("id = 3").unwrap();
    let ball3 = setup[m3..].lines().nth(1).unwrap().to_string();
    let m5 = setup.find("id = 5").unwrap();
    let ball5 = setup[m5..].lines().nth(1).unwrap().to_string();
    let bad = setup[..m5].to_string() + &setup[m5..].replacen(&ball5, &ball3, 1);
    std::fs::write(dir.path().join("bad.toml"), bad).unwrap();
    let o = mtec(&[
        "identify",
        "ballbar",
        "--setup",
        &p("bad.toml"),
        "--data",
        &p("dbb.csv"),
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.toml") && err.contains("rank 4 of 5"),
        "{err}"
    );

    // a non-numeric reading: file:line:column
    let data = std::fs::read_to_string(dir.path().join("dbb.csv")).unwrap();
    let mut lines: Vec<String> = data.lines().map(String::from).collect();
    let mut f: Vec<&str> = lines[3].split(',').collect();
    f[4] = "abc";
    lines[3] = f.join(",");
    std::fs::write(dir.path().join("bad.csv"), lines.join("\n")).unwrap();
    let o = mtec(&[
        "identify",
        "ballbar",
        "--setup",
        &p("setup.toml"),
        "--data",
        &p("bad.csv"),
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.csv:4:5"), "{err}");
}
