//! `ops::volumetric` in-process: a workpiece-carried X axis with a positioning error
//! EXX(x) = 1 + 0.01·x µm and a squareness EC0Y = 14 µrad moves the tool tip relative to the
//! workpiece by Ex = −(EXX(x) + EC0Y·y) (hand calculation: the table carries the workpiece the
//! other way; y in mm × µrad = 10⁻³ µm), in every form; the CSV and JSON the CLI prints; a point
//! outside the travel located.

use mtec_workflow::ops::volumetric::{self, Form, Options};
use mtec_workflow::{Error, Silent};
use std::path::{Path, PathBuf};

const MACHINE: &str =
    "chain = \"WXYFZT\"\ntool_offset_mm = [0, 0, 100]\n[axes.X]\ntravel = [0, 600]\n\
                       [axes.Y]\ntravel = [0, 800]\n[axes.Z]\ntravel = [0, 300]\n";
const ERRORS: &str = r#"{"format": "mtec.errors/1", "elements": {
  "EXX": {"type": "polynomial", "coeffs": [1, 0.01]}, "EC0Y": {"type": "constant", "value": 14}}}"#;

fn files(dir: &Path, points: &str) -> Options {
    let w = |n: &str, t: &str| -> PathBuf {
        let p = dir.join(n);
        std::fs::write(&p, t).unwrap();
        p
    };
    Options::new(
        w("m.toml", MACHINE),
        w("e.json", ERRORS),
        w("pts.csv", points),
    )
}

#[test]
fn the_error_is_the_hand_calculated_positioning_and_squareness_error_in_every_form() {
    let dir = tempfile::tempdir().unwrap();
    let pts = [[100.0, 200.0, 50.0], [0.0, 0.0, 0.0], [600.0, 800.0, 300.0]];
    let mut csv = String::from("x_mm,y_mm,z_mm\n");
    for q in &pts {
        csv.push_str(&format!("{},{},{}\n", q[0], q[1], q[2]));
    }
    let mut opts = files(dir.path(), &csv);
    for form in [
        Form::HtmExact,
        Form::HtmFirst,
        Form::PoeExact,
        Form::PoeFirst,
    ] {
        opts.form = form;
        let o = volumetric::run(&opts, &mut Silent).unwrap();
        assert_eq!(o.points.len(), pts.len());
        for (p, q) in o.points.iter().zip(&pts) {
            let ex = -((1.0 + 0.01 * q[0]) + 14e-3 * q[1]);
            // the exact forms differ from the first-order one by second-order terms, at most
            // y·θ²/2 = 800 mm · (14 µrad)² / 2 = 7.8e-5 µm here
            assert!(
                (p.ex_um - ex).abs() < 1e-4,
                "{form:?} {q:?}: {} vs {ex}",
                p.ex_um
            );
            assert!(
                p.ey_um.abs() < 1e-4 && p.ez_um.abs() < 1e-4,
                "{form:?} {p:?}"
            );
            assert!(p.orientation_urad.is_none());
        }
    }
    // the text and JSON `mtec volumetric` prints
    opts.form = Form::HtmExact;
    let o = volumetric::run(&opts, &mut Silent).unwrap();
    assert_eq!(
        o.to_string(),
        "x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n100,200,50,-4.8000,-0.0000,0.0000\n\
         0,0,0,-1.0000,0.0000,0.0000\n600,800,300,-18.2000,-0.0001,0.0000\n"
    );
    let v = serde_json::to_value(&o).unwrap();
    assert_eq!(v["format"], "mtec.volumetric/1");
    assert_eq!(v["form"], "HtmExact");
    assert_eq!(v["points"][0]["y_mm"], 200.0);
    assert_eq!(
        v["points"][0]
            .as_object()
            .unwrap()
            .keys()
            .collect::<Vec<_>>(),
        ["ex_um", "ey_um", "ez_um", "x_mm", "y_mm", "z_mm"]
    );
}

#[test]
fn a_rotary_chain_gives_the_orientation_error_in_the_axis_order_of_the_machine() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("rot.toml");
    std::fs::write(
        &m,
        "chain = \"WAYFXZT\"\ntool_offset_mm = [0, 0, 100]\n[axes.X]\ntravel = [-400, 400]\n\
         [axes.Y]\ntravel = [-300, 300]\n[axes.Z]\ntravel = [-400, 100]\n[axes.A]\n\
         travel = [-360, 360]\ncentre_mm = [0, 0, -80]\n",
    )
    .unwrap();
    let e = dir.path().join("e.json");
    // a constant roll of the A axis about its own axis (EAA = 10 µrad): the orientation error
    // is 10 µrad about X at every pose, and the tip, 180 mm above the A axis (tool offset 100 mm,
    // axis centre at z = -80 mm), moves by 10 µrad · 180 mm = 1.8 µm across it: along Y at
    // A = 0°, along Z at A = 90°
    std::fs::write(
        &e,
        r#"{"format": "mtec.errors/1", "elements": {"EAA": {"type": "constant", "value": 10}}}"#,
    )
    .unwrap();
    let p = dir.path().join("p.csv");
    std::fs::write(&p, "x_mm,y_mm,z_mm,a_deg\n0,0,0,0\n0,0,0,90\n").unwrap();
    let o = volumetric::run(&Options::new(&m, &e, &p), &mut Silent).unwrap();
    assert!(o.rotary);
    assert_eq!(o.columns, ["x_mm", "y_mm", "z_mm", "a_deg"]);
    for (p, dir) in o.points.iter().zip([[0.0, 1.8, 0.0], [0.0, 0.0, 1.8]]) {
        let r = p.orientation_urad.unwrap();
        assert!(
            (r[0].abs() - 10.0).abs() < 1e-9 && r[1].abs() < 1e-9 && r[2].abs() < 1e-9,
            "{r:?}"
        );
        // exact rotation: the tip also drops by 180 mm · θ²/2 = 9e-6 µm
        let e = [p.ex_um, p.ey_um, p.ez_um];
        for k in 0..3 {
            assert!((e[k].abs() - dir[k]).abs() < 1e-5, "{e:?}");
        }
    }
    assert_eq!(
        o.to_string(),
        "x_mm,y_mm,z_mm,a_deg,ex_um,ey_um,ez_um,eax_urad,eay_urad,eaz_urad\n\
         0,0,0,0,0.0000,1.8000,-0.0000,-10.000,0.000,0.000\n\
         0,0,0,90,0.0000,-0.0000,-1.8000,-10.000,0.000,0.000\n"
    );
}

#[test]
fn a_point_outside_the_travel_is_located() {
    let dir = tempfile::tempdir().unwrap();
    let opts = files(dir.path(), "x_mm,y_mm,z_mm\n100,200,50\n500,900,250\n");
    match volumetric::run(&opts, &mut Silent).unwrap_err() {
        Error::Input(i) => {
            assert_eq!((i.line, i.column), (Some(3), Some(2)));
            assert_eq!(i.file, opts.points);
            assert!(i
                .message
                .contains("y_mm = 900 is outside the travel [0, 800]"));
        }
        other => panic!("{other}"),
    }
}
