//! BPNN 3-10-3 on the virtual machine's `volumetric-grid` scenario (laser tracker, 11³ points,
//! σ = 0.3 µm): the source's fit-error band and the body-diagonal check against the truth, with
//! trilinear interpolation of the same grid (`mtec_comp::GridMap`) as the reference.

use mtec_comp::{ErrorModel, GridLimits, GridMap, Outside};
use mtec_io::Table;
use mtec_nn::{fit_grid, GridFitConfig};
use std::path::Path;

/// Fit within ±2 µm per axis at every grid point (the source: [−1.84, 2.05] µm); along the
/// four body diagonals PPP, NPP, NPN, PPN the BPNN's RMS error against the true (noise-free)
/// volumetric error is no worse than trilinear interpolation's + 1 µm, on every diagonal and
/// axis. Two seeds (two different machines).
#[test]
fn bpnn_fits_the_tracker_grid_and_predicts_the_diagonals() {
    for seed in [1u64, 4] {
        let out = mtec_sim::run_scenario("volumetric-grid", seed).unwrap();
        let file = |n: &str| &out.files.iter().find(|f| f.name == n).unwrap().contents;
        let grid = Table::parse(Path::new("grid.csv"), file("grid.csv")).unwrap();
        let col = |t: &Table, n: &str| t.f64_column(n).unwrap();
        let (x, y, z) = (col(&grid, "x_mm"), col(&grid, "y_mm"), col(&grid, "z_mm"));
        let (ex, ey, ez) = (
            col(&grid, "ex_um"),
            col(&grid, "ey_um"),
            col(&grid, "ez_um"),
        );
        assert_eq!(x.len(), 11 * 11 * 11);
        let p: Vec<[f64; 3]> = (0..x.len()).map(|i| [x[i], y[i], z[i]]).collect();
        let e: Vec<[f64; 3]> = (0..x.len()).map(|i| [ex[i], ey[i], ez[i]]).collect();

        let (net, report) = fit_grid(&p, &e, &GridFitConfig::default()).unwrap();
        assert_eq!(report.parameters, 73);
        assert_eq!(report.grid_values, 3993);
        for (axis, s) in [
            ("x", report.fit_error_x),
            ("y", report.fit_error_y),
            ("z", report.fit_error_z),
        ] {
            eprintln!(
                "seed {seed} e{axis}: fit error min {:.2} max {:.2} mean {:.3} std {:.3} um",
                s.min_um, s.max_um, s.mean_um, s.std_um
            );
            assert!(
                s.min_um >= -2.0 && s.max_um <= 2.0,
                "seed {seed} e{axis}: fit error [{:.2}, {:.2}] um outside ±2 um",
                s.min_um,
                s.max_um
            );
        }
        // the comparison is not empty: the grid spans far more than the fit band
        let span = e.iter().map(|v| v[0]).fold(f64::NEG_INFINITY, f64::max)
            - e.iter().map(|v| v[0]).fold(f64::INFINITY, f64::min);
        assert!(span > 8.0, "seed {seed}: ex spans only {span} um");

        let trilinear =
            GridMap::from_table(&grid, &GridLimits::default(), Outside::Refuse).unwrap();
        let d = Table::parse(Path::new("diagonals.csv"), file("diagonals.csv")).unwrap();
        let names = d.str_column("diagonal").unwrap();
        let (dx, dy, dz) = (col(&d, "x_mm"), col(&d, "y_mm"), col(&d, "z_mm"));
        let truth = [
            col(&d, "true_ex_um"),
            col(&d, "true_ey_um"),
            col(&d, "true_ez_um"),
        ];
        for diag in ["PPP", "NPP", "NPN", "PPN"] {
            let rows: Vec<usize> = (0..names.len()).filter(|&i| names[i] == diag).collect();
            assert_eq!(rows.len(), 51);
            let (mut sq_nn, mut sq_tri) = ([0.0; 3], [0.0; 3]);
            for &i in &rows {
                let q = [dx[i], dy[i], dz[i]];
                let (a, b) = (net.error_um(q), trilinear.error_um(q));
                for k in 0..3 {
                    sq_nn[k] += (a[k] - truth[k][i]).powi(2);
                    sq_tri[k] += (b[k] - truth[k][i]).powi(2);
                }
            }
            for k in 0..3 {
                let n = rows.len() as f64;
                let (rn, rt) = ((sq_nn[k] / n).sqrt(), (sq_tri[k] / n).sqrt());
                eprintln!(
                    "seed {seed} {diag} e{}: RMS vs truth BPNN {rn:.3} um, trilinear {rt:.3} um",
                    ["x", "y", "z"][k]
                );
                assert!(
                    rn <= rt + 1.0,
                    "seed {seed} {diag} axis {k}: BPNN {rn} vs trilinear {rt}"
                );
            }
        }
    }
}
