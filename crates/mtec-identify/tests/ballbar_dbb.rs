#![allow(clippy::needless_range_loop)] // index loops read like the Jacobi algorithm
//! Ballbar identification against the virtual machine (`dbb-rotary`) and an independent SVD.

use mtec_identify::ballbar::identify::solve_angle;
use mtec_identify::ballbar::{
    conditioning_report, identification_matrix, identify, predicted_dl_um,
    remove_mean_and_first_harmonic, ErrorMotions, Measurements, Setup, OBSERVABLE_NAMES,
};
use mtec_io::Table;
use std::collections::BTreeMap;
use std::path::Path;

fn scenario(seed: u64) -> (Setup, Measurements, serde_json::Value) {
    let out = mtec_sim::run_scenario("dbb-rotary", seed).unwrap();
    let file = |n: &str| {
        out.files
            .iter()
            .find(|f| f.name == n)
            .unwrap()
            .contents
            .clone()
    };
    let setup = Setup::parse(Path::new("setup.toml"), &file("setup.toml")).unwrap();
    let table = Table::parse(Path::new("dbb.csv"), &file("dbb.csv")).unwrap();
    let data = Measurements::from_table(&table, &setup).unwrap();
    (setup, data, out.truth)
}

type Key = (i64, i64);

/// The truth seen through the same path: model readings of the true motions (first order, ECC
/// included), mean and first harmonic removed per mode, solved per angle.
fn truth_reference(setup: &Setup, truth: &serde_json::Value) -> BTreeMap<(Key, i64), [f64; 5]> {
    let m = &truth["motions"];
    let col = |n: &str| -> Vec<f64> {
        m[n].as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let exp = col("experiment");
    let time = col("time_min");
    let angle = col("angle_deg");
    let e: Vec<Vec<f64>> = [
        "EXC_um", "EYC_um", "EZC_um", "EAC_urad", "EBC_urad", "ECC_urad",
    ]
    .iter()
    .map(|n| col(n))
    .collect();
    let mut groups: BTreeMap<Key, Vec<(f64, ErrorMotions)>> = BTreeMap::new();
    for i in 0..exp.len() {
        let motions = ErrorMotions {
            exc_um: e[0][i],
            eyc_um: e[1][i],
            ezc_um: e[2][i],
            eac_urad: e[3][i],
            ebc_urad: e[4][i],
            ecc_urad: e[5][i],
        };
        groups
            .entry((exp[i] as i64, (time[i] * 1e6).round() as i64))
            .or_default()
            .push((angle[i], motions));
    }
    let mut out = BTreeMap::new();
    for (key, mut g) in groups {
        g.sort_by(|a, b| a.0.total_cmp(&b.0));
        let angles: Vec<f64> = g.iter().map(|x| x.0).collect();
        let signals: Vec<Vec<f64>> = (0..5)
            .map(|mi| {
                g.iter()
                    .map(|(c, mo)| predicted_dl_um(setup, *c, mo)[mi])
                    .collect()
            })
            .collect();
        let cleaned: Vec<Vec<f64>> = signals
            .iter()
            .map(|s| remove_mean_and_first_harmonic(&angles, s).unwrap())
            .collect();
        for (j, &c) in angles.iter().enumerate() {
            let y: [f64; 5] = std::array::from_fn(|i| cleaned[i][j]);
            out.insert(
                (key, (c * 1e6).round() as i64),
                solve_angle(setup, c, y).unwrap(),
            );
        }
    }
    out
}

/// Identified EXC..EBC match the truth (same mean/first-harmonic removal) within 0.5 µm / 0.5 µrad
/// RMS over all angles and times, from exact-kinematics readings with set-up errors, head drift
/// and 0.1 µm noise.
#[test]
fn dbb_rotary_identification_matches_truth() {
    let (setup, data, truth) = scenario(11);
    assert_eq!(data.items.len(), 4 * 13);
    let id = identify(&setup, &data).unwrap();
    assert_eq!(id.rows.len(), 4 * 13 * 72);
    let reference = truth_reference(&setup, &truth);
    let mut sq = [0.0; 5];
    let mut amp = [0.0f64; 5];
    for r in &id.rows {
        let key = (
            (r.experiment, (r.time_min * 1e6).round() as i64),
            (r.angle_deg * 1e6).round() as i64,
        );
        let want = reference[&key];
        let got = r.motions.observable();
        for k in 0..5 {
            sq[k] += (got[k] - want[k]).powi(2);
            amp[k] = amp[k].max(want[k].abs());
        }
    }
    let n = id.rows.len() as f64;
    // Noise-limited check: the expected RMS from the covariance σ²·(AᵀA)⁻¹ averaged over the
    // angles, reduced by (N − 3)/N for the three removed Fourier terms per signal.
    let noise_um = truth["ballbar_noise_um"].as_f64().unwrap();
    let mut var = [0.0; 5];
    for i in 0..72 {
        let a = identification_matrix(&setup, i as f64 * 5.0);
        let cov = (a.transpose() * a).try_inverse().unwrap();
        for k in 0..5 {
            var[k] += cov[(k, k)] / 72.0;
        }
    }
    for k in 0..5 {
        let rms = (sq[k] / n).sqrt();
        let expected = noise_um * (var[k] * 69.0 / 72.0).sqrt();
        eprintln!(
            "{}: RMS {rms:.3}, expected from noise alone {expected:.3}",
            OBSERVABLE_NAMES[k]
        );
        assert!(
            (rms / expected - 1.0).abs() < 0.15,
            "{}: not noise-limited ({rms} vs {expected})",
            OBSERVABLE_NAMES[k]
        );
        eprintln!(
            "{}: RMS error {rms:.3} (largest cleaned truth value {:.2})",
            OBSERVABLE_NAMES[k], amp[k]
        );
        assert!(rms < 0.5, "{}: RMS {rms}", OBSERVABLE_NAMES[k]);
        // the comparison is not empty: the cleaned truth carries real signal
        assert!(amp[k] > 5.0 * rms);
    }
}

/// Thermal change is visible: the identified motions at 240 min differ from those at 0 min in
/// the fastest experiment by more than the identification noise.
#[test]
fn thermal_change_is_identified() {
    let (setup, data, truth) = scenario(3);
    let id = identify(&setup, &data).unwrap();
    let reference = truth_reference(&setup, &truth);
    let pick = |t: f64| -> Vec<[f64; 5]> {
        id.rows
            .iter()
            .filter(|r| r.experiment == 4 && r.time_min == t)
            .map(|r| r.motions.observable())
            .collect()
    };
    let (a, b) = (pick(0.0), pick(240.0));
    let change_exc = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x[0] - y[0]).abs())
        .fold(0.0, f64::max);
    let ref_change = reference
        .iter()
        .filter(|(((e, t), _), _)| *e == 4 && *t == 240_000_000)
        .map(|(((_, _), c), v)| (v[0] - reference[&((4, 0), *c)][0]).abs())
        .fold(0.0, f64::max);
    eprintln!("max EXC change over 4 h at 40 rpm: identified {change_exc:.2} um, truth {ref_change:.2} um");
    assert!(ref_change > 1.0);
    assert!((change_exc - ref_change).abs() < 0.5);
}

