//! Independent references: cases worked by hand, and NumPy's least squares on the same matrix.

use crate::support;

use mtec_identify::lines::{identify, LineData};
use mtec_io::Table;
use mtec_model::{ErrorElement, Machine};
use std::path::Path;

fn data(csv: &str) -> LineData {
    LineData::from_table(&Table::parse(Path::new("hand.csv"), csv).unwrap()).unwrap()
}

/// Readings of X lines worked by hand for the XYFZ machine (tool length L = 100 mm).
///
/// X carries the workpiece, so the tool sees the table's errors reversed. With the angular
/// errors acting about the carriage reference point (the machine zero, carried along), the
/// lever from it to the tool tip is (x, y, z + L), and the x-reading of a displacement laser is
///   Ex(x) = −EXX(x) − (z + L)·EBX(x) + y·ECX(x).
/// Truth: EXX = 10 µm·s, EBX = 20 µrad·s, ECX = 0, s = x/600.
/// Line A at y = 200, z = 50: reading = −(10 + 20·150/1000)·s = −13·s µm.
/// Line B at y = 200, z = 250: reading = −(10 + 20·350/1000)·s = −17·s µm.
fn hand_lines(with_b: bool) -> String {
    let mut csv = String::from("line,step,x_mm,y_mm,z_mm,ux,uy,uz,reading_um\n");
    for (name, z, per_s) in [("A", 50.0, -13.0), ("B", 250.0, -17.0)] {
        if name == "B" && !with_b {
            continue;
        }
        for k in 0..=6 {
            let x = 100.0 * k as f64;
            csv += &format!("{name},{k},{x},200,{z},1,0,0,{}\n", per_s * x / 600.0);
        }
    }
    csv
}

#[test]
fn one_x_line_gives_positioning_plus_abbe_pitch_and_names_what_it_cannot_separate() {
    let m = Machine::vmc_xyfz(100.0);
    let id = identify(&m, &data(&hand_lines(false)), 2).unwrap();
    let exx = ErrorElement::parse("EXX").unwrap();
    // one line cannot separate the pitch from the positioning: EXX absorbs the Abbe term
    let (v, _) = id.value_sigma(&exx, 600.0).unwrap();
    assert!(
        (v - 13.0).abs() < 1e-9,
        "EXX(600) = {v}, by hand 10 + 20·0.15 = 13"
    );
    let (v, _) = id.value_sigma(&exx, 300.0).unwrap();
    assert!((v - 6.5).abs() < 1e-9);
    // EBX (lever z + L), ECX (lever y) and EXX all read as functions of x alone on this line:
    // EBX goes first (angular), confounded with both; then ECX with EXX
    let find = |lost: &str| {
        id.report
            .unidentifiable
            .iter()
            .find(|u| u.element == lost)
            .unwrap_or_else(|| panic!("{lost} must be reported"))
            .confounded_with
            .clone()
    };
    assert_eq!(find("EBX"), ["EXX", "ECX"]);
    assert_eq!(find("ECX"), ["EXX"]);
    // elements this reading direction cannot see at all are named, not given numbers
    let eyx = ErrorElement::parse("EYX").unwrap();
    assert!(id.value_sigma(&eyx, 300.0).is_none());
    assert!(id.errors.unidentifiable.contains(&"EYX".to_string()));
}

#[test]
fn two_x_lines_at_two_heights_separate_pitch_from_positioning() {
    let m = Machine::vmc_xyfz(100.0);
    let id = identify(&m, &data(&hand_lines(true)), 2).unwrap();
    let at = |n: &str, q: f64| {
        id.value_sigma(&ErrorElement::parse(n).unwrap(), q)
            .unwrap()
            .0
    };
    // (B − A) = −200 mm · EBX → EBX(600) = 4 µm / 200 mm = 20 µrad; EXX = 13 − 3 = 10 µm
    assert!((at("EBX", 600.0) - 20.0).abs() < 1e-9);
    assert!((at("EXX", 600.0) - 10.0).abs() < 1e-9);
    assert!((at("EBX", 150.0) - 5.0).abs() < 1e-9);
    // the yaw needs a line at another y: still confounded with positioning
    let ecx = id
        .report
        .unidentifiable
        .iter()
        .find(|u| u.element == "ECX")
        .expect("ECX lost");
    assert!(ecx.confounded_with.contains(&"EXX".to_string()));
    assert!(id.report.residual_rms_um < 1e-9);
}

