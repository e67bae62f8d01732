//! The stateful machine error model (`mtec.machine-error/1`): a grid map plus a thermal model
//! run on line, checked against the analytic first-order lag response; the envelope rule (fade
//! to no thermal correction outside the training range); refusals with located messages.

use mtec_comp::{Compensator, CorrectionOptions, ErrorModel, StateError};
use mtec_thermal::{linear_model::LinearMethod, Split};
use mtec_thermal::{Feature, LinearModel, Metrics, ModelFile, ThermalModel, MODEL_FORMAT};
use std::path::{Path, PathBuf};

/// δ = 2 + 3·L₂₀[t1] − 1·t2  (µm): a lag of 20 min on t1, t2 directly.
fn thermal_file() -> String {
    let model = ThermalModel::Linear(LinearModel {
        method: LinearMethod::Mlr,
        features: vec![
            Feature::Lag {
                sensor: "t1_c".into(),
                tau_min: 20.0,
            },
            Feature::Temp {
                sensor: "t2_c".into(),
            },
        ],
        intercept_um: 2.0,
        coefficients: vec![3.0, -1.0],
        std_errors: None,
        ridge: None,
        warnings: Vec::new(),
    });
    let f = ModelFile {
        format: MODEL_FORMAT.into(),
        target: "ez_um".into(),
        model,
        split: Split::default(),
        train_metrics: Metrics::new(&[0.0, 1.0, 2.0], &[0.0, 1.0, 2.0], 2),
        test_metrics: None,
        validation: None,
        envelope: Vec::new(),
        candidates: Vec::new(),
        warnings: Vec::new(),
    };
    serde_json::to_string_pretty(&f).unwrap()
}

/// A map with e = (4, −1, 0.5) µm everywhere.
const MAP: &str = r#"{"format":"mtec.map/1","model":"trilinear","outside":"clamp","source":"test",
  "x_mm":[0,100],"y_mm":[0,100],"z_mm":[0,100],
  "ex_um":[4,4,4,4,4,4,4,4],"ey_um":[-1,-1,-1,-1,-1,-1,-1,-1],
  "ez_um":[0.5,0.5,0.5,0.5,0.5,0.5,0.5,0.5]}"#;

fn machine_json(extra_part: &str, envelope: &str) -> String {
    format!(
        r#"{{
  "format": "mtec.machine-error/1",
  "geometric": "map.json",
  "thermal": [
    {{"axis": "z", "model": "thermal.json", "sign": 1,
      "envelope": {envelope}}}{extra_part}
  ]
}}"#
    )
}

const ENVELOPE: &str = r#"{"t1_c": [19, 31], "t2_c": [18, 22]}"#;

fn setup(machine: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("map.json"), MAP).unwrap();
    std::fs::write(dir.path().join("thermal.json"), thermal_file()).unwrap();
    let p = dir.path().join("machine.json");
    std::fs::write(&p, machine).unwrap();
    (dir, p)
}

fn load(p: &Path) -> Box<dyn ErrorModel> {
    mtec_comp::load_error_model(p).unwrap()
}

#[test]
fn thermal_part_follows_the_lag_and_adds_to_the_map() {
    let (_d, p) = setup(&machine_json("", ENVELOPE));
    let mut m = load(&p);
    assert_eq!(m.state_inputs(), ["t1_c", "t2_c"]);
    // before the first reading: the map alone
    assert_eq!(m.error_um([50.0, 50.0, 50.0]), [4.0, -1.0, 0.5]);
    // start at 20 °C, then t1 steps to 30 °C: L(t) = 20 + 10·(1 − e^(−t/20))
    let s = m.update_state(&[20.0, 20.0], 0.0).unwrap();
    assert_eq!((s.thermal_weight, s.outside), (1.0, None));
    let at = |t_min: f64| 2.0 + 3.0 * (20.0 + 10.0 * (1.0 - (-t_min / 20.0f64).exp())) - 20.0;
    assert!((m.error_um([0.0; 3])[2] - (0.5 + at(0.0))).abs() < 1e-12);
    let mut t = 0.0;
    for dt_s in [1.0, 15.0, 60.0, 600.0, 1800.0] {
        m.update_state(&[30.0, 20.0], dt_s).unwrap();
        t += dt_s / 60.0;
        let e = m.error_um([10.0, 20.0, 30.0]);
        assert_eq!([e[0], e[1]], [4.0, -1.0]);
        assert!((e[2] - (0.5 + at(t))).abs() < 1e-9, "t={t}: {}", e[2]);
    }
    // the compensator solves with the state: the correction cancels map + drift
    let mut comp = Compensator::new(m, CorrectionOptions::default());
    let c = comp.correction_um([50.0, 50.0, 50.0]).unwrap();
    assert!((c[2] + 0.5 + at(t)).abs() < 1e-6, "{c:?}");
    comp.update_state(&[30.0, 20.0], 3600.0).unwrap();
    let c2 = comp.correction_um([50.0, 50.0, 50.0]).unwrap();
    assert!((c2[2] + 0.5 + at(t + 60.0)).abs() < 1e-6, "{c2:?}");
}

