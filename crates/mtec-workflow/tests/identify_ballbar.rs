//! `ops::identify_ballbar` in-process on the simulated dbb-rotary set: the temperatures joined
//! into each record equal the log's row (parsed here), `motions.csv` holds the records, the
//! files the CLI writes, and a log missing a measurement's time located at the data line.

use mtec_workflow::ops::identify_ballbar::{self, Options};
use mtec_workflow::{Error, Silent};
use std::collections::BTreeMap;
use std::path::Path;

fn scenario(dir: &Path) {
    let out = mtec_sim::run_scenario("dbb-rotary", 1).unwrap();
    for f in out.files {
        std::fs::write(dir.join(&f.name), f.contents).unwrap();
    }
}

fn options(d: &Path, temps: &str) -> Options {
    Options {
        setup: d.join("setup.toml"),
        data: d.join("dbb.csv"),
        temps: Some(d.join(temps)),
        out: Some(d.join("id")),
    }
}

#[test]
fn records_carry_the_logged_temperatures_and_the_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenario(d);
    let o = identify_ballbar::run(&options(d, "temps.csv"), &mut Silent).unwrap();
    assert_eq!(o.format, "mtec.ballbar-identification/1");
    assert_eq!(o.conditioning.rank, 5);
    // the log, read here: (experiment, time) -> sensor -> °C
    let text = std::fs::read_to_string(d.join("temps.csv")).unwrap();
    let mut rows = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let mut log: BTreeMap<(i64, String), BTreeMap<String, f64>> = BTreeMap::new();
    for r in rows {
        let c: Vec<&str> = r.split(',').collect();
        let t: f64 = c[1].parse().unwrap();
        let temps = header[2..]
            .iter()
            .zip(&c[2..])
            .map(|(h, v)| (h.to_string(), v.parse().unwrap()))
            .collect();
        log.insert((c[0].parse().unwrap(), format!("{t}")), temps);
    }
    assert!(o.motions.len() > 100);
    for m in &o.motions {
        let want = &log[&(m.experiment, format!("{}", m.time_min))];
        assert_eq!(
            &m.temperatures_c, want,
            "experiment {} t {}",
            m.experiment, m.time_min
        );
    }
    // motions.csv: one row per record, EXC to 0.1 nm
    let csv = std::fs::read_to_string(d.join("id/motions.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), o.motions.len() + 1);
    assert!(lines[0].starts_with("experiment,time_min,angle_deg,EXC_um,EYC_um,EZC_um"));
    let first: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(first[3], format!("{:.4}", o.motions[0].exc_um));
    for f in ["conditioning.json", "polar_EXC.svg", "time_EBC.svg"] {
        assert!(d.join("id").join(f).is_file(), "{f}");
    }
    let v: serde_json::Value = serde_json::from_str(&o.to_json().unwrap()).unwrap();
    assert_eq!(v["motions"].as_array().unwrap().len(), o.motions.len());
    assert!(v["motions"][0]["EXC_um"].is_number());
}

#[test]
fn a_measurement_without_temperatures_is_located() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenario(d);
    let text = std::fs::read_to_string(d.join("temps.csv")).unwrap();
    let short: Vec<&str> = text.lines().take(3).collect();
    std::fs::write(d.join("short.csv"), short.join("\n") + "\n").unwrap();
    match identify_ballbar::run(&options(d, "short.csv"), &mut Silent) {
        Err(Error::Input(e)) => {
            assert_eq!(e.file, d.join("dbb.csv"));
            assert!(
                e.line.is_some() && e.message.contains("no temperatures"),
                "{e}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(!d.join("id").exists());
}