/// The small design of three X lines (9 channels) from the `vmc-9line` data: the identifiable
/// columns, the readings and NumPy's answer (`fixtures/lines_lstsq.py`, numpy.linalg.lstsq and
/// σ̂²(AᵀA)⁻¹) are checked in. Our R-SVD solution must agree.
#[test]
fn least_squares_agrees_with_numpy_lstsq() {
    let fx: serde_json::Value =
        serde_json::from_str(include_str!("fixtures/lines_lstsq_numpy.json")).unwrap();
    let (a, y) = three_x_line_design();
    let exported: serde_json::Value =
        serde_json::from_str(include_str!("fixtures/lines_lstsq_input.json")).unwrap();
    let ea = exported["a"].as_array().unwrap();
    assert_eq!(ea.len(), a.nrows(), "fixture matches this design");
    for (i, row) in ea.iter().enumerate() {
        for (j, v) in row.as_array().unwrap().iter().enumerate() {
            assert!((v.as_f64().unwrap() - a[(i, j)]).abs() <= 1e-12 * (1.0 + a[(i, j)].abs()));
        }
    }
    let theta = fx["theta"].as_array().unwrap();
    let se = fx["std_err"].as_array().unwrap();
    let (ours, ours_se) = solve_kept(&a, &y);
    assert_eq!(theta.len(), ours.len());
    for j in 0..ours.len() {
        let t = theta[j].as_f64().unwrap();
        assert!(
            (t - ours[j]).abs() <= 1e-8 * (1.0 + t.abs()),
            "θ[{j}]: numpy {t}, ours {}",
            ours[j]
        );
        let s = se[j].as_f64().unwrap();
        assert!(
            (s - ours_se[j]).abs() <= 1e-8 * (1.0 + s.abs()),
            "σ[{j}]: numpy {s}, ours {}",
            ours_se[j]
        );
    }
    assert!((fx["rank"].as_u64().unwrap() as usize) == ours.len());
}

/// Lines X1, X2, X3 (run 1) of `vmc-9line` seed 1.
fn three_x_lines() -> (Machine, LineData) {
    let (m, mut d, _) = support::vmc_9line(1);
    d.channels
        .retain(|c| ["X1", "X2", "X3"].contains(&c.line.as_str()) && c.run == 1);
    (m, d)
}

/// Kept design columns (in layout order) and readings of X1, X2, X3 of `vmc-9line` seed 1.
fn three_x_line_design() -> (nalgebra::DMatrix<f64>, nalgebra::DVector<f64>) {
    let (m, d) = three_x_lines();
    let layout = mtec_identify::lines::Layout::new(&m, 3, &d).unwrap();
    let (a, y) = mtec_identify::lines::model::design_matrix(&m, &layout, &d);
    let an = mtec_identify::lines::identifiability::analyse(&a, &y, &layout).unwrap();
    (a.select_columns(an.active.iter()), y)
}

/// Our solver on a full-rank matrix: θ and its standard errors.
fn solve_kept(a: &nalgebra::DMatrix<f64>, y: &nalgebra::DVector<f64>) -> (Vec<f64>, Vec<f64>) {
    // a layout-free analysis: the matrix is full rank, so no element is dropped
    let m = Machine::vmc_xyfz(100.0);
    let empty = LineData {
        source: String::new(),
        path: None,
        point_column: 0,
        channels: vec![],
    };
    let mut layout = mtec_identify::lines::Layout::new(&m, 3, &empty).unwrap();
    layout.blocks.clear();
    layout.n_cols = a.ncols();
    let an = mtec_identify::lines::identifiability::analyse(a, y, &layout).unwrap();
    assert!(an.dropped.is_empty());
    let fit = mtec_identify::lines::solve::solve(a, y, &an);
    let se = (0..a.ncols()).map(|j| fit.cov[(j, j)].sqrt()).collect();
    (fit.theta.iter().copied().collect(), se)
}

