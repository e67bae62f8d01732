//! `ops::machine` in-process on the hand-written thermal model of the CLI's tests
//! (`crates/mtec-cli/tests/data/thermal_offset/linear.json`: e = 12·t1 − 228 µm along its axis):
//! the envelope against the ranges of the training rows read by hand, the machine file written,
//! the replay's RMS before and after against the model evaluated by hand, the `--json` document,
//! and bad input located.

use mtec_comp::machine::MachineFile;
use mtec_workflow::ops::machine::{self, BuildOptions, Part, ReplayOptions};
use mtec_workflow::{Error, Silent};
use std::path::{Path, PathBuf};

/// `linear.json` copied into `dir`, and a training log whose t1 spans [18, 26] °C and whose air
/// spans [19.5, 23] °C.
fn inputs(dir: &Path) -> (PathBuf, PathBuf) {
    let model = dir.join("linear.json");
    std::fs::copy(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../mtec-cli/tests/data/thermal_offset/linear.json"),
        &model,
    )
    .unwrap();
    let data = dir.join("train.csv");
    std::fs::write(
        &data,
        "time_min,t1_c,air_c\n0,19,20\n10,18,19.5\n20,26,23\n30,22,21\n",
    )
    .unwrap();
    (model, data)
}

#[test]
fn build_takes_the_envelope_from_the_training_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (model, data) = inputs(dir.path());
    let out = dir.path().join("sub").join("machine.json");
    let mut opts = BuildOptions::new(
        None,
        vec![Part::parse("Z=linear.json,sign=-1").unwrap()],
        &out,
    );
    opts.thermal[0].model = model;
    opts.data = Some(data);
    opts.guard = vec!["air_c".into()];
    let o = machine::build(&opts, &mut Silent).unwrap();
    let p = &o.file.thermal[0];
    assert_eq!((p.axis.as_str(), p.sign), ("z", -1.0));
    assert_eq!(p.model, "../linear.json", "relative to the machine file");
    assert_eq!(p.envelope["t1_c"], [18.0, 26.0]);
    assert_eq!(p.envelope["air_c"], [19.5, 23.0]);
    let written: MachineFile =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(written, o.file);
    assert_eq!(
        o.to_string(),
        format!(
            "thermal z (sign -1): ../linear.json; envelope air_c [19.5, 23], t1_c [18, 26]\nwrote {}\n",
            out.display()
        )
    );

    // nothing to build, a guard without a thermal part, a bad --thermal
    let none = BuildOptions::new(None, vec![], &out);
    assert!(matches!(
        machine::build(&none, &mut Silent),
        Err(Error::Usage(_))
    ));
    assert!(matches!(Part::parse("w=m.json"), Err(Error::Usage(m)) if m.contains("x, y or z")));
    assert!(matches!(
        Part::parse("z=m.json,sign=2"),
        Err(Error::Usage(_))
    ));
}

#[test]
fn replay_compensates_each_reading_with_the_state_up_to_its_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (model, data) = inputs(d);
    let built = d.join("machine.json");
    let mut opts = BuildOptions::new(None, vec![Part::parse("z=linear.json").unwrap()], &built);
    opts.thermal[0].model = model;
    opts.data = Some(data);
    machine::build(&opts, &mut Silent).unwrap();

    // t1 = 19, 20, 21 °C at 0, 10, 20 min: the model's drift 0, 12, 24 µm; the probes measured
    // 12 µm at 10 min and 30 µm at 20 min, so after compensation 0 and 6 µm
    let state = d.join("state.csv");
    std::fs::write(&state, "time_min,t1_c\n0,19\n10,20\n20,21\n").unwrap();
    let probes = d.join("probes.csv");
    std::fs::write(
        &probes,
        "time_min,probe,x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n10,a,0,0,0,2,0,12\n20,a,0,0,0,-2,0,30\n",
    )
    .unwrap();
    let csv = d.join("replay.csv");
    let ropts = ReplayOptions {
        model: built.clone(),
        state: state.clone(),
        probes: probes.clone(),
        output: Some(csv.clone()),
    };
    let o = machine::replay(&ropts, &mut Silent).unwrap();
    let s = &o.summary;
    assert_eq!((s.readings, s.state_rows), (2, 3));
    assert!((s.z.rms_before_um - ((144.0_f64 + 900.0) / 2.0).sqrt()).abs() < 1e-9);
    assert!((s.z.rms_after_um - 18.0_f64.sqrt()).abs() < 1e-9, "{s:?}");
    assert!((s.z.max_after_um - 6.0).abs() < 1e-9);
    assert_eq!(s.x.rms_before_um, 2.0);
    assert_eq!(s.x.rms_after_um, 2.0);
    assert_eq!(o.state_inputs, ["t1_c"]);
    // the command's --json: the summary and three keys, no more
    let mut doc = serde_json::to_value(&o.summary).unwrap();
    doc["format"] = "mtec.machine-replay/1".into();
    doc["model"] = o.model.clone().into();
    doc["state_inputs"] = serde_json::json!(["t1_c"]);
    assert_eq!(serde_json::to_value(&o).unwrap(), doc);
    // every reading written, after = before + correction
    let rows = std::fs::read_to_string(&csv).unwrap();
    let data: Vec<&str> = rows.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(data.len(), 3);
    let header: Vec<&str> = data[0].split(',').collect();
    let ez_after = header.iter().position(|h| *h == "ez_after_um").unwrap();
    let after: Vec<f64> = data[1..]
        .iter()
        .map(|l| l.split(',').nth(ez_after).unwrap().parse().unwrap())
        .collect();
    assert!(
        (after[0]).abs() < 1e-9 && (after[1] - 6.0).abs() < 1e-9,
        "{after:?}"
    );
    assert!(o
        .to_string()
        .ends_with(&format!("wrote {}\n", csv.display())));

    // a state reading that is not a number, located; the output over an input refused
    std::fs::write(&state, "time_min,t1_c\n0,19\n10,warm\n").unwrap();
    match machine::replay(&ropts, &mut Silent) {
        Err(Error::Input(i)) => assert_eq!((i.line, i.column), (Some(3), Some(2)), "{i}"),
        other => panic!("{other:?}"),
    }
    let over = ReplayOptions {
        output: Some(probes.clone()),
        ..ropts
    };
    assert!(matches!(
        machine::replay(&over, &mut Silent),
        Err(Error::Usage(_))
    ));
}
