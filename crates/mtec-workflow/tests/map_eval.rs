//! `ops::map::eval` streamed in chunks (issue 22): rows over several chunks come out in order,
//! each value written exactly as `{}` writes it; a point the model refuses is reported before a
//! later unreadable row of the same chunk, and an output file is left untouched on error.

use mtec_workflow::ops::map::{eval, EvalOptions};
use mtec_workflow::{Error, Silent};
use std::path::Path;

/// e = (1 + 2x + 3y + 4z, x·y/7, −z/3) on x ∈ {0, 10, 30}, y ∈ {0, 5}, z ∈ {−1, 1}: multilinear,
/// so trilinear interpolation reproduces it (to round-off) inside the box.
fn map_json(outside: &str) -> String {
    let (xs, ys, zs) = ([0.0, 10.0, 30.0], [0.0, 5.0], [-1.0, 1.0]);
    let mut e = [Vec::new(), Vec::new(), Vec::new()];
    for x in xs {
        for y in ys {
            for z in zs {
                e[0].push(1.0 + 2.0 * x + 3.0 * y + 4.0 * z);
                e[1].push(x * y / 7.0);
                e[2].push(-z / 3.0);
            }
        }
    }
    serde_json::json!({"format": "mtec.map/1", "model": "trilinear", "outside": outside,
        "x_mm": xs, "y_mm": ys, "z_mm": zs, "ex_um": e[0], "ey_um": e[1], "ez_um": e[2]})
    .to_string()
}

fn opts(dir: &Path, outside: &str, points: &str) -> EvalOptions {
    std::fs::write(dir.join("map.json"), map_json(outside)).unwrap();
    std::fs::write(dir.join("pts.csv"), points).unwrap();
    EvalOptions {
        model: dir.join("map.json"),
        points: dir.join("pts.csv"),
        out: Some(dir.join("out.csv")),
    }
}

#[test]
fn many_chunks_in_order_with_the_values_of_error_um() {
    let dir = tempfile::tempdir().unwrap();
    let n = 10_000; // more than two chunks
    let mut csv = String::from("# a comment\nid,x_mm,y_mm,z_mm\n");
    let mut pts = Vec::new();
    for i in 0..n {
        let p = [
            (i % 37) as f64 * 0.9,
            (i % 11) as f64 * 0.5 - 0.25,
            (i % 5) as f64 * 0.5 - 1.0,
        ];
        csv.push_str(&format!("{i}, {},{},{}\n", p[0], p[1], p[2]));
        pts.push(p);
    }
    let o = opts(dir.path(), "clamp", &csv);
    let outcome = eval(&o, &mut Silent).unwrap();
    assert_eq!(outcome.points, n);
    let map = mtec_comp::load_error_model(&o.model).unwrap();
    let mut want = String::from("x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n");
    for p in &pts {
        let e = map.error_um(*p);
        want.push_str(&format!(
            "{},{},{},{},{},{}\n",
            p[0], p[1], p[2], e[0], e[1], e[2]
        ));
    }
    assert_eq!(
        std::fs::read_to_string(dir.path().join("out.csv")).unwrap(),
        want
    );
}

#[test]
fn a_refused_point_is_reported_before_a_later_bad_row_and_the_output_is_untouched() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("out.csv"), "old\n").unwrap();
    let mut csv = String::from("x_mm,y_mm,z_mm\n");
    for _ in 0..5000 {
        csv.push_str("1,1,0\n");
    }
    // line 5002: outside the grid (refuse); line 5004: not a number
    csv.push_str("40,1,0\n1,1,0\n1,x,0\n");
    let e = eval(&opts(dir.path(), "refuse", &csv), &mut Silent).unwrap_err();
    let Error::Input(e) = e else { panic!("{e}") };
    assert_eq!((e.line, e.column), (Some(5002), Some(1)), "{e}");
    assert!(e.message.contains("no value at (40, 1, 0) mm"), "{e}");
    // the unreadable row alone: its own line and column
    let csv = csv.replace("40,1,0", "4,1,0");
    let e = eval(&opts(dir.path(), "refuse", &csv), &mut Silent).unwrap_err();
    let Error::Input(e) = e else { panic!("{e}") };
    assert_eq!((e.line, e.column), (Some(5004), Some(2)), "{e}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("out.csv")).unwrap(),
        "old\n"
    );
    let leftovers = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(leftovers, 3, "map.json, pts.csv, out.csv and nothing else");
}
