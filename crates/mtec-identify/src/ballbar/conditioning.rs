//! Conditioning of the per-angle identification and the design of a mode set.
//!
//! At each angle the five readings satisfy `A(C)·e = ΔL` with `A` the 5×5 matrix of
//! [`identification_matrix`] (rows = modes, columns `EXC EYC EZC` in µm/µm and `EAC EBC` in
//! µm/µrad). Its singular values (nalgebra SVD) give the rank and the condition number
//! κ = σ_max/σ_min; 1/σ_min (µm or µrad per µm of reading) is the worst amplification of reading
//! noise into a motion. κ depends on the units of the columns: it is quoted in mtec's output
//! units (µm, µrad), so mode sets are compared on the same footing.
//!
//! Rank rule: a singular value below `RANK_RTOL·σ_max` counts as zero. The left-out direction (the
//! right singular vector of the smallest singular value) is the combination of motions that no
//! mode sees; it is named in the refusal.

use super::model::{first_order_row, identification_matrix, OBSERVABLE_NAMES};
use super::setup::{PresetDims, Setup};
use super::BallbarError;
use nalgebra::{DMatrix, Matrix5, SVD};

/// Relative threshold under which a singular value is treated as zero.
pub const RANK_RTOL: f64 = 1e-9;

/// Conditioning of the identification at one angle.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AngleConditioning {
    pub angle_deg: f64,
    /// Singular values, largest first.
    pub singular_values: [f64; 5],
    pub rank: usize,
    /// σ_max/σ_min (infinite when rank-deficient).
    pub condition_number: f64,
}

/// Conditioning of a mode set over the angles it is used at.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ConditioningReport {
    pub format: &'static str,
    pub unknowns: [&'static str; 5],
    /// Smallest rank over the angles.
    pub rank: usize,
    pub worst_angle_deg: f64,
    pub worst_condition_number: f64,
    /// Largest 1/σ_min over the angles: reading noise (µm) to motion (µm or µrad) amplification.
    pub worst_noise_gain: f64,
    /// Largest |coefficient| of ECC (µm/µrad) in any mode at any angle; 0 when bars lie in axial
    /// planes. A nonzero value means an ECC motion would leak into the identified five.
    pub ecc_coefficient_max: f64,
    /// What stays invisible over a whole revolution once each mode's mean and first harmonic are
    /// removed (harmonics 2 and up of the motions).
    pub revolution: RevolutionObservability,
    pub per_angle: Vec<AngleConditioning>,
}

/// Observability of the motions' harmonics 2..=`max_harmonic` over one revolution when every mode
/// signal also carries an unknown mean and first harmonic (the set-up error).
///
/// Least-squares system over `n_angles` evenly spaced angles: rows (mode, angle), columns the
/// cosine and sine coefficients of each motion's harmonics 2..=`max_harmonic` plus three set-up
/// terms per mode. Its null space (SVD, same rank rule as per angle) is the set of motion
/// combinations that change no cleaned reading; each is named by its largest coefficients.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RevolutionObservability {
    pub max_harmonic: usize,
    pub unknowns: usize,
    pub rank: usize,
    /// One entry per null-space direction, e.g. `+0.70·EBC·cos2C −0.70·EAC·sin2C …`.
    pub unobservable: Vec<String>,
}