/// Writes the fixture input (run once: `cargo test -p mtec-identify --test integration lines_reference:: -- --ignored`),
/// then `python3 tests/fixtures/lines_lstsq.py` writes the NumPy answer.
#[test]
#[ignore]
fn export_lstsq_fixture_input() {
    let (a, y) = three_x_line_design();
    let rows: Vec<Vec<f64>> = (0..a.nrows())
        .map(|i| a.row(i).iter().copied().collect())
        .collect();
    // kind of each row (0 displacement, 1 straightness): the weighted path's groups
    let (_, d) = three_x_lines();
    let kinds: Vec<u8> = d
        .channels
        .iter()
        .flat_map(|c| {
            let k = (c.kind == mtec_identify::lines::ChannelKind::Straightness) as u8;
            std::iter::repeat_n(k, c.readings_um.len())
        })
        .collect();
    let v = serde_json::json!({ "a": rows, "y": y.iter().copied().collect::<Vec<f64>>(), "kind": kinds });
    std::fs::write(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/lines_lstsq_input.json"
        ),
        serde_json::to_string(&v).unwrap(),
    )
    .unwrap();
}

/// The weighted path of `identify` (issue 19): ordinary least squares, a variance per kind of
/// optics from its residuals (RSS_k over its share n_k·(m − k)/m of the degrees of freedom), rows
/// weighted by 1/σ_kind, weighted least squares. NumPy's answer on the same matrix (the fixture,
/// `fixtures/lines_lstsq.py`) must agree with `identify`'s θ and standard errors.
#[test]
fn weighted_least_squares_agrees_with_numpy() {
    let fx: serde_json::Value =
        serde_json::from_str(include_str!("fixtures/lines_lstsq_numpy.json")).unwrap();
    let w = &fx["weighted"];
    let (m, d) = three_x_lines();
    let id = identify(&m, &d, 3).unwrap();
    let theta = w["theta"].as_array().unwrap();
    let se = w["std_err"].as_array().unwrap();
    assert_eq!(theta.len(), id.analysis.active.len());
    for (j, &c) in id.analysis.active.iter().enumerate() {
        let t = theta[j].as_f64().unwrap();
        let ours = id.fit.theta[c];
        assert!(
            (t - ours).abs() <= 1e-8 * (1.0 + t.abs()),
            "θ[{j}]: numpy {t}, ours {ours}"
        );
        let s = se[j].as_f64().unwrap();
        let ours_se = id.fit.cov[(j, j)].sqrt();
        assert!(
            (s - ours_se).abs() <= 1e-8 * (1.0 + s.abs()),
            "σ[{j}]: numpy {s}, ours {ours_se}"
        );
    }
}

/// The design uses the Jacobian as an affine function of the pose (exact for X, Y, Z chains):
/// it must equal the direct first-order Jacobian of mtec-model everywhere.
#[test]
fn affine_jacobian_equals_the_direct_one() {
    use mtec_identify::lines::model::{direct_jacobian, AffineJacobian};
    let m = Machine::vmc_xyfz(100.0);
    let layout = mtec_identify::lines::Layout::new(&m, 3, &data(&hand_lines(false))).unwrap();
    let aff = AffineJacobian::new(&m, &layout);
    for q in [
        [0.0, 0.0, 0.0],
        [600.0, 800.0, 300.0],
        [123.4, 567.8, 91.0],
        [590.0, 10.0, 290.0],
    ] {
        let a = aff.at(&q);
        let d = direct_jacobian(&m, &layout, &q);
        for (x, y) in a.iter().zip(&d) {
            for k in 0..3 {
                assert!(
                    (x[k] - y[k]).abs() < 1e-9 * (1.0 + y[k].abs()),
                    "{q:?}: {x:?} vs {y:?}"
                );
            }
        }
    }
}
