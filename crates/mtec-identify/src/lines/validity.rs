//! Whether an identification can be trusted: three checks, each a warning and `valid = false`.
//!
//! 1. Conditioning: the condition number κ of the kept, column-scaled design. Above
//!    [`COND_LIMIT`] a reading error of ε (relative) may move the parameters by κ·ε.
//! 2. Between the points: the *amplification* Λ of the least-squares fit of each error
//!    function on the positions its axis was measured at, Λ = max_q Σ_k |ℓ_k(q)| with
//!    ℓ(q)ᵀ = b(q)ᵀ(BᵀB)⁻¹Bᵀ = b(q)ᵀR⁻¹Qᵀ (B = QR the basis at the measured positions, the
//!    Lebesgue function of the discrete least-squares projection): a reading error of δ at
//!    the measured positions can become Λ·δ between them. Above [`LAMBDA_LIMIT`] the degree is
//!    more than the measured positions support (Runge's phenomenon).
//! 3. Residual against repeatability: σ_fit/σ_rep, with σ_rep the pure error of the repeat runs
//!    (each reading's residual minus the mean residual of the same channel and point over the
//!    runs: what the runs disagree about, whatever the model). Above [`RATIO_LIMIT`] the
//!    functions do not follow the machine's shape. Needs ≥ 2 runs.

use super::basis;
use super::data::{measured_positions, LineData};
use super::model::Layout;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// Condition number above which a result is not trusted.
pub const COND_LIMIT: f64 = 1e6;
/// Amplification between measured positions above which a degree is not supported.
pub const LAMBDA_LIMIT: f64 = 4.0;
/// Fit residual over repeatability above which the model's shape does not fit.
pub const RATIO_LIMIT: f64 = 3.0;

/// Λ of a degree-`degree` Legendre fit on positions `q` (mm) of a travel (401 test positions).
pub fn amplification(q: &[f64], travel: [f64; 2], degree: usize) -> f64 {
    let x = |v: f64| (2.0 * v - travel[0] - travel[1]) / (travel[1] - travel[0]);
    let n = degree + 1;
    if q.len() < n {
        return f64::INFINITY;
    }
    let b = DMatrix::from_fn(q.len(), n, |i, j| basis::legendre_all(degree, x(q[i]))[j]);
    let qr = b.qr();
    let Some(r_inv) = qr.r().try_inverse() else {
        return f64::INFINITY;
    };
    // rows of Q R⁻ᵀ: ℓ(q) = Q R⁻ᵀ b(q)
    let q_mat = qr.q();
    let (lo, hi) = (
        q.iter().copied().fold(f64::INFINITY, f64::min),
        q.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    (0..=400)
        .map(|i| {
            let v = lo + (hi - lo) * i as f64 / 400.0;
            let bv = DMatrix::from_row_slice(1, n, &basis::legendre_all(degree, x(v)));
            let l = &bv * &r_inv * q_mat.transpose();
            l.iter().map(|c| c.abs()).sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// σ_rep (µm) and its degrees of freedom from the residuals of a fit; None with one run only.
pub fn repeatability(data: &LineData, residual: &nalgebra::DVector<f64>) -> Option<(f64, usize)> {
    let mut groups: BTreeMap<(String, usize), Vec<f64>> = BTreeMap::new();
    let mut row = 0;
    for c in &data.channels {
        for k in 0..c.readings_um.len() {
            groups
                .entry((c.name.clone(), k))
                .or_default()
                .push(residual[row]);
            row += 1;
        }
    }
    let (mut ss, mut dof) = (0.0, 0usize);
    for v in groups.values().filter(|v| v.len() > 1) {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        ss += v.iter().map(|x| (x - m).powi(2)).sum::<f64>();
        dof += v.len() - 1;
    }
    (dof > 0).then(|| ((ss / dof as f64).sqrt(), dof))
}

/// The largest amplification over the layout's polynomial blocks, with the block's element.
pub fn worst_amplification(layout: &Layout, data: &LineData) -> Option<(String, usize, f64)> {
    let pos = measured_positions(data);
    layout
        .blocks
        .iter()
        .filter(|b| b.degree() > 0)
        .map(|b| {
            let d = b.degree();
            (
                b.element.name(),
                d,
                amplification(&pos[b.element.axis.index()], b.travel, d),
            )
        })
        .max_by(|a, b| a.2.total_cmp(&b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplification_grows_with_the_degree_on_equispaced_points() {
        let q: Vec<f64> = (0..=20).map(|k| 10.0 + 29.0 * k as f64).collect();
        let l: Vec<f64> = (2..=12)
            .map(|d| amplification(&q, [0.0, 600.0], d))
            .collect();
        println!("{l:.2?}");
        assert!(l[0] < 2.0 && l[10] > LAMBDA_LIMIT, "{l:?}");
    }
}