/// See [`RevolutionObservability`].
pub fn revolution_observability(
    setup: &Setup,
    n_angles: usize,
    max_harmonic: usize,
) -> RevolutionObservability {
    let n_angles = n_angles.max(2 * max_harmonic + 4);
    let harmonics: Vec<usize> = (2..=max_harmonic).collect();
    let n_motion = 5 * 2 * harmonics.len();
    let cols = n_motion + 15;
    let rows = 5 * n_angles;
    let mut m = DMatrix::<f64>::zeros(rows, cols);
    for j in 0..n_angles {
        let c_deg = 360.0 * j as f64 / n_angles as f64;
        let c = c_deg.to_radians();
        for (i, mode) in setup.modes.iter().enumerate() {
            let r = i * n_angles + j;
            let g = first_order_row(mode, c_deg);
            for (k, gk) in g.iter().take(5).enumerate() {
                for (hi, &n) in harmonics.iter().enumerate() {
                    let col = (k * harmonics.len() + hi) * 2;
                    m[(r, col)] = gk * (n as f64 * c).cos();
                    m[(r, col + 1)] = gk * (n as f64 * c).sin();
                }
            }
            let base = n_motion + 3 * i;
            m[(r, base)] = 1.0;
            m[(r, base + 1)] = c.cos();
            m[(r, base + 2)] = c.sin();
        }
    }
    let svd = SVD::new(m, false, true);
    let smax = svd.singular_values.max();
    let v_t = svd.v_t.expect("v_t was requested");
    let mut unobservable = Vec::new();
    let mut rank = 0;
    for (idx, &sv) in svd.singular_values.iter().enumerate() {
        if sv > RANK_RTOL * smax {
            rank += 1;
            continue;
        }
        let v: Vec<f64> = (0..cols).map(|c| v_t[(idx, c)]).collect();
        let mut terms: Vec<(f64, String)> = Vec::new();
        for (k, name) in OBSERVABLE_NAMES.iter().enumerate() {
            for (hi, &n) in harmonics.iter().enumerate() {
                let col = (k * harmonics.len() + hi) * 2;
                for (o, f) in [(0, "cos"), (1, "sin")] {
                    terms.push((v[col + o], format!("{name}·{f}{n}C")));
                }
            }
        }
        terms.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
        let named: Vec<String> = terms
            .iter()
            .filter(|t| t.0.abs() > 0.05)
            .map(|(c, n)| format!("{c:+.3}·{n}"))
            .collect();
        unobservable.push(named.join(" "));
    }
    // Columns beyond the number of rows cannot be resolved either (never the case for n_angles ≥
    // 2·max_harmonic + 4 and five modes).
    rank = rank.min(cols);
    RevolutionObservability {
        max_harmonic,
        unknowns: cols,
        rank,
        unobservable,
    }
}

/// SVD of the identification matrix at one angle.
pub fn angle_conditioning(setup: &Setup, angle_deg: f64) -> AngleConditioning {
    let a = identification_matrix(setup, angle_deg);
    let (sv, rank, cond, _) = svd_parts(&a);
    AngleConditioning {
        angle_deg,
        singular_values: sv,
        rank,
        condition_number: cond,
    }
}

/// Singular values (descending), rank, κ and the right singular vector of σ_min.
fn svd_parts(a: &Matrix5<f64>) -> ([f64; 5], usize, f64, [f64; 5]) {
    let svd = SVD::new(*a, false, true);
    let mut idx: Vec<usize> = (0..5).collect();
    idx.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
    let sv: [f64; 5] = std::array::from_fn(|k| svd.singular_values[idx[k]]);
    let rank = sv.iter().filter(|&&s| s > RANK_RTOL * sv[0]).count();
    let cond = if rank < 5 {
        f64::INFINITY
    } else {
        sv[0] / sv[4]
    };
    let v_t = svd.v_t.expect("v_t was requested");
    let null: [f64; 5] = std::array::from_fn(|j| v_t[(idx[4], j)]);
    (sv, rank, cond, null)
}

