//! `ops::compensate_thermal_offset` in-process on the hand-written models of the CLI's tests
//! (`crates/mtec-cli/tests/data/thermal_offset/README.md`: e = 12·t1 − 228 µm, so +12 µm at
//! 20 °C): the update against that hand value, the LinuxCNC and Siemens lines against the
//! golden files worked from the controllers' documentation, the file written, a bad log located.

use mtec_comp::thermal_offset::OutsidePolicy;
use mtec_workflow::ops::compensate_thermal_offset::{self, Format, Options};
use mtec_workflow::{Error, Silent};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../mtec-cli/tests/data/thermal_offset")
        .join(name)
}

fn golden(name: &str) -> String {
    std::fs::read_to_string(data("golden").join(name)).unwrap()
}

#[test]
fn the_g10_update_is_minus_the_drift_and_matches_the_golden_lines() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g54.ngc");
    let mut opts = Options::new(data("machine.json"), data("now.csv"), Format::G10);
    opts.base_mm = Some(-312.4501);
    opts.out = Some(out.clone());
    let o = compensate_thermal_offset::run(&opts, &mut Silent).unwrap();
    // t1 = 20 °C at the last row (line 4, 60 min): e = 12·20 − 228 = +12 µm, the offset −12 µm
    let u = o.update.as_ref().unwrap();
    assert!((u.drift_um - 12.0).abs() < 1e-9, "{u:?}");
    assert!((u.correction_um + 12.0).abs() < 1e-9, "{u:?}");
    assert_eq!(u.weight, 1.0);
    assert!(o.setting.is_none() && o.notes.is_empty());
    assert_eq!((o.now_line, o.now_time_min, o.axis), (4, 60.0, 'Z'));
    assert_eq!(o.text, golden("linuxcnc.ngc"));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), o.text);
    assert_eq!(
        o.to_string(),
        format!(
            "thermal-offset: Z offset update -12.000 um (drift +12.000 um, weight 1) at line 4 (60 min) of {}\n",
            data("now.csv").display()
        )
    );
    let json = serde_json::to_value(&o).unwrap();
    assert_eq!(json["format"], "g10");
    assert_eq!(json["axis"], "Z");
}

#[test]
fn sinumerik_frame_and_setting_data() {
    let dir = tempfile::tempdir().unwrap();
    let mut opts = Options::new(data("machine.json"), data("now.csv"), Format::Sinumerik);
    opts.out = Some(dir.path().join("frame.spf"));
    let o = compensate_thermal_offset::run(&opts, &mut Silent).unwrap();
    assert_eq!(o.text, golden("sinumerik_frame.spf"));

    // exp-ambient (README): b = 20·(1 − e^−1) µm at P0 = −500 mm, tan(beta) = k in mm/mm
    let mut opts = Options::new(
        data("exp_machine.json"),
        data("exp_now.csv"),
        Format::SinumerikSd,
    );
    opts.position_origin_mm = -500.0;
    opts.travel_mm = Some([-500.0, 0.0]);
    opts.starts_at_rest = true;
    opts.out = Some(dir.path().join("sd.spf"));
    let o = compensate_thermal_offset::run(&opts, &mut Silent).unwrap();
    assert_eq!(o.text, golden("sinumerik_sd.spf"));
    let s = o.setting.as_ref().unwrap();
    let (b_um, k) = (
        20.0 * (1.0 - (-1.0_f64).exp()),
        0.04 * (1.0 - (-1.0_f64).exp()),
    );
    assert!((s.k0_mm * 1e3 - b_um).abs() < 1e-9, "{s:?} vs b {b_um}");
    assert!((s.tan_beta - k * 1e-3).abs() < 1e-12, "{s:?} vs k {k}");
    assert_eq!((s.p0_mm, s.machine_axis.as_str()), (-500.0, "AX3"));
    assert_eq!(
        std::fs::read_to_string(dir.path().join("sd.spf")).unwrap(),
        o.text
    );
}

#[test]
fn a_bad_log_is_located_and_mistakes_are_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let temps = dir.path().join("now.csv");
    std::fs::write(&temps, "time_min,t1_c\n0,19\n30,warm\n").unwrap();
    let mut opts = Options::new(data("machine.json"), &temps, Format::G10);
    opts.base_mm = Some(0.0);
    let e = compensate_thermal_offset::run(&opts, &mut Silent).unwrap_err();
    match &e {
        Error::Input(i) => {
            assert_eq!((i.line, i.column), (Some(3), Some(2)), "{i}");
            assert!(i.message.contains("`t1_c` is `warm`"), "{i}");
        }
        other => panic!("{other:?}"),
    }

    // outside the envelope (t1 = 27 °C > 26, e = 12·27 − 228 = 96 µm): refused, or faded over
    // 2 °C to w = 1 − 1/2, c = −0.5·96 µm
    std::fs::write(&temps, "time_min,t1_c\n0,19\n60,27\n").unwrap();
    assert!(matches!(
        compensate_thermal_offset::run(&opts, &mut Silent),
        Err(Error::Input(_))
    ));
    opts.outside = OutsidePolicy::Fade;
    opts.out = Some(dir.path().join("g54.ngc"));
    let o = compensate_thermal_offset::run(&opts, &mut Silent).unwrap();
    let u = o.update.unwrap();
    assert!((u.weight - 0.5).abs() < 1e-12, "{u:?}");
    assert!((u.correction_um + 48.0).abs() < 1e-9, "{u:?}");

    // g10 without its base, an option of another format, the output over an input
    opts.base_mm = None;
    assert!(matches!(
        compensate_thermal_offset::run(&opts, &mut Silent),
        Err(Error::Usage(m)) if m.contains("--base-mm is required")
    ));
    opts.base_mm = Some(0.0);
    opts.travel_mm = Some([0.0, 1.0]);
    assert!(matches!(
        compensate_thermal_offset::run(&opts, &mut Silent),
        Err(Error::Usage(m)) if m == "--travel-mm is read by --format sinumerik-sd only; --format g10 does not use it: leave it out"
    ));
    opts.travel_mm = None;
    opts.out = Some(temps.clone());
    assert!(matches!(
        compensate_thermal_offset::run(&opts, &mut Silent),
        Err(Error::Usage(_))
    ));
    assert_eq!(
        std::fs::read_to_string(&temps).unwrap(),
        "time_min,t1_c\n0,19\n60,27\n"
    );
}
