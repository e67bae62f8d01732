//! BPNN volumetric-map fit on an 11 × 11 × 11 grid (the source's laser-tracker grid size).
//!
//! Until the `volumetric-grid` scenario of mtec-sim is available here, the grid comes from an
//! analytic, smooth volumetric error field of realistic magnitude (positioning ~14 µm over the
//! travel, squareness, quadratic straightness, a half-sine term) plus tracker noise σ = 0.3 µm.
//! Reference for the diagonal test: trilinear interpolation of the same noisy grid (written out
//! below as the textbook formula), against the noise-free field along the four body diagonals.

use mtec_nn::{fit_grid, Bpnn, GridFitConfig};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

const TRAVEL_MM: [f64; 3] = [600.0, 800.0, 300.0];
const N: usize = 11;

/// Noise-free volumetric error field [ex, ey, ez] in µm.
fn field_um(p: [f64; 3]) -> [f64; 3] {
    let (u, v, w) = (
        p[0] / TRAVEL_MM[0],
        p[1] / TRAVEL_MM[1],
        p[2] / TRAVEL_MM[2],
    );
    let pi = std::f64::consts::PI;
    [
        14.0 * u - 5.0 * u * u + 8.0 * v + 3.0 * u * w + 2.0 * (pi * v).sin(),
        10.0 * v + 4.0 * v * v - 6.0 * u + 2.5 * w * v + 1.5 * (pi * u).cos(),
        6.0 * w + 5.0 * u * u - 4.0 * u * v + 3.0 * v * v + (pi * w).sin(),
    ]
}

fn grid(seed: u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, 0.3).unwrap();
    let mut p = Vec::new();
    let mut e = Vec::new();
    for i in 0..N {
        for j in 0..N {
            for k in 0..N {
                let q = [
                    TRAVEL_MM[0] * i as f64 / (N - 1) as f64,
                    TRAVEL_MM[1] * j as f64 / (N - 1) as f64,
                    TRAVEL_MM[2] * k as f64 / (N - 1) as f64,
                ];
                let f = field_um(q);
                p.push(q);
                e.push([
                    f[0] + noise.sample(&mut rng),
                    f[1] + noise.sample(&mut rng),
                    f[2] + noise.sample(&mut rng),
                ]);
            }
        }
    }
    (p, e)
}

/// Trilinear interpolation in the regular grid (index order i, j, k as generated above):
/// f = Σ_{a,b,c∈{0,1}} f_{i+a, j+b, k+c} · (a ? s : 1−s)(b ? t : 1−t)(c ? r : 1−r).
fn trilinear(e: &[[f64; 3]], p: [f64; 3]) -> [f64; 3] {
    let mut idx = [0usize; 3];
    let mut frac = [0.0; 3];
    for a in 0..3 {
        let g = (p[a] / TRAVEL_MM[a] * (N - 1) as f64).clamp(0.0, (N - 1) as f64);
        idx[a] = (g.floor() as usize).min(N - 2);
        frac[a] = g - idx[a] as f64;
    }
    let mut out = [0.0; 3];
    for a in 0..2 {
        for b in 0..2 {
            for c in 0..2 {
                let wgt = (if a == 1 { frac[0] } else { 1.0 - frac[0] })
                    * (if b == 1 { frac[1] } else { 1.0 - frac[1] })
                    * (if c == 1 { frac[2] } else { 1.0 - frac[2] });
                let v = e[((idx[0] + a) * N + idx[1] + b) * N + idx[2] + c];
                for d in 0..3 {
                    out[d] += wgt * v[d];
                }
            }
        }
    }
    out
}