/// The conditioning report of a setup at the given angles.
pub fn conditioning_report(setup: &Setup, angles_deg: &[f64]) -> ConditioningReport {
    let per_angle: Vec<AngleConditioning> = angles_deg
        .iter()
        .map(|&c| angle_conditioning(setup, c))
        .collect();
    let worst = per_angle
        .iter()
        .max_by(|a, b| a.condition_number.total_cmp(&b.condition_number));
    let ecc_coefficient_max = angles_deg
        .iter()
        .flat_map(|&c| {
            setup
                .modes
                .iter()
                .map(move |m| first_order_row(m, c)[5].abs())
        })
        .fold(0.0, f64::max);
    ConditioningReport {
        format: "mtec.ballbar-conditioning/1",
        unknowns: OBSERVABLE_NAMES,
        rank: per_angle.iter().map(|a| a.rank).min().unwrap_or(0),
        worst_angle_deg: worst.map(|w| w.angle_deg).unwrap_or(f64::NAN),
        worst_condition_number: worst.map(|w| w.condition_number).unwrap_or(f64::NAN),
        worst_noise_gain: per_angle
            .iter()
            .map(|a| 1.0 / a.singular_values[4])
            .fold(0.0, f64::max),
        ecc_coefficient_max,
        revolution: revolution_observability(setup, angles_deg.len().max(36), 6),
        per_angle,
    }
}

/// Refuses a mode set that cannot identify the five motions at one of the angles, naming the
/// invisible combination.
pub fn check_identifiable(setup: &Setup, angles_deg: &[f64]) -> Result<(), BallbarError> {
    for &c in angles_deg {
        let a = identification_matrix(setup, c);
        let (sv, rank, _, null) = svd_parts(&a);
        if rank < 5 {
            let mut terms: Vec<String> = null
                .iter()
                .zip(OBSERVABLE_NAMES)
                .filter(|(v, _)| v.abs() > 1e-6)
                .map(|(v, n)| format!("{v:+.3}·{n}"))
                .collect();
            if terms.is_empty() {
                terms.push("(none)".into());
            }
            let hint = hint_for(setup);
            return Err(BallbarError::RankDeficient {
                angle_deg: c,
                rank,
                singular_values: sv
                    .iter()
                    .map(|s| format!("{s:.3e}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                null_combination: terms.join(" "),
                hint,
            });
        }
    }
    Ok(())
}

/// A plain-language reason for the usual rank-deficient layouts.
fn hint_for(setup: &Setup) -> String {
    let axial: Vec<i64> = setup
        .modes
        .iter()
        .filter(|m| first_order_row(m, 0.0)[2].abs() > 1e-9)
        .map(|m| m.id)
        .collect();
    if axial.is_empty() {
        return "No mode has an axial (Z) component, so EZC is invisible: incline at least one bar."
            .into();
    }
    let heights: Vec<f64> = setup.modes.iter().map(|m| m.tool_ball_mm[2]).collect();
    if heights.iter().all(|h| (h - heights[0]).abs() < 1e-9)
        && setup
            .modes
            .iter()
            .all(|m| (m.workpiece_ball_mm[2] - heights[0]).abs() < 1e-9)
    {
        return "All bars lie in one plane normal to the axis, so a tilt cannot be told from a \
                radial shift: put the balls of some modes at another height."
            .into();
    }
    "Two or more modes see the same combination of motions (e.g. the second mount at the same \
     table angle twice, or the inclined bars' tool cup at the centre ball's height): move a mount \
     or change a height."
        .into()
}

/// How good a mode set is over one revolution.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DesignScore {
    pub worst_condition_number: f64,
    pub worst_angle_deg: f64,
    pub worst_noise_gain: f64,
}

/// Scores a mode set by its worst-case condition number over `n_angles` evenly spaced angles.
pub fn score_mode_set(setup: &Setup, n_angles: usize) -> DesignScore {
    let angles: Vec<f64> = (0..n_angles.max(1))
        .map(|i| 360.0 * i as f64 / n_angles.max(1) as f64)
        .collect();
    let r = conditioning_report(setup, &angles);
    DesignScore {
        worst_condition_number: r.worst_condition_number,
        worst_angle_deg: r.worst_angle_deg,
        worst_noise_gain: r.worst_noise_gain,
    }
}

/// Ranges of the preset's free dimensions for [`search_preset`] (mm, inclusive, `steps` values
/// each). `a` is searched as a fraction of `b` in `a_over_b`, so that `k = sqrt(b² − a²)` exists.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PresetRanges {
    pub h_mm: (f64, f64),
    pub b_mm: (f64, f64),
    pub a_over_b: (f64, f64),
    pub steps: usize,
    pub mount2_angles_deg: [f64; 3],
}

