//! ISO 230-4 values of a circular test: least-squares circle, circular deviation G per
//! direction, bidirectional circular deviation G(b), circular hysteresis H.
//!
//! Definitions used (ISO 230-4:2005, clause 3):
//! - the reference circle is the least-squares circle of the actual path: the centre (a, b) and
//!   radius ρ that minimise Σ (|P_i − (a, b)| − ρ)² (a geometric fit, solved by Gauss–Newton
//!   from the linearised "limaçon" start dl ≈ ρ₀ + a cos θ + b sin θ);
//! - circular deviation G = max_i r_i − min_i r_i, r_i the radial distance of the actual path from
//!   the least-squares centre of that path (one direction);
//! - bidirectional circular deviation G(b): the same range for the cw and ccw paths together
//!   about the least-squares circle of both paths;
//! - circular hysteresis H = max_θ |r_cw(θ) − r_ccw(θ)|, both radii about the common centre of
//!   G(b); where the two directions were not sampled at the same angles, r_ccw is interpolated
//!   linearly (periodically) at the cw angles and vice versa, and the larger value kept.
//!
//! A partial arc (ISO 230-4 permits one where the full circle cannot be traced): the same
//! definitions over the samples actually taken: each least-squares circle is fitted to the arc
//! (the geometric fit needs no symmetry), G and G(b) are ranges over the arc, and H is taken
//! where both directions overlap, interpolating linearly along the arc (not round it).
//!
//! Points are formed in µm relative to the nominal centre: P_i = (R + dl_i)(cos θ_i, sin θ_i).

use super::trace::{circle_fit_condition, CircularTrace, Sample, Travel};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// A least-squares circle (µm, relative to the nominal centre / nominal radius).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LsqCircle {
    /// Centre of the trace relative to the ballbar's pivot (µm along axis 1, axis 2).
    pub centre_um: [f64; 2],
    /// Radius minus the nominal radius (µm).
    pub radius_deviation_um: f64,
}

/// ISO 230-4 results of one test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Iso230_4 {
    pub circle_ccw: LsqCircle,
    pub circle_cw: LsqCircle,
    pub circle_bidirectional: LsqCircle,
    #[serde(rename = "G_ccw_um")]
    pub g_ccw_um: f64,
    #[serde(rename = "G_cw_um")]
    pub g_cw_um: f64,
    #[serde(rename = "G_bidirectional_um")]
    pub g_bidirectional_um: f64,
    #[serde(rename = "H_um")]
    pub h_um: f64,
    /// Condition number of the bidirectional circle fit ([`circle_fit_condition`]): √2 on a
    /// full circle, growing as 1/span² on a partial arc.
    pub circle_fit_condition: f64,
}

fn point_um(radius_um: f64, s: &Sample) -> [f64; 2] {
    let t = s.angle_deg.to_radians();
    let r = radius_um + s.dl_um;
    [r * t.cos(), r * t.sin()]
}

/// Geometric least-squares circle through the samples (Gauss–Newton, linearised start).
pub fn fit_circle(radius_mm: f64, samples: &[Sample]) -> LsqCircle {
    let r0 = radius_mm * 1000.0;
    let pts: Vec<[f64; 2]> = samples.iter().map(|s| point_um(r0, s)).collect();
    let n = pts.len();
    // Linearised start: dl ≈ ρ + a cos θ + b sin θ.
    let a_mat = DMatrix::from_fn(n, 3, |i, j| {
        let t = samples[i].angle_deg.to_radians();
        [1.0, t.cos(), t.sin()][j]
    });
    let y = DVector::from_iterator(n, samples.iter().map(|s| s.dl_um));
    let start = a_mat
        .clone()
        .svd(true, true)
        .solve(&y, 1e-12)
        .unwrap_or_else(|_| DVector::from_vec(vec![0.0, 0.0, 0.0]));
    let (mut a, mut b, mut rho) = (start[1], start[2], r0 + start[0]);
    for _ in 0..20 {
        // residual f_i = |P_i − c| − ρ; ∂f/∂a = −(x−a)/d, ∂f/∂b = −(y−b)/d, ∂f/∂ρ = −1
        let mut jac = DMatrix::zeros(n, 3);
        let mut f = DVector::zeros(n);
        for (i, p) in pts.iter().enumerate() {
            let (dx, dy) = (p[0] - a, p[1] - b);
            let d = dx.hypot(dy);
            f[i] = d - rho;
            jac[(i, 0)] = -dx / d;
            jac[(i, 1)] = -dy / d;
            jac[(i, 2)] = -1.0;
        }
        let Ok(step) = jac.svd(true, true).solve(&(-f), 1e-12) else {
            break;
        };
        a += step[0];
        b += step[1];
        rho += step[2];
        if step.norm() < 1e-10 {
            break;
        }
    }
    LsqCircle {
        centre_um: [a, b],
        radius_deviation_um: rho - r0,
    }
}

