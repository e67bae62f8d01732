//! Selective compensation (issue 19, item 4) on the simulator: `identify lines` on the realistic
//! 9-line measurement, then `compensate gcode --elements key`. What the report estimates from
//! the model alone (the rate with the key elements, the loss) is checked against the rates the
//! simulator's truth gives when the machine is commanded from the identified set with all
//! elements and with the key ones only.

use mtec_model::{ErrorSet, Machine};
use mtec_workflow::ops::compensate_gcode::{self, Options};
use mtec_workflow::ops::identify_lines;
use mtec_workflow::ops::selective::{self, Elements};
use mtec_workflow::Silent;

#[test]
fn key_elements_rate_and_loss_agree_with_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = mtec_sim::run_scenario("vmc-9line-realistic", 2).unwrap();
    for f in &out.files {
        std::fs::write(d.join(&f.name), &f.contents).unwrap();
    }
    let truth: ErrorSet = serde_json::from_value(out.truth["errors"].clone()).unwrap();
    let mut id = identify_lines::Options::new(d.join("machine.toml"), d.join("lines.csv"));
    id.kinematic_model = Some(d.join("km.json"));
    let identified = identify_lines::run(&id, &mut Silent).unwrap().errors;
    std::fs::write(
        d.join("p.ngc"),
        "G21 G90\nG0 X10 Y20 Z30\nG1 X590 Y780 Z290 F1000\nM2\n",
    )
    .unwrap();

    let mut opts = Options::new(d.join("km.json"), d.join("p.ngc"), d.join("key.ngc"));
    opts.elements = Elements::Key;
    let o = compensate_gcode::run(&opts, &mut Silent).unwrap();
    let s = o.selective.expect("a selective report");
    println!("{s}");
    assert!(!s.left_out.is_empty() && s.elements.len() >= 3, "{s:?}");

    // the truth's rates, commanded from the identified set with all and with the key elements
    let spec: mtec_model::MachineSpec = mtec_io::read_toml(&d.join("machine.toml")).unwrap();
    let machine = Machine::from_spec(spec).unwrap();
    let mut key = identified.clone();
    key.elements.retain(|e, _| s.elements.contains(&e.name()));
    let all_t = selective::rate(&machine, &truth, &identified).unwrap();
    let key_t = selective::rate(&machine, &truth, &key).unwrap();
    for i in 0..3 {
        let loss_t = 100.0 * (all_t[i] - key_t[i]);
        println!(
            "axis {i}: truth: all {:.1} %, key {:.1} %, loss {loss_t:.1}; model: key {:.1} %, loss {:.1}",
            100.0 * all_t[i],
            100.0 * key_t[i],
            s.rate_selected_pct[i],
            s.loss_pct[i]
        );
        // the identified model compensates the truth (issue 19: ≥ 92 % on this seed's axes)
        assert!(all_t[i] > 0.92, "axis {i}: {all_t:?}");
        // the model's estimate of what leaving the other elements out costs holds on the truth
        // within 3 percentage points (the truth's own residual, 2–3 % here, adds to both)
        assert!(
            (loss_t - s.loss_pct[i]).abs() <= 3.0,
            "axis {i}: loss on the truth {loss_t:.2} vs estimated {:.2}",
            s.loss_pct[i]
        );
    }
    // and the list is the one EFAST ranks: the first-ranked element is among the key ones
    assert_eq!(s.elements[0], s.ranking[0].0);
}

#[test]
fn a_list_naming_an_element_the_model_lacks_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let machine = Machine::vmc_xyfz(100.0);
    let mut set = ErrorSet::new("test");
    set.insert(
        mtec_model::ErrorElement::parse("EXX").unwrap(),
        mtec_model::ErrorFunction::polynomial(vec![0.0, 0.01]),
    );
    let file = mtec_comp::kinematic::KinematicFile::new(&machine, &set).unwrap();
    std::fs::write(d.join("km.json"), file.to_json().unwrap()).unwrap();
    std::fs::write(d.join("p.ngc"), "G21 G90\nG0 X10 Y20 Z30\nM2\n").unwrap();
    let mut opts = Options::new(d.join("km.json"), d.join("p.ngc"), d.join("o.ngc"));
    opts.elements = "EXX,EYY".parse().unwrap();
    let e = compensate_gcode::run(&opts, &mut Silent).unwrap_err();
    assert!(matches!(e, mtec_workflow::Error::Usage(_)), "{e:?}");
    assert!(e.to_string().contains("no element `EYY`"), "{e}");
    assert!(!d.join("o.ngc").exists());
}

/// `sensitivity --sampling lhs:N`: N poses, each axis with exactly one pose in each of N equal
/// slices of its travel (the Latin hypercube property), indices aggregated over them; with
/// `--at` as well it is a usage error.
#[test]
fn lhs_poses_stratify_every_travel_and_feed_the_analysis() {
    use mtec_workflow::ops::sensitivity::{self, lhs_poses, Options, Outcome};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let machine = Machine::vmc_xyfz(100.0); // the travels of m.toml below
    let n = 10;
    let poses = lhs_poses(&machine, n, 3);
    for (i, a) in machine.axes.iter().enumerate() {
        let [lo, hi] = machine.travel(*a);
        let mut slices: Vec<usize> = poses
            .iter()
            .map(|p| ((p[i] - lo) / (hi - lo) * n as f64).floor() as usize)
            .collect();
        slices.sort_unstable();
        assert_eq!(slices, (0..n).collect::<Vec<_>>(), "axis {a:?}");
    }
    std::fs::write(
        d.join("m.toml"),
        "chain = \"WXYFZT\"\ntool_offset_mm = [0, 0, 100]\n[axes.X]\ntravel = [0, 600]\n\
         [axes.Y]\ntravel = [0, 800]\n[axes.Z]\ntravel = [0, 300]\n",
    )
    .unwrap();
    std::fs::write(
        d.join("s.csv"),
        "element,mean,std,unit\nEXX,1,2,um\nEYY,0,3,um\nECX,0,5,urad\n",
    )
    .unwrap();
    let mut opts = Options::machine(d.join("m.toml"), d.join("s.csv"));
    opts.lhs_poses = Some(n);
    let Outcome::Machine(o) = sensitivity::run(&opts, &mut Silent).unwrap() else {
        panic!("a machine's outcome")
    };
    assert_eq!(o.report.points, n);
    opts.at = Some(vec![1.0, 2.0, 3.0]);
    let e = sensitivity::run(&opts, &mut Silent).unwrap_err();
    assert!(e.to_string().contains("without --at"), "{e}");
}
