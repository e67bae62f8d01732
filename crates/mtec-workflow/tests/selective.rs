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

/// The project report's "Selective compensation" section: a project with `[lines]` and
/// `[compensation] elements = "key"` compensates its program with the key elements only and
/// reports the ranking and the rates. The rate with the key elements is recomputed here by
/// another route: each command solved by fixed-point iteration p ← t − e(p) on the first-order
/// model of the key elements (not mtec-comp's solver), the machine's error being the exact
/// model of all of them, over the 4 × 4 × 4 grid of the travels.
#[test]
fn project_report_section_gives_the_key_elements_and_their_rates() {
    use mtec_model::{Formalism, Order, VolumetricModel};
    use mtec_workflow::project::{self, RunOptions};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for f in mtec_sim::run_scenario("vmc-9line", 1).unwrap().files {
        std::fs::write(d.join(&f.name), &f.contents).unwrap();
    }
    std::fs::write(
        d.join("p.ngc"),
        "G21 G90\nG0 X10 Y20 Z30\nG1 X590 Y780 Z290 F1000\nM2\n",
    )
    .unwrap();
    std::fs::write(
        d.join("project.toml"),
        "name = \"sel\"\nmachine = \"machine.toml\"\n[lines]\ndata = \"lines.csv\"\n\
         [compensation]\ngcode = [\"p.ngc\"]\nelements = \"key\"\n",
    )
    .unwrap();
    let res = d.join("res");
    let run = RunOptions {
        project: d.join("project.toml"),
        out: Some(res.clone()),
        title: None,
    };
    let done = project::run(&run, &mut Silent).unwrap();
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(res.join("selective.json")).unwrap())
            .unwrap();
    assert_eq!(saved["compensated"], "key");
    let key: Vec<String> = serde_json::from_value(saved["key"]["elements"].clone()).unwrap();
    let pct = |f: &str| -> [f64; 3] { serde_json::from_value(saved["key"][f].clone()).unwrap() };
    let (all_pct, key_pct, loss_pct) = (
        pct("rate_all_pct"),
        pct("rate_selected_pct"),
        pct("loss_pct"),
    );

    let km: mtec_comp::kinematic::KinematicFile =
        serde_json::from_str(&std::fs::read_to_string(res.join("kinematic-model.json")).unwrap())
            .unwrap();
    let machine = Machine::from_spec(km.machine.clone()).unwrap();
    let full = km.errors.clone();
    let mut part = full.clone();
    part.elements.retain(|e, _| key.contains(&e.name()));
    assert_eq!(part.elements.len(), key.len());
    assert!(key.len() < full.elements.len(), "{key:?}");
    let truth = VolumetricModel::new(&machine, &full);
    let rate_by_iteration = |compensated: &ErrorSet| -> [f64; 3] {
        let model = VolumetricModel::new(&machine, compensated);
        let grid = |a: usize| {
            let [lo, hi] = machine.travel(machine.axes[a]);
            (0..4).map(move |k| lo + (hi - lo) * k as f64 / 3.0)
        };
        let (mut before, mut after) = ([0.0; 3], [0.0; 3]);
        for x in grid(0) {
            for y in grid(1) {
                for z in grid(2) {
                    let t = [x, y, z];
                    let mut p = t;
                    for _ in 0..30 {
                        let e = model
                            .error(&p, Formalism::Htm, Order::FirstOrder)
                            .position_um;
                        p = [0, 1, 2].map(|i| t[i] - e[i] / 1000.0);
                    }
                    let e0 = truth.error(&t, Formalism::Htm, Order::Exact).position_um;
                    let e1 = truth.error(&p, Formalism::Htm, Order::Exact).position_um;
                    for i in 0..3 {
                        before[i] += e0[i] * e0[i];
                        after[i] += ((p[i] - t[i]) * 1e3 + e1[i]).powi(2);
                    }
                }
            }
        }
        [0, 1, 2].map(|i| 100.0 * (1.0 - (after[i] / before[i]).sqrt()))
    };
    let (all_i, key_i) = (rate_by_iteration(&full), rate_by_iteration(&part));
    let html = std::fs::read_to_string(&done.report).unwrap();
    assert!(html.contains("Selective compensation"));
    for i in 0..3 {
        println!(
            "axis {i}: all {:.2} / {:.2} %, key {:.2} / {:.2} %, loss {:.2}",
            all_pct[i], all_i[i], key_pct[i], key_i[i], loss_pct[i]
        );
        assert!((all_pct[i] - all_i[i]).abs() < 0.01, "axis {i}");
        assert!((key_pct[i] - key_i[i]).abs() < 0.01, "axis {i}");
        assert!(
            (loss_pct[i] - (all_i[i] - key_i[i])).abs() < 0.02,
            "axis {i}"
        );
        assert!(key_i[i] > 50.0, "axis {i}: {key_i:?}");
        assert!(
            html.contains(&format!("<td>{:.1} %</td>", key_pct[i])),
            "axis {i}"
        );
        assert!(
            html.contains(&format!("<td>{:.1}</td>", loss_pct[i])),
            "axis {i}"
        );
    }
    // leaving elements out costs something on one axis at least (X here: EXY, EXZ and EBY,
    // left out, move the tool tip along X only)
    assert!(loss_pct.iter().any(|l| *l > 1.0), "{loss_pct:?}");
    for e in &key {
        assert!(html.contains(&format!("<td>{e}</td>")), "{e}");
    }

    // the program is compensated with the key elements: as `compensate gcode --elements key`
    // of the same model file gives it, and not as with all elements
    let mut opts = Options::new(
        res.join("kinematic-model.json"),
        d.join("p.ngc"),
        d.join("key.ngc"),
    );
    opts.elements = Elements::Key;
    compensate_gcode::run(&opts, &mut Silent).unwrap();
    let project_ngc = std::fs::read(res.join("p-compensated.ngc")).unwrap();
    assert_eq!(project_ngc, std::fs::read(d.join("key.ngc")).unwrap());
    opts.elements = Elements::All;
    opts.output = d.join("all.ngc");
    compensate_gcode::run(&opts, &mut Silent).unwrap();
    assert_ne!(project_ngc, std::fs::read(d.join("all.ngc")).unwrap());
}

/// `[compensation] elements = "key"` in a project that compensates with its `[map]`: a map has
/// no elements, so the run fails with a usage error saying so (not the key silently ignored).
#[test]
fn project_elements_with_a_map_is_refused() {
    use mtec_workflow::project::{self, RunOptions};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for sc in ["vmc-9line", "volumetric-grid"] {
        for f in mtec_sim::run_scenario(sc, 1).unwrap().files {
            std::fs::write(d.join(&f.name), &f.contents).unwrap();
        }
    }
    std::fs::write(d.join("p.ngc"), "G21 G90\nG0 X10 Y20 Z30\nM2\n").unwrap();
    std::fs::write(
        d.join("project.toml"),
        "machine = \"machine.toml\"\n[lines]\ndata = \"lines.csv\"\n[map]\ngrid = \"grid.csv\"\n\
         [compensation]\ngcode = [\"p.ngc\"]\nelements = \"key\"\n",
    )
    .unwrap();
    let run = RunOptions {
        project: d.join("project.toml"),
        out: Some(d.join("res")),
        title: None,
    };
    let e = project::run(&run, &mut Silent).unwrap_err();
    assert!(matches!(e, mtec_workflow::Error::Usage(_)), "{e:?}");
    assert!(e.to_string().contains("[map] stage's map"), "{e}");
    assert!(!d.join("res/p-compensated.ngc").exists());
}