/// Radial distances (µm) of the samples from a centre, minus the nominal radius.
pub fn radii_about(radius_mm: f64, samples: &[Sample], c: &LsqCircle) -> Vec<f64> {
    let r0 = radius_mm * 1000.0;
    samples
        .iter()
        .map(|s| {
            let p = point_um(r0, s);
            (p[0] - c.centre_um[0]).hypot(p[1] - c.centre_um[1]) - r0
        })
        .collect()
}

fn range(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Periodic linear interpolation of (angle_deg, value) pairs at `at_deg`.
fn interp_periodic(sorted: &[(f64, f64)], at_deg: f64) -> f64 {
    let n = sorted.len();
    let a = at_deg.rem_euclid(360.0);
    let k = sorted.partition_point(|p| p.0 <= a);
    let (lo, hi) = if k == 0 {
        ((sorted[n - 1].0 - 360.0, sorted[n - 1].1), sorted[0])
    } else if k == n {
        (sorted[n - 1], (sorted[0].0 + 360.0, sorted[0].1))
    } else {
        (sorted[k - 1], sorted[k])
    };
    if hi.0 == lo.0 {
        return lo.1;
    }
    lo.1 + (hi.1 - lo.1) * (a - lo.0) / (hi.0 - lo.0)
}

fn sorted_pairs(samples: &[Sample], r: &[f64]) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = samples
        .iter()
        .map(|s| s.angle_deg)
        .zip(r.iter().copied())
        .collect();
    v.sort_by(|x, y| x.0.total_cmp(&y.0));
    v
}

/// Linear interpolation of (position, value) pairs sorted by position at `at`; `None` outside.
fn interp_along(sorted: &[(f64, f64)], at: f64) -> Option<f64> {
    let (first, last) = (sorted[0].0, sorted[sorted.len() - 1].0);
    if at < first || at > last {
        return None;
    }
    let k = sorted.partition_point(|p| p.0 <= at);
    if k == sorted.len() {
        return Some(sorted[k - 1].1);
    }
    let (lo, hi) = (sorted[k - 1], sorted[k]);
    if hi.0 == lo.0 {
        return Some(lo.1);
    }
    Some(lo.1 + (hi.1 - lo.1) * (at - lo.0) / (hi.0 - lo.0))
}

