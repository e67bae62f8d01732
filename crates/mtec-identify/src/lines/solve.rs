//! Least-squares solution of the kept (full-rank) design and its statistics.
//!
//! θ from R θ = Qᵀy on the column-scaled kept design (Householder QR, [`super::identifiability`]);
//! residual variance σ̂² = ‖y − Aθ‖²/(m − k); covariance Cov(θ) = σ̂² (AᵀA)⁻¹ = σ̂² R⁻¹R⁻ᵀ
//! (unscaled by the column norms); the uncertainty of an error function at q is
//! σ_f(q) = √(b(q)ᵀ Cov_B b(q)), b the block's basis, and an element's reported uncertainty is
//! max σ_f over its travel (101 positions).

use super::data::LineData;
use super::identifiability::Analysis;
use super::model::{Block, ElementKind, Layout};
use nalgebra::{DMatrix, DVector};

/// The fitted parameters and their covariance.
#[derive(Debug, Clone)]
pub struct Fit {
    /// Parameter values in layout column order (0 for dropped columns).
    pub theta: DVector<f64>,
    /// Covariance over the active columns (same order as `analysis.active`).
    pub cov: DMatrix<f64>,
    /// Residual of every reading (µm), in data order.
    pub residual_um: DVector<f64>,
    /// √(RSS/(m − k)): the noise the fit implies, µm.
    pub sigma_um: f64,
    /// Degrees of freedom m − k.
    pub dof: usize,
}

/// Solves the kept design: R θ_s = Qᵀy (back substitution), Cov_s = σ̂² R⁻¹R⁻ᵀ.
pub fn solve(a: &DMatrix<f64>, y: &DVector<f64>, an: &Analysis) -> Fit {
    let k = an.active.len();
    let r = &an.kept_r;
    let theta_s = r
        .solve_upper_triangular(&an.qty)
        .unwrap_or_else(|| DVector::from_element(k, f64::NAN));
    let mut theta = DVector::zeros(a.ncols());
    for (j, &c) in an.active.iter().enumerate() {
        theta[c] = theta_s[j] / an.scale[c];
    }
    let residual = y - a * &theta;
    let m = a.nrows();
    let dof = m.saturating_sub(k);
    let sigma2 = if dof > 0 {
        residual.norm_squared() / dof as f64
    } else {
        f64::NAN
    };
    let r_inv = r
        .solve_upper_triangular(&DMatrix::identity(k, k))
        .unwrap_or_else(|| DMatrix::from_element(k, k, f64::NAN));
    let mut cov = &r_inv * r_inv.transpose() * sigma2;
    for i in 0..k {
        for j in 0..k {
            cov[(i, j)] /= an.scale[an.active[i]] * an.scale[an.active[j]];
        }
    }
    Fit {
        theta,
        cov,
        residual_um: residual,
        sigma_um: sigma2.sqrt(),
        dof,
    }
}

impl Fit {
    /// Value and 1σ of a kept block's function at axis position q.
    pub fn value_sigma(&self, an: &Analysis, b: &Block, q: f64) -> (f64, f64) {
        let basis: Vec<f64> = b.basis(q).collect();
        let pos: Vec<usize> = b
            .cols()
            .map(|c| an.active.iter().position(|&x| x == c).expect("kept block"))
            .collect();
        let value: f64 = b.cols().zip(&basis).map(|(c, bv)| self.theta[c] * bv).sum();
        let mut var = 0.0;
        for (i, &pi) in pos.iter().enumerate() {
            for (j, &pj) in pos.iter().enumerate() {
                var += basis[i] * self.cov[(pi, pj)] * basis[j];
            }
        }
        (value, var.max(0.0).sqrt())
    }

    /// (max |value|, max 1σ) of a kept block over its travel (101 positions).
    pub fn envelope(&self, an: &Analysis, b: &Block) -> (f64, f64) {
        let [lo, hi] = b.travel;
        let n = if b.kind == ElementKind::Squareness {
            1
        } else {
            101
        };
        (0..n)
            .map(|i| {
                let q = lo + (hi - lo) * i as f64 / 100.0;
                self.value_sigma(an, b, q)
            })
            .fold((0.0f64, 0.0f64), |(mv, ms), (v, s)| {
                (mv.max(v.abs()), ms.max(s))
            })
    }

    /// RMS of the residuals of each channel (µm), in data order.
    pub fn channel_rms(&self, data: &LineData) -> Vec<(String, f64)> {
        let mut row = 0;
        data.channels
            .iter()
            .map(|c| {
                let n = c.readings_um.len();
                let ss: f64 = (row..row + n).map(|i| self.residual_um[i].powi(2)).sum();
                row += n;
                (c.label(), (ss / n as f64).sqrt())
            })
            .collect()
    }

    /// Alignment slope (µrad) and 1σ of each straightness channel.
    pub fn slopes(
        &self,
        an: &Analysis,
        layout: &Layout,
        data: &LineData,
    ) -> Vec<(String, f64, f64)> {
        layout
            .slopes
            .iter()
            .map(|&(ci, col)| {
                let sd = an
                    .active
                    .iter()
                    .position(|&x| x == col)
                    .map_or(f64::NAN, |j| self.cov[(j, j)].max(0.0).sqrt());
                (data.channels[ci].label(), self.theta[col], sd)
            })
            .collect()
    }
}

/// Σ_p c_p ((q − lo)/L)^p as coefficients of powers of q (binomial expansion).
pub fn polynomial_in_q(coeffs: &[(i32, f64)], travel: [f64; 2]) -> Vec<f64> {
    let (lo, len) = (travel[0], travel[1] - travel[0]);
    let deg = coeffs.iter().map(|c| c.0).max().unwrap_or(0).max(0) as usize;
    let mut out = vec![0.0; deg + 1];
    for &(p, c) in coeffs {
        let p = p as usize;
        // ((q − lo)/L)^p = Σ_k C(p,k) q^k (−lo)^(p−k) / L^p
        let mut binom = 1.0;
        for (k, o) in out.iter_mut().enumerate().take(p + 1) {
            *o += c * binom * (-lo).powi((p - k) as i32) / len.powi(p as i32);
            binom = binom * (p - k) as f64 / (k + 1) as f64;
        }
    }
    out
}
