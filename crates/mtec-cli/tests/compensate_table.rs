//! `mtec compensate table` with a model that is not a grid: a BPNN fitted by
//! `mtec map fit --model bpnn` gives the same compensation values as `mtec map eval` of that
//! network at the table points (negated, in mm), and asks for a range it cannot take from a grid.

mod support;

use support::{mtec, text};

/// A smooth volumetric error over the 0..100 mm cube (µm): what the network learns.
fn field(x: f64, y: f64, z: f64) -> [f64; 3] {
    [
        -1.0 + 0.02 * x + 0.0001 * y * z,
        0.01 * y - 0.3 * (x / 50.0 - 1.0).powi(2),
        0.005 * z + 0.001 * x,
    ]
}

#[test]
fn bpnn_model_writes_a_linuxcnc_table_equal_to_its_predictions() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let mut grid = String::from("x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n");
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..5 {
                let (x, y, z) = (25.0 * i as f64, 25.0 * j as f64, 25.0 * k as f64);
                let e = field(x, y, z);
                grid.push_str(&format!("{x},{y},{z},{},{},{}\n", e[0], e[1], e[2]));
            }
        }
    }
    std::fs::write(p("grid.csv"), grid).unwrap();
    let o = mtec(&[
        "map",
        "fit",
        "--grid",
        &p("grid.csv"),
        "--model",
        "bpnn",
        "--hidden",
        "6",
        "-o",
        &p("bpnn.json"),
    ]);
    assert!(o.status.success(), "{}", text(&o));

    // without a grid there is no default range
    let o = mtec(&[
        "compensate",
        "table",
        "--model",
        &p("bpnn.json"),
        "--format",
        "linuxcnc",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("--range"), "{}", text(&o));

    let o = mtec(&[
        "compensate",
        "table",
        "--model",
        &p("bpnn.json"),
        "--format",
        "linuxcnc",
        "--axis",
        "X",
        "--range",
        "0:100:12.5",
        "--at",
        "0,40,60",
        "-o",
        &p("x.comp"),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table: Vec<[f64; 3]> = std::fs::read_to_string(p("x.comp"))
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|s| s.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(table.len(), 9);

    let mut points = String::from("x_mm,y_mm,z_mm\n");
    for r in &table {
        points.push_str(&format!("{},40,60\n", r[0]));
    }
    std::fs::write(p("points.csv"), points).unwrap();
    let o = mtec(&[
        "map",
        "eval",
        "--map",
        &p("bpnn.json"),
        "--points",
        &p("points.csv"),
        "-o",
        &p("eval.csv"),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let eval = std::fs::read_to_string(p("eval.csv")).unwrap();
    let mut lines = eval.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let ex = header.iter().position(|h| *h == "ex_um").unwrap();
    for (r, line) in table.iter().zip(lines) {
        let e: f64 = line.split(',').nth(ex).unwrap().parse().unwrap();
        // type 1 (offsets): trim = −error, in mm with 6 decimals; both directions equal
        assert!((r[1] + e * 1e-3).abs() < 1e-6, "{r:?} vs ex {e} um");
        assert_eq!(r[1], r[2]);
        // and the network is close to the field it was fitted on
        let want = field(r[0], 40.0, 60.0)[0];
        assert!((e - want).abs() < 0.1, "x {}: {e} vs {want}", r[0]);
    }
}