/// Points along a body diagonal; `dir` gives for each axis whether it runs up (+) or down (−)
/// (PPP: all up; NPP: X down, Y, Z up; NPN; PPN). 57 points: off the grid nodes.
fn diagonal(dir: [bool; 3]) -> Vec<[f64; 3]> {
    (0..57)
        .map(|s| {
            let f = s as f64 / 56.0;
            let mut q = [0.0; 3];
            for a in 0..3 {
                q[a] = TRAVEL_MM[a] * if dir[a] { f } else { 1.0 - f };
            }
            q
        })
        .collect()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

#[test]
fn trilinear_reference_reproduces_grid_nodes_and_linear_fields() {
    // A trilinear field is reproduced exactly by trilinear interpolation.
    let lin = |p: [f64; 3]| {
        [
            p[0] * 0.01 + p[1] * p[2] * 1e-5,
            p[1] * 0.02 - p[0] * p[1] * 1e-6,
            1.0,
        ]
    };
    let mut e = Vec::new();
    for i in 0..N {
        for j in 0..N {
            for k in 0..N {
                e.push(lin([
                    TRAVEL_MM[0] * i as f64 / 10.0,
                    TRAVEL_MM[1] * j as f64 / 10.0,
                    TRAVEL_MM[2] * k as f64 / 10.0,
                ]));
            }
        }
    }
    for q in diagonal([true, false, true]) {
        let (a, b) = (trilinear(&e, q), lin(q));
        for d in 0..3 {
            assert!((a[d] - b[d]).abs() < 1e-9);
        }
    }
}

#[test]
fn bpnn_3_10_3_fits_the_grid_within_2_um_and_predicts_the_diagonals() {
    let (p, e) = grid(11);
    let (net, report) = fit_grid(&p, &e, &GridFitConfig::default()).unwrap();
    eprintln!(
        "{}",
        serde_json::to_string_pretty(&report)
            .unwrap()
            .lines()
            .take(40)
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert_eq!(report.parameters, 73);
    assert_eq!(report.grid_values, 3993);
    for s in [report.fit_error_x, report.fit_error_y, report.fit_error_z] {
        assert!(
            s.min_um >= -2.0 && s.max_um <= 2.0,
            "fit error outside ±2 µm: {s:?}"
        );
        assert!(s.mean_um.abs() < 0.1, "{s:?}");
    }
    // the noise is 0.3 µm: a fit much better than that would be over-fitting, much worse under-fitting
    assert!(
        report.fit_error_x.std_um > 0.2 && report.fit_error_x.std_um < 0.8,
        "{:?}",
        report.fit_error_x
    );

    for (name, dir) in [
        ("PPP", [true; 3]),
        ("NPP", [false, true, true]),
        ("NPN", [false, true, false]),
        ("PPN", [true, true, false]),
    ] {
        let pts = diagonal(dir);
        for d in 0..3 {
            let nn: Vec<f64> = pts
                .iter()
                .map(|q| net.error_um(*q)[d] - field_um(*q)[d])
                .collect();
            let tri: Vec<f64> = pts
                .iter()
                .map(|q| trilinear(&e, *q)[d] - field_um(*q)[d])
                .collect();
            eprintln!(
                "{name} axis {d}: BPNN RMS {:.3} µm, trilinear RMS {:.3} µm",
                rms(&nn),
                rms(&tri)
            );
            assert!(rms(&nn) <= rms(&tri) + 1.0, "{name} axis {d}");
            assert!(nn.iter().all(|r| r.abs() < 2.0), "{name} axis {d}: {nn:?}");
        }
    }

    // the saved model evaluates identically after a round trip through mtec.bpnn/1
    // (to the last bit or so: serde_json's default float parser is not always correctly rounded)
    let back = Bpnn::load_volumetric(&net.to_json()).unwrap();
    let (u, v) = (
        back.error_um([123.0, 456.0, 78.0]),
        net.error_um([123.0, 456.0, 78.0]),
    );
    for d in 0..3 {
        assert!((u[d] - v[d]).abs() < 1e-9);
    }
}

#[test]
fn same_seed_same_weights_on_the_grid() {
    let (p, e) = grid(3);
    let cfg = GridFitConfig {
        max_epochs: 15,
        ..GridFitConfig::default()
    };
    let (a, _) = fit_grid(&p, &e, &cfg).unwrap();
    let (b, _) = fit_grid(&p, &e, &cfg).unwrap();
    assert_eq!(a.params(), b.params());
}