/// A rank-deficient mode set is refused with the reason, on the same data.
#[test]
fn rank_deficient_mode_set_is_refused() {
    let (setup, data, _) = scenario(5);
    let mut bad = setup.clone();
    // Move mode 5's second mount onto mode 3's table angle: both see the same combination.
    bad.modes[4].workpiece_ball_mm = bad.modes[2].workpiece_ball_mm;
    let bad = Setup::new(bad.modes).unwrap();
    let e = identify(&bad, &data).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("rank-deficient") && msg.contains("rank 4 of 5"),
        "{msg}"
    );
    assert!(msg.contains("cannot be identified"), "{msg}");
}

/// The condition report equals singular values computed another way: square roots of the
/// eigenvalues of AᵀA by cyclic Jacobi rotations (written out here, no nalgebra SVD).
#[test]
fn condition_report_matches_independent_eigenvalues() {
    let setup = Setup::preset(Setup::default_dims()).unwrap();
    let angles: Vec<f64> = (0..24).map(|i| i as f64 * 15.0).collect();
    let report = conditioning_report(&setup, &angles);
    let mut worst = 0.0f64;
    let mut cond_at = BTreeMap::new();
    for (pa, &c) in report.per_angle.iter().zip(&angles) {
        let a = identification_matrix(&setup, c);
        let mut m = [[0.0f64; 5]; 5];
        for i in 0..5 {
            for j in 0..5 {
                m[i][j] = (0..5).map(|k| a[(k, i)] * a[(k, j)]).sum();
            }
        }
        let mut eig = jacobi_eigenvalues(m);
        eig.sort_by(|x, y| y.total_cmp(x));
        for k in 0..5 {
            let s = eig[k].max(0.0).sqrt();
            assert!(
                (s - pa.singular_values[k]).abs() < 1e-9 * pa.singular_values[0],
                "C={c}: {s} vs {}",
                pa.singular_values[k]
            );
        }
        let cond = (eig[0] / eig[4]).sqrt();
        assert!((cond - pa.condition_number).abs() < 1e-6 * cond);
        worst = worst.max(cond);
        cond_at.insert((c * 1e6).round() as i64, cond);
    }
    // the worst angle (ties are possible: the layout repeats every 120°) has the worst condition
    let at_reported = cond_at[&((report.worst_angle_deg * 1e6).round() as i64)];
    assert!((at_reported - worst).abs() < 1e-6 * worst);
    assert!((report.worst_condition_number - worst).abs() < 1e-6 * worst);
}

/// Eigenvalues of a symmetric matrix by cyclic Jacobi rotations (Golub & Van Loan §8.5).
fn jacobi_eigenvalues(mut a: [[f64; 5]; 5]) -> [f64; 5] {
    for _sweep in 0..100 {
        let off: f64 = (0..5)
            .flat_map(|i| (0..5).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..5 {
            for q in p + 1..5 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..5 {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..5 {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
            }
        }
    }
    std::array::from_fn(|i| a[i][i])
}