#[test]
fn outside_the_envelope_the_thermal_part_fades_to_nothing() {
    let (_d, p) = setup(&machine_json("", ENVELOPE));
    let mut m = load(&p);
    m.update_state(&[25.0, 20.0], 0.0).unwrap();
    let inside = m.error_um([0.0; 3])[2] - 0.5;
    assert!((inside - (2.0 + 75.0 - 20.0)).abs() < 1e-12);
    // t2 = 23 °C: 1 °C beyond 22 °C, half of the 2 °C fade width
    let s = m.update_state(&[25.0, 23.0], 0.0).unwrap();
    assert_eq!(s.outside, Some(1));
    assert!((s.thermal_weight - 0.5).abs() < 1e-12);
    let half = m.error_um([0.0; 3])[2] - 0.5;
    assert!((half - 0.5 * (2.0 + 75.0 - 23.0)).abs() < 1e-12, "{half}");
    // 5 °C beyond: no thermal correction at all, the map still applies
    let s = m.update_state(&[25.0, 27.0], 0.0).unwrap();
    assert_eq!((s.thermal_weight, s.outside), (0.0, Some(1)));
    assert_eq!(m.error_um([0.0; 3]), [4.0, -1.0, 0.5]);
    // below the range too, and the worst input is reported
    let s = m.update_state(&[17.5, 17.0], 0.0).unwrap();
    assert_eq!(s.outside, Some(0));
    assert!((s.thermal_weight - 0.25).abs() < 1e-12);
    // back inside: full weight again (the filters kept running meanwhile)
    let s = m.update_state(&[25.0, 20.0], 0.0).unwrap();
    assert_eq!((s.thermal_weight, s.outside), (1.0, None));
}

#[test]
fn a_guard_column_fades_the_part_although_the_model_does_not_read_it() {
    // the envelope names `air_c`, which the model does not read: it becomes a state input
    let (_d, p) = setup(&machine_json(
        "",
        r#"{"t1_c": [19, 31], "t2_c": [18, 22], "air_c": [18, 24]}"#,
    ));
    let mut m = load(&p);
    assert_eq!(m.state_inputs(), ["t1_c", "t2_c", "air_c"]);
    m.update_state(&[25.0, 20.0, 21.0], 0.0).unwrap();
    let inside = m.error_um([0.0; 3])[2] - 0.5;
    assert!((inside - (2.0 + 75.0 - 20.0)).abs() < 1e-12);
    // the air 1.5 °C above its range: weight 1 − 1.5/2, the model's own inputs inside theirs
    let s = m.update_state(&[25.0, 20.0, 25.5], 0.0).unwrap();
    assert_eq!(s.outside, Some(2));
    assert!((s.thermal_weight - 0.25).abs() < 1e-12);
    let faded = m.error_um([0.0; 3])[2] - 0.5;
    assert!(
        (faded - 0.25 * (2.0 + 75.0 - 20.0)).abs() < 1e-12,
        "{faded}"
    );
}

#[test]
fn bad_readings_are_refused_and_leave_the_state_alone() {
    let (_d, p) = setup(&machine_json("", ENVELOPE));
    let mut m = load(&p);
    m.update_state(&[25.0, 20.0], 0.0).unwrap();
    let before = m.error_um([0.0; 3]);
    assert_eq!(
        m.update_state(&[25.0], 1.0),
        Err(StateError::Count {
            given: 1,
            expected: 2
        })
    );
    assert_eq!(
        m.update_state(&[25.0, f64::NAN], 1.0),
        Err(StateError::NotFinite { index: 1 })
    );
    assert_eq!(
        m.update_state(&[30.0, 20.0], -1.0),
        Err(StateError::TimeStep)
    );
    assert_eq!(m.error_um([0.0; 3]), before);
    // a static model takes no readings
    let (_d2, p2) = setup(&machine_json("", ENVELOPE));
    let mut map = mtec_comp::load_error_model(&p2.with_file_name("map.json")).unwrap();
    assert!(map.state_inputs().is_empty());
    assert!(map.update_state(&[], 1.0).is_ok());
    assert!(map.update_state(&[20.0], 1.0).is_err());
}

#[test]
fn bad_machine_files_are_refused_with_a_location() {
    let cases = [
        (
            machine_json("", r#"{"t1_c": [19, 31]}"#),
            "no training range for input `t2_c`",
        ),
        (
            machine_json("", r#"{"t1_c": [19, 31], "t2_c": [22, 18]}"#),
            "is not a range",
        ),
        (
            machine_json("", ENVELOPE).replace("\"axis\": \"z\"", "\"axis\": \"w\""),
            "x, y or z",
        ),
        (
            machine_json("", ENVELOPE).replace("\"sign\": 1", "\"sign\": 2"),
            "must be 1 or -1",
        ),
        (
            machine_json("", ENVELOPE).replace("thermal.json", "missing.json"),
            "missing.json",
        ),
        (
            machine_json("", ENVELOPE).replace("machine-error/1", "machine-error/9"),
            "unknown model format `mtec.machine-error/9`",
        ),
        (
            machine_json("", ENVELOPE).replace("\"sign\"", "\"sing\""),
            "unknown field",
        ),
    ];
    for (text, want) in cases {
        let (_d, p) = setup(&text);
        let err = mtec_comp::load_error_model(&p)
            .err()
            .unwrap_or_else(|| panic!("accepted: {text}"));
        let msg = err.to_string();
        assert!(msg.contains(want), "{msg}\nwanted: {want}");
        if !want.contains("missing.json") {
            assert!(err.line.is_some(), "no line in: {msg}");
        }
    }
}
