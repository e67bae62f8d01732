//! Bad line-measurement files are refused with the file, line and column of the problem.

use mtec_identify::lines::{identify, LineData, LinesError};
use mtec_io::Table;
use mtec_model::Machine;
use std::path::Path;

const HEADER: &str = "line,step,x_mm,y_mm,z_mm,ux,uy,uz,reading_um\n";

fn good_rows(name: &str) -> String {
    (0..=4)
        .map(|k| {
            format!(
                "{name},{k},{},10,10,1,0,0,{}\n",
                100 * k + 10,
                0.1 * k as f64
            )
        })
        .collect()
}

fn parse(text: &str) -> Result<LineData, String> {
    let t = Table::parse(Path::new("bad.csv"), text).map_err(|e| e.to_string())?;
    LineData::from_table(&t).map_err(|e| e.to_string())
}

#[test]
fn good_file_parses() {
    let d = parse(&format!("{HEADER}{}", good_rows("X1"))).unwrap();
    assert_eq!(d.channels.len(), 1);
    assert_eq!(d.channels[0].readings_um.len(), 5);
}

#[test]
fn missing_column_is_named() {
    let e = parse("line,step,x_mm,y_mm,z_mm,ux,uy,uz\nX1,0,0,0,0,1,0,0\n").unwrap_err();
    assert!(
        e.starts_with("bad.csv:1:") && e.contains("reading_um"),
        "{e}"
    );
}

#[test]
fn misnamed_column_is_named() {
    let e = parse("line,step,x_m,y_mm,z_mm,ux,uy,uz,reading_um\nX1,0,0,0,0,1,0,0,0\n").unwrap_err();
    assert!(
        e.starts_with("bad.csv:1:") && e.contains("missing column `x_mm`"),
        "{e}"
    );
}

#[test]
fn readings_and_positions_no_machine_has_are_located() {
    // a reading of a metre (nm written as um, raw counts) gave NaN everywhere and an empty
    // error file with exit 0; a position of 1e300 mm made the identification hang
    let rows = good_rows("X1").replacen(",0.2\n", ",1e6\n", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(
        e.starts_with("bad.csv:4:9:") && e.contains("implausible"),
        "{e}"
    );
    let rows = good_rows("X1").replacen("X1,3,310,", "X1,3,1e300,", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(
        e.starts_with("bad.csv:5:3:") && e.contains("`x_mm` is 1e300 mm: implausible"),
        "{e}"
    );
    // just inside the bounds: read
    let rows = good_rows("X1").replacen(",0.2\n", ",-999999\n", 1);
    assert!(parse(&format!("{HEADER}{rows}")).is_ok());
}

#[test]
fn nan_reading_is_located() {
    let mut rows = good_rows("X1");
    rows = rows.replacen(",0.2\n", ",NaN\n", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(
        e.starts_with("bad.csv:4:9:") && e.contains("not a finite number"),
        "{e}"
    );
}

#[test]
fn too_few_points_is_located() {
    let text = format!(
        "{HEADER}{}Y1,0,10,10,10,0,1,0,0\nY1,1,10,20,10,0,1,0,0.1\n",
        good_rows("X1")
    );
    let e = parse(&text).unwrap_err();
    assert!(
        e.starts_with("bad.csv:7:") && e.contains("`Y1` has 2 point(s)"),
        "{e}"
    );
}

#[test]
fn non_unit_direction_is_located() {
    let rows = good_rows("X1").replacen("10,10,1,0,0,0.1", "10,10,1,0.5,0,0.1", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(
        e.starts_with("bad.csv:3:6:") && e.contains("unit vector"),
        "{e}"
    );
}

#[test]
fn point_off_the_line_is_located() {
    let rows = good_rows("X1").replacen("210,10,10", "210,10.5,10", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(
        e.starts_with("bad.csv:4:3:") && e.contains("off the straight line"),
        "{e}"
    );
}

#[test]
fn direction_changing_within_a_channel_is_located() {
    let rows = good_rows("X1").replacen("310,10,10,1,0,0", "310,10,10,0,1,0", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(
        e.starts_with("bad.csv:5:6:") && e.contains("changes its reading direction"),
        "{e}"
    );
}

#[test]
fn duplicated_step_is_located() {
    let rows = good_rows("X1").replacen("X1,2,", "X1,1,", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(e.contains("bad.csv:") && e.contains("step 1 twice"), "{e}");
}

#[test]
fn non_integer_step_is_located() {
    let rows = good_rows("X1").replacen("X1,2,", "X1,2.5,", 1);
    let e = parse(&format!("{HEADER}{rows}")).unwrap_err();
    assert!(e.starts_with("bad.csv:4:2:"), "{e}");
}

#[test]
fn point_outside_the_travel_is_located() {
    // a straight line that runs beyond X's 600 mm travel at its third point
    let text =
        format!("{HEADER}X1,0,250,10,10,1,0,0,0\nX1,1,400,10,10,1,0,0,0\nX1,2,650,10,10,1,0,0,0\n");
    let d = parse(&text).unwrap();
    let err = identify(&Machine::vmc_xyfz(100.0), &d, 3).unwrap_err();
    match err {
        LinesError::Input(e) => {
            let s = e.to_string();
            assert!(
                s.starts_with("bad.csv:4:3:") && s.contains("outside the travel of axis X"),
                "{s}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn too_few_readings_for_the_degree_is_an_error_not_a_panic() {
    let d = parse(&format!("{HEADER}{}", good_rows("X1"))).unwrap();
    let e = identify(&Machine::vmc_xyfz(100.0), &d, 12).unwrap_err();
    assert!(matches!(e, LinesError::TooFewReadings { .. }), "{e:?}");
    let e = identify(&Machine::vmc_xyfz(100.0), &d, 1).unwrap_err();
    assert!(e.to_string().contains("degree"), "{e}");
}
