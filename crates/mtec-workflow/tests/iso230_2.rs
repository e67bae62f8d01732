//! `ops::iso230_2` in-process: the statistics against the ISO 230-2 definitions worked here
//! from the run file's rows, the file written, and a bad row located.

use mtec_workflow::ops::iso230_2::{self, Options};
use mtec_workflow::{Collect, Error};
use std::collections::BTreeMap;
use std::path::Path;

fn simulated_run(dir: &Path) -> std::path::PathBuf {
    let out = mtec_sim::run_scenario("iso230-2", 5).unwrap();
    for f in out.files {
        std::fs::write(dir.join(&f.name), f.contents).unwrap();
    }
    dir.join("iso230-2.csv")
}

/// Mean and sample standard uncertainty (ISO 230-2 eq. 5 and 7) of each target's deviations in
/// one direction, straight from the CSV text.
fn by_target(csv: &str, dir: &str) -> Vec<(f64, f64, f64)> {
    let mut g: BTreeMap<i64, Vec<f64>> = BTreeMap::new();
    for line in csv.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f[2] == dir {
            let t: f64 = f[0].parse().unwrap();
            g.entry((t * 1e6).round() as i64)
                .or_default()
                .push(f[3].parse().unwrap());
        }
    }
    g.into_iter()
        .map(|(t, x)| {
            let n = x.len() as f64;
            let m = x.iter().sum::<f64>() / n;
            let s = (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            (t as f64 / 1e6, m, s)
        })
        .collect()
}

#[test]
fn statistics_follow_the_iso_definitions_and_the_file_is_the_json() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let csv = std::fs::read_to_string(&run).unwrap();
    let out = dir.path().join("res");
    let mut opts = Options::new(&run);
    opts.out = Some(out.clone());
    let mut obs = Collect::default();
    let o = iso230_2::run(&opts, &mut obs).unwrap();
    assert_eq!(obs.warnings.len(), o.warnings.len());

    let up = by_target(&csv, "+");
    let down = by_target(&csv, "-");
    assert_eq!(o.targets.len(), up.len());
    assert!(up.len() >= 5);
    for ((t, (p, mu, su)), (_, md, sd)) in o.targets.iter().zip(&up).zip(&down) {
        assert!((t.target_mm - p).abs() < 1e-9);
        assert!((t.mean_up_um - mu).abs() < 1e-9, "{} vs {mu}", t.mean_up_um);
        assert!((t.mean_down_um - md).abs() < 1e-9);
        assert!((t.s_up_um - su).abs() < 1e-9);
        assert!((t.s_down_um - sd).abs() < 1e-9);
        // eq. 8: B_i = mean up - mean down
        assert!((t.reversal_um - (mu - md)).abs() < 1e-9);
    }
    let max = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::MIN, f64::max);
    let min = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::MAX, f64::min);
    // R_up = max 4 s_up; E_up = max mean - min mean; A_up = max(mean + 2s) - min(mean - 2s);
    // M = range of the bidirectional means; B = max |B_i|
    let r_up = max(&mut up.iter().map(|u| 4.0 * u.2));
    let e_up = max(&mut up.iter().map(|u| u.1)) - min(&mut up.iter().map(|u| u.1));
    let a_up =
        max(&mut up.iter().map(|u| u.1 + 2.0 * u.2)) - min(&mut up.iter().map(|u| u.1 - 2.0 * u.2));
    let bi: Vec<f64> = up
        .iter()
        .zip(&down)
        .map(|(u, d)| (u.1 + d.1) / 2.0)
        .collect();
    let m = max(&mut bi.iter().copied()) - min(&mut bi.iter().copied());
    let b = max(&mut up.iter().zip(&down).map(|(u, d)| (u.1 - d.1).abs()));
    assert!((o.axis.r_up_um - r_up).abs() < 1e-9);
    assert!((o.axis.e_up_um - e_up).abs() < 1e-9);
    assert!((o.axis.a_up_um - a_up).abs() < 1e-9);
    assert!((o.axis.m_um - m).abs() < 1e-9);
    assert!((o.axis.b_um - b).abs() < 1e-9);
    assert_eq!(o.corrections.scale_factor, 1.0);

    // the one file the CLI writes, with the JSON the CLI prints (format and the axis keys at
    // the top level, as docs/formats.md shows)
    let names: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names, ["iso230-2.json"]);
    let text = std::fs::read_to_string(out.join("iso230-2.json")).unwrap();
    assert_eq!(text, o.to_json().unwrap());
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["format"], "mtec.iso230-2/1");
    assert_eq!(v["A_up_um"].as_f64().unwrap(), o.axis.a_up_um);
    assert!(v["corrections"]["air"].is_null());
    assert!(o.to_string().contains("VDI/DGQ 3441 (um): Ps = "));
}

#[test]
fn a_bad_direction_is_located_and_an_output_over_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.csv");
    std::fs::write(
        &p,
        "target_mm,run,direction,deviation_um\n0,1,+,1\n0,1,up,2\n",
    )
    .unwrap();
    match iso230_2::run(&Options::new(&p), &mut Collect::default()) {
        Err(Error::Input(e)) => {
            assert_eq!(e.file, p);
            assert_eq!((e.line, e.column), (Some(3), Some(3)));
        }
        other => panic!("{other:?}"),
    }
    let run = simulated_run(dir.path());
    let renamed = dir.path().join("iso230-2.json");
    std::fs::rename(&run, &renamed).unwrap();
    let mut opts = Options::new(&renamed);
    opts.out = Some(dir.path().to_path_buf());
    assert!(matches!(
        iso230_2::run(&opts, &mut Collect::default()),
        Err(Error::Usage(_))
    ));
    let mut opts = Options::new(&renamed);
    opts.air_temp_c = Some(20.0);
    assert!(matches!(
        iso230_2::run(&opts, &mut Collect::default()),
        Err(Error::Usage(m)) if m.contains("--pressure-pa")
    ));
}
