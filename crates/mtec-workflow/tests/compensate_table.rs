//! `ops::compensate_table` in-process on a map of a linear error field: the LinuxCNC trims
//! against the field evaluated by hand, the HEIDENHAIN pair of files, and a broken model file
//! located.

use mtec_comp::table::Axis;
use mtec_workflow::ops::compensate_table::{self, Format, Options, Range};
use mtec_workflow::ops::map;
use mtec_workflow::{Error, Silent};
use std::path::Path;

/// The measured error (um): linear, so the trilinear map reproduces it exactly.
fn field(x: f64, y: f64, z: f64) -> [f64; 3] {
    [3.0 + 0.02 * x + 0.01 * y - 0.005 * z, 0.5 - 0.004 * x, 0.0]
}

/// A 5×3×3 grid over X 0..200, Y 0..100, Z 0..100 mm, fitted into `dir/map.json`.
fn map_file(dir: &Path) -> std::path::PathBuf {
    let mut grid = String::from("x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n");
    for i in 0..5 {
        for j in 0..3 {
            for k in 0..3 {
                let (x, y, z) = (50.0 * i as f64, 50.0 * j as f64, 50.0 * k as f64);
                let e = field(x, y, z);
                grid.push_str(&format!("{x},{y},{z},{},{},{}\n", e[0], e[1], e[2]));
            }
        }
    }
    std::fs::write(dir.join("grid.csv"), grid).unwrap();
    let out = dir.join("map.json");
    map::fit(
        &map::FitOptions::trilinear(dir.join("grid.csv"), &out),
        &mut Silent,
    )
    .unwrap();
    out
}

#[test]
fn linuxcnc_trims_are_the_negated_field_on_the_maps_grid() {
    let dir = tempfile::tempdir().unwrap();
    let model = map_file(dir.path());
    let out = dir.path().join("x.comp");
    let o = compensate_table::run(
        &Options::new(&model, Format::Linuxcnc, Some(out.clone())),
        &mut Silent,
    )
    .unwrap();
    // default range: the map's X nodes; default --at: the grid box's centre (100, 50, 50), so
    // ex = 3 + 0.02 x + 0.5 - 0.25 = 3.25 + 0.02 x um, and the trim is -ex in mm
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        "0.000000 -0.003250 -0.003250\n\
         50.000000 -0.004250 -0.004250\n\
         100.000000 -0.005250 -0.005250\n\
         150.000000 -0.006250 -0.006250\n\
         200.000000 -0.007250 -0.007250\n"
    );
    assert_eq!(o.points, 5);
    assert_eq!(o.out.as_deref(), Some(out.as_path()));
    assert!(o.cma.is_none() && o.warnings.is_empty());
    assert_eq!(
        o.to_string(),
        format!("linuxcnc table from {}\n", o.provenance)
    );
    let json = serde_json::to_value(&o).unwrap();
    assert_eq!(json["format"], "linuxcnc");
    assert_eq!(json["points"], 5);

    // a range and a position of its own: 25 mm steps at Y 0, Z 100 (ex = 2.5 + 0.02 x)
    let mut opts = Options::new(&model, Format::Linuxcnc, Some(out.clone()));
    opts.range = Some(Range::parse("0:50:25").unwrap());
    opts.at = Some([0.0, 0.0, 100.0]);
    compensate_table::run(&opts, &mut Silent).unwrap();
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        "0.000000 -0.002500 -0.002500\n\
         25.000000 -0.003000 -0.003000\n\
         50.000000 -0.003500 -0.003500\n"
    );
}

#[test]
fn heidenhain_writes_the_table_and_its_assignment_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = map_file(dir.path());
    let com = dir.path().join("X.COM");
    let mut opts = Options::new(&model, Format::Heidenhain, Some(com.clone()));
    opts.axis = Axis::X;
    let o = compensate_table::run(&opts, &mut Silent).unwrap();
    let cma = dir.path().join("config.cma");
    assert_eq!(o.cma.as_deref(), Some(cma.as_path()));
    let com_text = std::fs::read_to_string(&com).unwrap();
    let cma_text = std::fs::read_to_string(&cma).unwrap();
    assert!(cma_text.contains("X.COM"), "{cma_text}");
    assert!(!com_text.is_empty());
    assert_eq!(
        o.to_string(),
        format!(
            "heidenhain: {} and {} from {}\n",
            com.display(),
            cma.display(),
            o.provenance
        )
    );
    // two files: not stdout
    opts.out = Some("-".into());
    assert!(matches!(
        compensate_table::run(&opts, &mut Silent),
        Err(Error::Usage(_))
    ));
}

#[test]
fn a_broken_model_is_located_and_an_output_over_the_model_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = map_file(dir.path());
    // the output is the model: refused before anything is written
    let before = std::fs::read(&model).unwrap();
    let e = compensate_table::run(
        &Options::new(&model, Format::Linuxcnc, Some(model.clone())),
        &mut Silent,
    )
    .unwrap_err();
    assert!(matches!(e, Error::Usage(_)), "{e:?}");
    assert_eq!(std::fs::read(&model).unwrap(), before);

    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        "{\n  \"format\": \"mtec.map/1\",\n  \"axes_mm\": [1,,2]\n}\n",
    )
    .unwrap();
    let e = compensate_table::run(&Options::new(&bad, Format::Linuxcnc, None), &mut Silent)
        .unwrap_err();
    match &e {
        Error::Input(i) => {
            assert_eq!(i.file, bad);
            assert_eq!(i.line, Some(3), "{i}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(e.exit_code(), 2);

    // a range that is not a whole number of steps (beckhoff's grid)
    let mut opts = Options::new(&model, Format::Beckhoff, Some(dir.path().join("b.csv")));
    opts.grid[0] = Some(Range::parse("0:100:30").unwrap());
    assert!(matches!(
        compensate_table::run(&opts, &mut Silent),
        Err(Error::Usage(_))
    ));
    assert!(!dir.path().join("b.csv").exists());
}