impl Default for PresetRanges {
    /// Heights 50–250 mm, bar lengths 100–300 mm (common ballbar lengths), a/b 0.2–0.95.
    fn default() -> Self {
        PresetRanges {
            h_mm: (50.0, 250.0),
            b_mm: (100.0, 300.0),
            a_over_b: (0.2, 0.95),
            steps: 9,
            mount2_angles_deg: [0.0, 120.0, 240.0],
        }
    }
}

/// The best preset found and how it scored.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DesignResult {
    pub dims: PresetDims,
    pub k_mm: f64,
    pub score: DesignScore,
    pub evaluated: usize,
}

/// Grid search of (h, b, a) (k follows from the constant bar length) minimising the worst-case
/// condition number over one revolution (36 angles).
pub fn search_preset(r: &PresetRanges) -> Result<DesignResult, BallbarError> {
    let steps = r.steps.max(2);
    let lin = |(lo, hi): (f64, f64), i: usize| lo + (hi - lo) * i as f64 / (steps - 1) as f64;
    let mut best: Option<DesignResult> = None;
    let mut evaluated = 0;
    for ih in 0..steps {
        for ib in 0..steps {
            for ia in 0..steps {
                let b = lin(r.b_mm, ib);
                let dims = PresetDims {
                    h_mm: lin(r.h_mm, ih),
                    b_mm: b,
                    a_mm: lin(r.a_over_b, ia) * b,
                    mount2_angles_deg: r.mount2_angles_deg,
                };
                let Ok(setup) = Setup::preset(dims) else {
                    continue;
                };
                evaluated += 1;
                let score = score_mode_set(&setup, 36);
                if best
                    .is_none_or(|b| score.worst_condition_number < b.score.worst_condition_number)
                {
                    best = Some(DesignResult {
                        dims,
                        k_mm: dims.k_mm(),
                        score,
                        evaluated: 0,
                    });
                }
            }
        }
    }
    best.map(|b| DesignResult { evaluated, ..b })
        .ok_or_else(|| {
            BallbarError::Geometry("no valid preset in the search ranges (need 0 < a < b)".into())
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ballbar::setup::Mode;

    /// With the preset, exactly the hand-derived family is invisible (two directions: the real
    /// and imaginary scale of `EBC + i·EAC = s·e^{−2iC}`, with `EXC = −h·EBC`, `EYC = h·EAC`).
    #[test]
    fn revolution_observability_names_the_minus_two_wobble() {
        let s = Setup::preset(Setup::default_dims()).unwrap();
        let r = revolution_observability(&s, 72, 6);
        assert_eq!(r.unknowns, 5 * 2 * 5 + 15);
        assert_eq!(r.rank, r.unknowns - 2, "{:?}", r.unobservable);
        for u in &r.unobservable {
            assert!(
                u.contains("EBC") && u.contains("EAC") && u.contains("2C"),
                "{u}"
            );
            assert!(!u.contains("EZC") && !u.contains("3C"), "{u}");
        }
        // the direction is the hand-derived one: per unit EBC·cos2C, EXC·cos2C = −h·1e-3 = −0.1
        let mut fam = vec![0.0; 50];
        let h = Setup::default_dims().h_mm * 1e-3;
        // column order: motion k, harmonic index (n − 2), cos/sin
        let col = |k: usize, n: usize, o: usize| (k * 5 + (n - 2)) * 2 + o;
        fam[col(4, 2, 0)] = 1.0; // EBC cos2C
        fam[col(3, 2, 1)] = -1.0; // EAC −sin2C
        fam[col(0, 2, 0)] = -h; // EXC = −h·EBC
        fam[col(1, 2, 1)] = -h; // EYC = h·EAC
        let mut max_reading: f64 = 0.0;
        for j in 0..72 {
            let c = j as f64 * 5.0;
            let cr = c.to_radians();
            for (i, mode) in s.modes.iter().enumerate() {
                let g = first_order_row(mode, c);
                let mut v = 0.0;
                for k in 0..5 {
                    for n in 2..=6 {
                        v += g[k]
                            * (fam[col(k, n, 0)] * (n as f64 * cr).cos()
                                + fam[col(k, n, 1)] * (n as f64 * cr).sin());
                    }
                }
                // modes 1–2 read nothing; modes 3–5 read only a first harmonic
                if i < 2 {
                    assert!(v.abs() < 1e-12);
                }
                max_reading = max_reading.max(v.abs());
            }
        }
        assert!(max_reading > 0.1);
    }

    #[test]
    fn preset_is_full_rank_everywhere() {
        let s = Setup::preset(Setup::default_dims()).unwrap();
        let angles: Vec<f64> = (0..72).map(|i| i as f64 * 5.0).collect();
        check_identifiable(&s, &angles).unwrap();
        let r = conditioning_report(&s, &angles);
        assert_eq!(r.rank, 5);
        assert!(r.worst_condition_number.is_finite());
        assert!(r.ecc_coefficient_max < 1e-12);
    }

    #[test]
    fn two_inclined_modes_at_the_same_table_angle_are_refused() {
        let mut d = Setup::default_dims();
        d.mount2_angles_deg = [0.0, 120.0, 0.0];
        let s = Setup::preset(d).unwrap();
        let e = check_identifiable(&s, &[0.0, 90.0]).unwrap_err();
        match &e {
            BallbarError::RankDeficient { rank, .. } => assert_eq!(*rank, 4),
            other => panic!("{other:?}"),
        }
        assert!(e.to_string().contains("rank 4 of 5"), "{e}");
    }

    #[test]
    fn coplanar_radial_bars_name_the_lost_combination() {
        // Five horizontal bars at one height: EZC invisible.
        let modes = (0..5)
            .map(|i| {
                let phi = (i as f64 * 72.0).to_radians();
                Mode {
                    id: i + 1,
                    workpiece_ball_mm: [60.0 * phi.cos(), 60.0 * phi.sin(), 100.0],
                    tool_ball_mm: [210.0 * phi.cos(), 210.0 * phi.sin(), 100.0],
                }
            })
            .collect();
        let s = Setup::new(modes).unwrap();
        let e = check_identifiable(&s, &[0.0]).unwrap_err();
        assert!(e.to_string().contains("EZC"), "{e}");
    }

    #[test]
    fn search_beats_or_equals_the_default_layout() {
        // A 3×3×3 grid that contains the default layout (h 100, b 500, a = 0.6·b = 300).
        let r = PresetRanges {
            h_mm: (50.0, 150.0),
            b_mm: (150.0, 500.0),
            a_over_b: (0.3, 0.9),
            steps: 3,
            ..Default::default()
        };
        let best = search_preset(&r).unwrap();
        assert_eq!(best.evaluated, 27);
        let default = score_mode_set(&Setup::preset(Setup::default_dims()).unwrap(), 36);
        assert!(
            best.score.worst_condition_number <= default.worst_condition_number * (1.0 + 1e-12)
        );
        assert!((best.k_mm.hypot(best.dims.a_mm) - best.dims.b_mm).abs() < 1e-9);
        // and it is the minimum over the grid, recomputed point by point
        for h in [50.0, 100.0, 150.0] {
            for b in [150.0, 325.0, 500.0] {
                for f in [0.3, 0.6, 0.9] {
                    let mut d = Setup::default_dims();
                    (d.h_mm, d.b_mm, d.a_mm) = (h, b, f * b);
                    let s = score_mode_set(&Setup::preset(d).unwrap(), 36);
                    assert!(
                        best.score.worst_condition_number
                            <= s.worst_condition_number * (1.0 + 1e-12),
                        "{best:?} vs {s:?} at {h} {b} {f}"
                    );
                }
            }
        }
    }
}