/// The ISO 230-4 evaluation of a trace.
pub fn evaluate(trace: &CircularTrace) -> Iso230_4 {
    let r = trace.radius_mm;
    let ccw = trace.samples(Travel::Ccw);
    let cw = trace.samples(Travel::Cw);
    let circle_ccw = fit_circle(r, ccw);
    let circle_cw = fit_circle(r, cw);
    let both: Vec<Sample> = ccw.iter().chain(cw.iter()).copied().collect();
    let circle_b = fit_circle(r, &both);
    let g_ccw = range(&radii_about(r, ccw, &circle_ccw));
    let g_cw = range(&radii_about(r, cw, &circle_cw));
    let rb_ccw = radii_about(r, ccw, &circle_b);
    let rb_cw = radii_about(r, cw, &circle_b);
    let g_b = range(
        &rb_ccw
            .iter()
            .chain(rb_cw.iter())
            .copied()
            .collect::<Vec<_>>(),
    );
    let (h1, h2) = match &trace.arc {
        None => {
            let s_ccw = sorted_pairs(ccw, &rb_ccw);
            let s_cw = sorted_pairs(cw, &rb_cw);
            let h1 = s_cw
                .iter()
                .map(|(a, v)| (v - interp_periodic(&s_ccw, *a)).abs())
                .fold(0.0, f64::max);
            let h2 = s_ccw
                .iter()
                .map(|(a, v)| (v - interp_periodic(&s_cw, *a)).abs())
                .fold(0.0, f64::max);
            (h1, h2)
        }
        Some(arc) => {
            // positions along the arc; only where the other direction was traced too
            let along = |s: &[Sample], r: &[f64]| -> Vec<(f64, f64)> {
                let mut v: Vec<(f64, f64)> = s
                    .iter()
                    .map(|x| arc.along(x.angle_deg))
                    .zip(r.iter().copied())
                    .collect();
                v.sort_by(|x, y| x.0.total_cmp(&y.0));
                v
            };
            let (s_ccw, s_cw) = (along(ccw, &rb_ccw), along(cw, &rb_cw));
            let h = |a: &[(f64, f64)], b: &[(f64, f64)]| {
                a.iter()
                    .filter_map(|(u, v)| interp_along(b, *u).map(|w| (v - w).abs()))
                    .fold(0.0, f64::max)
            };
            (h(&s_cw, &s_ccw), h(&s_ccw, &s_cw))
        }
    };
    let angles: Vec<f64> = both.iter().map(|s| s.angle_deg).collect();
    Iso230_4 {
        circle_ccw,
        circle_cw,
        circle_bidirectional: circle_b,
        g_ccw_um: g_ccw,
        g_cw_um: g_cw,
        g_bidirectional_um: g_b,
        h_um: h1.max(h2),
        circle_fit_condition: circle_fit_condition(&angles),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::circular::trace::Plane;

    /// ISO 230-4's definitions worked by hand on an 8-point-per-direction trace.
    ///
    /// The machine's paths about their own centre C = (30, −20) µm are
    ///   θ (deg):       0    45   90   135  180  225  270  315
    ///   r_cw − R:      2    −1   2    −1   2    −1   2    −1      (µm)
    ///   r_ccw − R:     4    0    1    −0.5 4    0    1    −0.5
    /// Each path is symmetric under a half turn about C (r(θ) = r(θ + 180°)), so the
    /// least-squares objective is symmetric under c ↦ 2C − c and its minimum lies at C for each
    /// path and for both together. The least-squares radius about a fixed centre is the mean
    /// radius: cw R + (2 − 1)/2 = R + 0.5, ccw R + 2·(4 + 0 + 1 − 0.5)/8 = R + 1.125,
    /// both R + (0.5 + 1.125)/2 = R + 0.8125.
    ///   G(cw)  = 2 − (−1)   = 3
    ///   G(ccw) = 4 − (−0.5) = 4.5
    ///   G(b)   = max over both − min over both = 4 − (−1) = 5
    ///   H      = max |r_cw − r_ccw| = max(|2−4|, |−1−0|, |2−1|, |−1+0.5|) = 2
    /// The ballbar sees these points from its pivot at the nominal centre, so the file holds
    /// dl = |C + (R + r)(cos θ, sin θ)| − R, computed exactly below.
    #[test]
    fn hand_worked_iso230_4() {
        let radius_mm = 100.0;
        let r0 = radius_mm * 1000.0;
        let c = [30.0, -20.0];
        let cw_r = [2.0, -1.0, 2.0, -1.0, 2.0, -1.0, 2.0, -1.0];
        let ccw_r = [4.0, 0.0, 1.0, -0.5, 4.0, 0.0, 1.0, -0.5];
        let to_samples = |r: &[f64; 8]| -> Vec<Sample> {
            (0..8)
                .map(|k| {
                    let t = (45.0 * k as f64).to_radians();
                    let p = [c[0] + (r0 + r[k]) * t.cos(), c[1] + (r0 + r[k]) * t.sin()];
                    Sample {
                        // the ballbar's angle is the direction seen from the pivot
                        angle_deg: p[1].atan2(p[0]).to_degrees().rem_euclid(360.0),
                        dl_um: p[0].hypot(p[1]) - r0,
                    }
                })
                .collect()
        };
        let trace = CircularTrace {
            radius_mm,
            plane: Plane::XY,
            feed_mm_min: None,
            arc: None,
            cw: to_samples(&cw_r),
            ccw: to_samples(&ccw_r),
        };
        let v = evaluate(&trace);
        let tol = 1e-6;
        for circle in [v.circle_cw, v.circle_ccw, v.circle_bidirectional] {
            assert!((circle.centre_um[0] - 30.0).abs() < tol, "{circle:?}");
            assert!((circle.centre_um[1] + 20.0).abs() < tol, "{circle:?}");
        }
        assert!((v.circle_cw.radius_deviation_um - 0.5).abs() < tol);
        assert!((v.circle_ccw.radius_deviation_um - 1.125).abs() < tol);
        assert!((v.circle_bidirectional.radius_deviation_um - 0.8125).abs() < tol);
        assert!((v.g_cw_um - 3.0).abs() < tol, "{v:?}");
        assert!((v.g_ccw_um - 4.5).abs() < tol, "{v:?}");
        assert!((v.g_bidirectional_um - 5.0).abs() < tol, "{v:?}");
        assert!((v.h_um - 2.0).abs() < 1e-3, "{v:?}");
    }

    /// A 220° arc (−110° to 110°, through 0°) worked by hand.
    ///
    /// The path is a circle of centre C = (30, −20) µm and radius ρ = R + 5 µm, sampled every
    /// 10° of φ (the angle seen from C), with a bump: radial deviations r(0°) = h,
    /// r(±60°) = −h, r(±90°) = h/2, 0 elsewhere. Then Σ r = h − 2h + h = 0,
    /// Σ r cos φ = h − 2h·½ + 0 = 0 and Σ r sin φ = 0 (even in φ). Each point is exactly
    /// C + (ρ + r)(cos φ, sin φ), so at (C, ρ) the gradient of Σ(|P − c| − ρ)², −2Σ r (cos φ,
    /// sin φ, 1), vanishes: (C, ρ) is the least-squares circle, and G = h − (−h) = 2h.
    /// With h = 2 µm ccw and h = 1 µm cw: G(ccw) = 4, G(cw) = 2; both fits are at (C, ρ), so
    /// G(b) = 2 − (−2) = 4 and H = max |r_ccw − r_cw| = max(1, 1, 0.5) = 1 µm.
    /// Independently, the circle through three of the unbumped points (φ = −110°, −30°, 110°),
    /// from the perpendicular bisectors (circumcentre formula), is (C, ρ): the construction
    /// holds what it claims.
    #[test]
    fn hand_worked_partial_arc() {
        use crate::circular::trace::Arc;
        let radius_mm = 100.0;
        let r0 = radius_mm * 1000.0;
        let c = [30.0, -20.0];
        let rho = r0 + 5.0;
        let bump = |phi: i32, h: f64| match phi {
            0 => h,
            60 | -60 => -h,
            90 | -90 => h / 2.0,
            _ => 0.0,
        };
        let point = |phi: i32, r: f64| {
            let t = (phi as f64).to_radians();
            [c[0] + (rho + r) * t.cos(), c[1] + (rho + r) * t.sin()]
        };
        // circumcentre of three unbumped points: |P − c|² equal for all three, two linear
        // equations 2(P_k − P_1)·c = |P_k|² − |P_1|², solved by Cramer's rule
        let (p1, p2, p3) = (point(-110, 0.0), point(-30, 0.0), point(110, 0.0));
        let sq = |p: [f64; 2]| p[0] * p[0] + p[1] * p[1];
        let (a11, a12, b1) = (
            2.0 * (p2[0] - p1[0]),
            2.0 * (p2[1] - p1[1]),
            sq(p2) - sq(p1),
        );
        let (a21, a22, b2) = (
            2.0 * (p3[0] - p1[0]),
            2.0 * (p3[1] - p1[1]),
            sq(p3) - sq(p1),
        );
        let det = a11 * a22 - a12 * a21;
        let cc = [(b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det];
        assert!(
            (cc[0] - c[0]).abs() < 1e-5 && (cc[1] - c[1]).abs() < 1e-5,
            "{cc:?}"
        );
        assert!(((p1[0] - cc[0]).hypot(p1[1] - cc[1]) - rho).abs() < 1e-5);

        let samples = |h: f64, order: &mut dyn Iterator<Item = i32>| -> Vec<Sample> {
            order
                .map(|phi| {
                    let p = point(phi, bump(phi, h));
                    Sample {
                        // the ballbar's angle and length are seen from the pivot at the origin
                        angle_deg: p[1].atan2(p[0]).to_degrees().rem_euclid(360.0),
                        dl_um: p[0].hypot(p[1]) - r0,
                    }
                })
                .collect()
        };
        let trace = CircularTrace {
            radius_mm,
            plane: Plane::ZX,
            feed_mm_min: None,
            arc: Some(Arc {
                start_deg: 250.0,
                end_deg: 110.0,
                span_deg: 220.0,
            }),
            ccw: samples(2.0, &mut (-11..=11).map(|k| 10 * k)),
            cw: samples(1.0, &mut (-11..=11).rev().map(|k| 10 * k)),
        };
        let v = evaluate(&trace);
        let tol = 1e-6;
        for circle in [v.circle_ccw, v.circle_cw, v.circle_bidirectional] {
            assert!((circle.centre_um[0] - c[0]).abs() < tol, "{circle:?}");
            assert!((circle.centre_um[1] - c[1]).abs() < tol, "{circle:?}");
            assert!((circle.radius_deviation_um - 5.0).abs() < tol, "{circle:?}");
        }
        assert!((v.g_ccw_um - 4.0).abs() < tol, "{v:?}");
        assert!((v.g_cw_um - 2.0).abs() < tol, "{v:?}");
        assert!((v.g_bidirectional_um - 4.0).abs() < tol, "{v:?}");
        // the two directions are sampled at the same points; H interpolates along the arc only
        assert!((v.h_um - 1.0).abs() < 1e-6, "{v:?}");
        assert!(v.circle_fit_condition > 2.5 && v.circle_fit_condition < 4.0);
    }
}
