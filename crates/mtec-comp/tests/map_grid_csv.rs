//! Grid CSV validation: every defect is reported with its line and column.

use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_io::{InputError, Table};
use std::path::Path;

fn read(text: &str, limits: GridLimits) -> Result<GridMap, InputError> {
    let t = Table::parse(Path::new("grid.csv"), text)?;
    GridMap::from_table(&t, &limits, Outside::Clamp)
}

const HEADER: &str = "x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n";

/// A 3×2×2 grid, rows in a scrambled order.
fn good_rows() -> Vec<String> {
    let mut rows = Vec::new();
    for z in [0.0, 10.0] {
        for x in [20.0, 0.0, 10.0] {
            for y in [5.0, 0.0] {
                rows.push(format!("{x},{y},{z},{},{},{}", x + y + z, x - y, z));
            }
        }
    }
    rows
}

fn text(rows: &[String]) -> String {
    format!("{HEADER}{}\n", rows.join("\n"))
}

#[test]
fn scrambled_complete_grid_is_sorted() {
    let m = read(&text(&good_rows()), GridLimits::default()).unwrap();
    assert_eq!(m.axes_mm()[0], vec![0.0, 10.0, 20.0]);
    assert_eq!(m.axes_mm()[1], vec![0.0, 5.0]);
    assert_eq!(m.node_um(2, 1, 1), [35.0, 15.0, 10.0]);
}

#[test]
fn duplicate_node_names_both_lines() {
    let mut rows = good_rows();
    let dup = rows[3].clone();
    rows.push(dup);
    let e = read(&text(&rows), GridLimits::default()).unwrap_err();
    assert_eq!((e.line, e.column), (Some(14), Some(1)), "{e}");
    assert!(
        e.message.contains("appears twice") && e.message.contains("line 5"),
        "{e}"
    );
}

#[test]
fn missing_node_is_named() {
    let mut rows = good_rows();
    rows.remove(0); // (20, 5, 0)
    let e = read(&text(&rows), GridLimits::default()).unwrap_err();
    // x = 20 now appears in 3 rows instead of 4: not regular, reported at its first row
    assert!(e.message.contains("not a regular grid"), "{e}");
    assert_eq!(e.column, Some(1));
}

#[test]
fn stray_value_is_located() {
    let mut rows = good_rows();
    rows[5] = rows[5].replace("0,0,", "0,0.5,"); // line 7: y = 0.5 instead of 0
    let e = read(&text(&rows), GridLimits::default()).unwrap_err();
    assert_eq!(e.line, Some(7), "{e}");
    assert_eq!(e.column, Some(2), "{e}");
}

#[test]
fn non_number_is_located() {
    let mut rows = good_rows();
    rows[2] = rows[2].replacen(",", ",abc,", 1).replacen(",5,", ",", 1);
    let t = text(&rows);
    let e = read(&t, GridLimits::default()).unwrap_err();
    assert_eq!(e.line, Some(4), "{e}");
}

#[test]
fn controller_limits() {
    let lim = GridLimits {
        max_points_per_axis: Some(2),
        require_uniform: false,
    };
    let e = read(&text(&good_rows()), lim).unwrap_err();
    assert!(e.message.contains("at most 2 points per axis"), "{e}");
    // unequal spacing refused when the controller needs it
    let rows: Vec<String> = good_rows()
        .iter()
        .map(|r| r.replacen("20,", "25,", 1))
        .collect();
    let e = read(
        &text(&rows),
        GridLimits::for_controller("fanuc-3d").unwrap(),
    )
    .unwrap_err();
    assert!(e.message.contains("equally spaced"), "{e}");
    read(&text(&rows), GridLimits::default()).unwrap();
}

#[test]
fn wrong_unit_suffix_is_reported() {
    let t = "x_mm,y_mm,z_mm,ex_mm,ey_um,ez_um\n0,0,0,0,0,0\n";
    let e = read(t, GridLimits::default()).unwrap_err();
    assert!(e.message.contains("wrong unit suffix"), "{e}");
}
