//! The trilinear map against SciPy's RegularGridInterpolator on the same grid and points
//! (fixture and generating script in tests/map_fixtures/, SciPy 1.17.1, NumPy 2.4.6).

use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_io::Table;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/map_fixtures")
        .join(name)
}

fn compare(outside: Outside, expected: &str) -> f64 {
    let map = GridMap::read_csv(&fixture("grid.csv"), &GridLimits::default(), outside).unwrap();
    let t = Table::read(&fixture(expected)).unwrap();
    let cols =
        ["x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um"].map(|c| t.f64_column(c).unwrap());
    let mut worst: f64 = 0.0;
    for r in (0..cols[0].len()).map(|i| cols.each_ref().map(|c| c[i])) {
        let e = map.try_error_um([r[0], r[1], r[2]]).unwrap();
        worst = e
            .iter()
            .zip(&r[3..])
            .fold(worst, |w, (a, b)| w.max((a - b).abs()));
    }
    worst
}

/// Tolerance 1e-9 µm: both compute the same multilinear interpolant in f64; only the order of
/// operations differs (observed difference ~1e-14 µm).
#[test]
fn matches_scipy_with_linear_extrapolation() {
    let worst = compare(Outside::Extrapolate, "scipy_extrapolate.csv");
    assert!(worst < 1e-9, "largest difference {worst} um");
}

#[test]
fn matches_scipy_on_clipped_points() {
    let worst = compare(Outside::Clamp, "scipy_clamp.csv");
    assert!(worst < 1e-9, "largest difference {worst} um");
}

/// With `refuse`, exactly the points SciPy had to extrapolate are refused.
#[test]
fn refuse_rejects_exactly_the_outside_points() {
    let map = GridMap::read_csv(
        &fixture("grid.csv"),
        &GridLimits::default(),
        Outside::Refuse,
    )
    .unwrap();
    let t = Table::read(&fixture("points.csv")).unwrap();
    let (x, y, z) = (
        t.f64_column("x_mm").unwrap(),
        t.f64_column("y_mm").unwrap(),
        t.f64_column("z_mm").unwrap(),
    );
    for i in 0..x.len() {
        let inside = (0.0..=500.0).contains(&x[i])
            && (-200.0..=300.0).contains(&y[i])
            && (-300.0..=0.0).contains(&z[i]);
        assert_eq!(
            map.try_error_um([x[i], y[i], z[i]]).is_ok(),
            inside,
            "point {i}"
        );
    }
}
