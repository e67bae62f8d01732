//! `ops::circular` in-process: a trace made here from a known centre offset and scale mismatch
//! (first-order ballbar model, ISO 230-4 annex) gives those values back, G = the peak-to-valley
//! of the 2θ term, H = 0; the two files the CLI writes; a bad trace located.

use mtec_measure::circular::Plane;
use mtec_workflow::ops::circular::{self, Options};
use mtec_workflow::{Error, Silent};
use std::fmt::Write as _;

/// dl = c₁ cos θ + c₂ sin θ + R(s₁ − s₂)/2 · cos 2θ, both directions, 360 samples each.
fn trace(c1_um: f64, c2_um: f64, scale_ppm: f64) -> String {
    let r_um = 100_000.0;
    let mut s = String::from("# radius_mm = 100\n# plane = XY\nangle_deg,direction,dl_um\n");
    for dir in ["ccw", "cw"] {
        for i in 0..360 {
            let th = (i as f64).to_radians();
            let dl = c1_um * th.cos()
                + c2_um * th.sin()
                + r_um * scale_ppm * 1e-6 / 2.0 * (2.0 * th).cos();
            writeln!(s, "{i},{dir},{dl:.6}").unwrap();
        }
    }
    s
}

#[test]
fn a_known_trace_gives_its_faults_back_and_both_files() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("circular.csv");
    std::fs::write(&run, trace(12.0, -7.0, 40.0)).unwrap();
    let out = dir.path().join("result");
    let mut opts = Options::new(&run);
    opts.out = Some(out.clone());
    let o = circular::run(&opts, &mut Silent).unwrap();
    assert_eq!(o.plane, Plane::XY);
    assert_eq!((o.samples.ccw, o.samples.cw), (360, 360));
    // the least-squares centre is the offset (second-order terms: c²/2R < 1e-3 µm)
    let c = &o.iso230_4.circle_bidirectional;
    assert!((c.centre_um[0] - 12.0).abs() < 2e-3, "{:?}", c.centre_um);
    assert!((c.centre_um[1] + 7.0).abs() < 2e-3, "{:?}", c.centre_um);
    // what is left is R(s₁−s₂)/2 cos 2θ = 2 µm amplitude: G = 4 µm in each direction, H = 0
    assert!(
        (o.iso230_4.g_ccw_um - 4.0).abs() < 2e-3,
        "{}",
        o.iso230_4.g_ccw_um
    );
    assert!((o.iso230_4.g_cw_um - 4.0).abs() < 2e-3);
    assert!(o.iso230_4.h_um.abs() < 2e-3);
    assert!(o.arc.is_none());
    let d = &o.diagnostics;
    let value = |id: &str| d.get(id).unwrap().value.unwrap();
    assert!((value("centre_offset_X") - 12.0).abs() < 2e-3);
    assert!((value("centre_offset_Y") + 7.0).abs() < 2e-3);
    assert!((value("scale_mismatch") - 40.0).abs() < 0.05);
    assert_eq!(
        d.faults.iter().find(|f| f.present).unwrap().id,
        "scale_mismatch"
    );

    let mut names: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["circular.json", "polar.svg"]);
    let text = std::fs::read_to_string(out.join("circular.json")).unwrap();
    assert_eq!(text, o.to_json().unwrap());
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["format"], "mtec.circular/1");
    assert_eq!(v["plane"], "XY");
    assert_eq!(v["samples"]["cw"], 360);
    assert!(std::fs::read_to_string(out.join("polar.svg"))
        .unwrap()
        .starts_with("<svg"));
    assert!(o.to_string().contains("circular hysteresis H"));
}

#[test]
fn a_bad_direction_is_located() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("bad.csv");
    std::fs::write(
        &run,
        "# radius_mm = 100\nangle_deg,direction,dl_um\n0,cw,1\n1,up,1\n",
    )
    .unwrap();
    match circular::run(&Options::new(&run), &mut Silent) {
        Err(Error::Input(e)) => {
            assert_eq!(e.file, run);
            assert_eq!(e.line, Some(4), "{e}");
        }
        other => panic!("{other:?}"),
    }
    let mut opts = Options::new(&run);
    opts.threshold_um = -1.0;
    assert!(matches!(
        circular::run(&opts, &mut Silent),
        Err(Error::Usage(_))
    ));
}

/// The 220° arc of `circular-test-arc`: its span in the JSON and the text report, the
/// undetermined faults named in both; the same file read with a 60° arc refused at the option.
#[test]
fn a_partial_arc_is_evaluated_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = mtec_sim::run_scenario("circular-test-arc", 4).unwrap();
    let run = dir.path().join("circular-arc.csv");
    std::fs::write(&run, &out.files[0].contents).unwrap();
    let o = circular::run(&Options::new(&run), &mut Silent).unwrap();
    let arc = o.arc.unwrap();
    assert_eq!(
        (arc.start_deg, arc.end_deg, arc.span_deg),
        (250.0, 110.0, 220.0)
    );
    let v: serde_json::Value = serde_json::from_str(&o.to_json().unwrap()).unwrap();
    assert_eq!(v["arc"]["span_deg"], 220.0);
    let f = v["diagnostics"]["faults"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["id"] == "backlash_Z_neg")
        .unwrap();
    assert!(f["value"].is_null() && f["determined"] == false, "{f}");
    assert_eq!(f["note"], "not determined by a 220° arc");
    let text = o.to_string();
    assert!(text.contains("span 220.0°"), "{text}");
    assert!(text.contains("not determined by a 220° arc"), "{text}");

    let mut opts = Options::new(&run);
    opts.arc_deg = Some([-30.0, 30.0]);
    match circular::run(&opts, &mut Silent) {
        Err(Error::Input(e)) => assert!(e.message.contains("spans 60.0°"), "{e}"),
        other => panic!("{other:?}"),
    }
}
