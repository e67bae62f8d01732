//! Linear least squares on a design of regressors: ordinary least squares (MLR) by QR, ridge
//! regression in standardised (correlation) form by SVD, variance inflation factors, and the
//! warning every linear kind gives when large standardised coefficients cancel.
//!
//! Ridge convention (Hoerl & Kennard 1970, the form ridge traces are drawn in): the regressors
//! are standardised with their mean and population standard deviation, z = (x − x̄)/s_x, the
//! target with ȳ and s_y; the standardised coefficients are
//! β*(k) = (R + kI)⁻¹ r with R = ZᵀZ/n the correlation matrix and r = Zᵀ(y−ȳ)/(n s_y),
//! and the de-standardised equation is b_j = β*_j s_y / s_j, b₀ = ȳ − Σ b_j x̄_j.
//! This equals scikit-learn's `Ridge(alpha = n·k)` fitted on `StandardScaler` output (the
//! fixtures check it). k = 0 is ordinary least squares.

use crate::error::ThermalError;
use nalgebra::{DMatrix, DVector};

/// Relative size of a QR diagonal below which a column counts as dependent on the others.
const RANK_TOL: f64 = 1e-10;

/// An ordinary least-squares fit y = b₀ + Σ b_j x_j.
#[derive(Debug, Clone)]
pub struct OlsFit {
    pub intercept: f64,
    pub coefficients: Vec<f64>,
    /// Standard errors of [intercept, coefficients…] from σ²(XᵀX)⁻¹, σ² = SSE/(n−p−1).
    pub std_errors: Vec<f64>,
}

/// Ordinary least squares with an intercept, by Householder QR of [1 X].
pub fn ols(x: &DMatrix<f64>, y: &[f64], names: &[String]) -> Result<OlsFit, ThermalError> {
    let (n, p) = x.shape();
    if n <= p + 1 {
        return Err(ThermalError::TooFewRows {
            rows: n,
            params: p + 1,
        });
    }
    let mut a = DMatrix::from_element(n, p + 1, 1.0);
    a.view_mut((0, 1), (n, p)).copy_from(x);
    // column scaling keeps the rank test meaningful for regressors in any unit
    let scale: Vec<f64> = (0..=p)
        .map(|j| a.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    for j in 0..=p {
        a.column_mut(j).scale_mut(1.0 / scale[j]);
    }
    let qr = a.clone().qr();
    let r = qr.r();
    let rmax = (0..=p).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
    let weak: Vec<usize> = (0..=p)
        .filter(|&i| r[(i, i)].abs() <= RANK_TOL * rmax)
        .collect();
    if !weak.is_empty() {
        return Err(ThermalError::RankDeficient {
            rank: p + 1 - weak.len(),
            cols: p + 1,
            names: weak
                .iter()
                .map(|&i| {
                    if i == 0 {
                        "intercept".to_string()
                    } else {
                        names.get(i - 1).cloned().unwrap_or_else(|| format!("x{i}"))
                    }
                })
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    // R b = Qᵀ y  (normal equations solved through the QR factors)
    let mut qty = DVector::from_column_slice(y);
    qr.q_tr_mul(&mut qty);
    let rt = r.view((0, 0), (p + 1, p + 1)).into_owned();
    let b = rt
        .solve_upper_triangular(&qty.rows(0, p + 1).into_owned())
        .ok_or(ThermalError::RankDeficient {
            rank: 0,
            cols: p + 1,
            names: names.join(", "),
        })?;
    let yv = DVector::from_column_slice(y);
    let resid = &yv - &a * &b;
    let sigma2 = resid.norm_squared() / (n - p - 1) as f64;
    // (XᵀX)⁻¹ = R⁻¹R⁻ᵀ
    let rinv = rt
        .solve_upper_triangular(&DMatrix::identity(p + 1, p + 1))
        .expect("R checked non-singular");
    let cov_diag: Vec<f64> = (0..=p).map(|i| rinv.row(i).norm_squared()).collect();
    let coef: Vec<f64> = (0..=p).map(|j| b[j] / scale[j]).collect();
    let se: Vec<f64> = (0..=p)
        .map(|j| (sigma2 * cov_diag[j]).sqrt() / scale[j])
        .collect();
    Ok(OlsFit {
        intercept: coef[0],
        coefficients: coef[1..].to_vec(),
        std_errors: se,
    })
}

/// The standardisation of a design: column means and population standard deviations, and the
/// target's mean and standard deviation.
#[derive(Debug, Clone)]
pub struct Standardisation {
    pub x_mean: Vec<f64>,
    pub x_std: Vec<f64>,
    pub y_mean: f64,
    pub y_std: f64,
}

/// A ridge problem in correlation form, factorised once (SVD of Z/√n) so that the coefficients for
/// any k cost O(p²): the ridge trace evaluates 100 values of k from one factorisation.
#[derive(Debug, Clone)]
pub struct RidgeProblem {
    pub std: Standardisation,
    /// Singular values of Z/√n (their squares are the eigenvalues of the correlation matrix R).
    pub singular: Vec<f64>,
    v: DMatrix<f64>,
    /// Uᵀ(y−ȳ)/(√n s_y)
    uty: DVector<f64>,
}

impl RidgeProblem {
    /// Standardises `x` and `y` and factorises; `names` are used in messages only.
    pub fn new(x: &DMatrix<f64>, y: &[f64], names: &[String]) -> Result<Self, ThermalError> {
        let (n, p) = x.shape();
        if n < 3 || p == 0 {
            return Err(ThermalError::TooFewRows {
                rows: n,
                params: p + 1,
            });
        }
        let nf = n as f64;
        let mut x_mean = Vec::with_capacity(p);
        let mut x_std = Vec::with_capacity(p);
        let columns: Vec<&[f64]> = x.as_slice().chunks_exact(n).collect();
        for (j, col) in columns.iter().enumerate() {
            let (m, ss) = crate::tall_qr::mean_and_ss(col);
            let s = (ss / nf).sqrt();
            if !(s > 1e-12 * m.abs().max(1.0)) {
                return Err(ThermalError::ConstantColumn(
                    names.get(j).cloned().unwrap_or_else(|| format!("x{j}")),
                ));
            }
            x_mean.push(m);
            x_std.push(s);
        }
        let (y_mean, y_ss) = crate::tall_qr::mean_and_ss(y);
        let y_std = (y_ss / nf).sqrt();
        if !(y_std > 0.0) {
            return Err(ThermalError::ConstantColumn("target".into()));
        }
        // SVD of the tall Z = (X − x̄)/(s_x√n) through its QR (Golub & Van Loan 2013, §8.6.3,
        // "R-SVD"): Z = QR, R = U_r Σ Vᵀ, so Z = (Q U_r) Σ Vᵀ and Uᵀy* = U_rᵀ (Qᵀy*)[..p].
        // Neither Z, the n × p U nor Q is formed: the blocked QR standardises as it goes and
        // carries y* = (y − ȳ)/(s_y√n) along as an extra column, which comes out as Qᵀy*
        // (issue 22).
        let mut cols = columns;
        cols.push(y);
        let shift: Vec<f64> = x_mean.iter().copied().chain([y_mean]).collect();
        let scale: Vec<f64> = x_std
            .iter()
            .chain([&y_std])
            .map(|s| 1.0 / (s * nf.sqrt()))
            .collect();
        let rq = crate::tall_qr::tall_r(&cols, &shift, &scale, p);
        let rows = n.min(p); // a wide design (n < p) has only n non-zero rows of R
        let r = DMatrix::from_fn(rows, p, |i, j| rq[i * (p + 1) + j]);
        let qty = DVector::from_fn(rows, |i, _| rq[i * (p + 1) + p]);
        let svd = r.svd(true, true);
        let u = svd.u.expect("u requested");
        let v = svd.v_t.expect("v requested").transpose();
        let uty = u.transpose() * qty;
        Ok(RidgeProblem {
            std: Standardisation {
                x_mean,
                x_std,
                y_mean,
                y_std,
            },
            singular: svd.singular_values.iter().copied().collect(),
            v,
            uty,
        })
    }

    /// Standardised coefficients β*(k) = V diag(σ/(σ²+k)) Uᵀ y*  (Hoerl & Kennard 1970, eq. 2.2 by SVD).
    pub fn standardised(&self, k: f64) -> Result<Vec<f64>, ThermalError> {
        let smax = self.singular.iter().cloned().fold(0.0, f64::max);
        let mut w = DVector::zeros(self.singular.len());
        for (i, s) in self.singular.iter().enumerate() {
            let den = s * s + k;
            if k == 0.0 && *s <= 1e-12 * smax {
                return Err(ThermalError::RankDeficient {
                    rank: self.singular.iter().filter(|s| **s > 1e-12 * smax).count(),
                    cols: self.singular.len(),
                    names: "(exactly collinear sensors; use k > 0)".into(),
                });
            }
            w[i] = s / den * self.uty[i];
        }
        Ok((&self.v * w).iter().copied().collect())
    }

    /// De-standardised equation: (b₀, b) with y ≈ b₀ + Σ b_j x_j.
    pub fn destandardise(&self, beta_std: &[f64]) -> (f64, Vec<f64>) {
        let s = &self.std;
        let b: Vec<f64> = beta_std
            .iter()
            .zip(&s.x_std)
            .map(|(bs, sx)| bs * s.y_std / sx)
            .collect();
        let b0 = s.y_mean - b.iter().zip(&s.x_mean).map(|(b, m)| b * m).sum::<f64>();
        (b0, b)
    }
}

/// Variance inflation factor of each regressor: VIF_j = 1/(1 − R²_j), R²_j from the OLS of x_j on
/// all other regressors with an intercept (the definition statsmodels'
/// `variance_inflation_factor` applies to a design with a constant). An exactly dependent
/// regressor has VIF = ∞.
///
/// Computed from one QR of the centred design X_c = QR: VIF_j = [(X_cᵀX_c)⁻¹]_jj·(X_cᵀX_c)_jj,
/// with (X_cᵀX_c)⁻¹ = R⁻¹R⁻ᵀ (the same number as the auxiliary regressions, p times cheaper).
/// A rank-deficient design falls back to the auxiliary regressions to tell which regressors
/// are the dependent ones.
pub fn vif(x: &DMatrix<f64>, names: &[String]) -> Result<Vec<f64>, ThermalError> {
    let (n, p) = x.shape();
    if n <= p + 1 {
        return Err(ThermalError::TooFewRows {
            rows: n,
            params: p + 1,
        });
    }
    // X_c = X − x̄ is formed block by block inside the QR (`tall_qr`), never as a whole copy
    let nf = n as f64;
    let cols: Vec<&[f64]> = x.as_slice().chunks_exact(n).collect();
    let mean: Vec<f64> = cols.iter().map(|col| crate::tall_qr::mean(col)).collect();
    let rq = crate::tall_qr::tall_r(&cols, &mean, &vec![1.0; p], p);
    // Σ(x_j − x̄_j)² = ‖X_c e_j‖² = ‖R e_j‖² (Q is orthogonal): no second pass over the data
    let ss: Vec<f64> = (0..p)
        .map(|j| (0..=j).map(|i| rq[i * p + j].powi(2)).sum())
        .collect();
    for j in 0..p {
        if ss[j].sqrt() <= 1e-12 * mean[j].abs().max(1.0) * nf.sqrt() {
            return Err(ThermalError::ConstantColumn(names[j].clone()));
        }
    }
    let r = DMatrix::from_fn(p, p, |i, j| rq[i * p + j]);
    let rmax = (0..p).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
    if (0..p).all(|i| r[(i, i)].abs() > RANK_TOL * rmax * 1e3) {
        // VIF_j = [(X_cᵀX_c)⁻¹]_jj (X_cᵀX_c)_jj = ‖row j of R⁻¹‖²·Σ(x_j − x̄_j)²
        if let Some(rinv) = r.solve_upper_triangular(&DMatrix::identity(p, p)) {
            return Ok((0..p).map(|j| rinv.row(j).norm_squared() * ss[j]).collect());
        }
    }
    vif_by_regressions(x, names)
}

/// VIF by the definition: one auxiliary OLS regression per regressor.
pub fn vif_by_regressions(x: &DMatrix<f64>, names: &[String]) -> Result<Vec<f64>, ThermalError> {
    let (n, p) = x.shape();
    let mut out = Vec::with_capacity(p);
    for j in 0..p {
        if p == 1 {
            out.push(1.0);
            continue;
        }
        let others = x.clone().remove_column(j);
        let others_names: Vec<String> = names
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != j)
            .map(|(_, s)| s.clone())
            .collect();
        let xj: Vec<f64> = x.column(j).iter().copied().collect();
        let mean = xj.iter().sum::<f64>() / n as f64;
        let sst: f64 = xj.iter().map(|v| (v - mean).powi(2)).sum();
        if sst <= 0.0 {
            return Err(ThermalError::ConstantColumn(names[j].clone()));
        }
        let r2 = match ols(&others, &xj, &others_names) {
            Ok(fit) => {
                let mut sse = 0.0;
                for i in 0..n {
                    let f = fit.intercept
                        + (0..p - 1)
                            .map(|c| fit.coefficients[c] * others[(i, c)])
                            .sum::<f64>();
                    sse += (xj[i] - f).powi(2);
                }
                1.0 - sse / sst
            }
            Err(ThermalError::RankDeficient { .. }) => {
                // the other regressors are themselves dependent: minimum-norm least squares
                // (SVD) of the centred x_j on the centred others gives the same fitted values
                let mut oc = others.clone();
                for c in 0..p - 1 {
                    let m = oc.column(c).sum() / n as f64;
                    oc.column_mut(c).add_scalar_mut(-m);
                }
                let yc = DVector::from_iterator(n, xj.iter().map(|v| v - mean));
                let svd = oc.clone().svd(true, true);
                let eps = 1e-10 * svd.singular_values.max();
                let b = svd
                    .solve(&yc, eps)
                    .map_err(|e| ThermalError::Invalid(e.to_string()))?;
                1.0 - (&yc - &oc * b).norm_squared() / sst
            }
            Err(e) => return Err(e),
        };
        out.push(if r2 >= 1.0 {
            f64::INFINITY
        } else {
            1.0 / (1.0 - r2)
        });
    }
    Ok(out)
}

/// |β*| above which a standardised coefficient is "large": the feature alone would swing the
/// prediction by this many standard deviations of the drift.
pub const LARGE_STANDARDISED_COEFFICIENT: f64 = 4.0;

/// A warning when large standardised coefficients β*_j (b_j·s_j/s_y) of opposite sign cancel:
/// the prediction is then a small difference of large terms, which amplifies sensor noise and
/// breaks outside the duty cycle it was fitted on (Hoerl & Kennard 1970: the mark of collinearity).
pub fn cancellation_warning(names: &[String], beta_std: &[f64]) -> Option<String> {
    let large: Vec<(usize, f64)> = beta_std
        .iter()
        .enumerate()
        .filter(|(_, b)| b.abs() > LARGE_STANDARDISED_COEFFICIENT || !b.is_finite())
        .map(|(j, b)| (j, *b))
        .collect();
    let pos = large.iter().any(|(_, b)| *b > 0.0);
    let neg = large.iter().any(|(_, b)| *b < 0.0);
    (pos && neg).then(|| {
        let list: Vec<String> = large
            .iter()
            .map(|(j, b)| format!("{} {b:+.1}", names.get(*j).map(|s| s.as_str()).unwrap_or("?")))
            .collect();
        format!(
            "large coefficients of opposite sign cancel (standardised, in standard deviations of the drift: {}): the prediction is a small difference of large terms, which amplifies sensor noise and fails outside the training duty cycle; use fewer sensors or more shrinkage (larger k)",
            list.join(", ")
        )
    })
}

#[cfg(test)]
mod r_svd_tests {
    use super::*;

    /// The trace through QR + SVD of R equals the ridge normal equations (R + kI)β* = r solved
    /// directly (Hoerl & Kennard 1970, eq. 2.2), for tall designs (some longer than one block of
    /// the blocked QR, 128 rows, and one not a multiple of it) and for a wide one (n < p, where R
    /// is n × p).
    #[test]
    fn r_svd_ridge_equals_the_direct_solution() {
        for (n, p) in [(40, 5), (4, 6), (1000, 16), (257, 3)] {
            let x = DMatrix::from_fn(n, p, |i, j| {
                ((i * 7 + j * 13) % 11) as f64 + (i * j) as f64 * 0.1
            });
            let y: Vec<f64> = (0..n)
                .map(|i| (i as f64 * 0.7).sin() + i as f64 * 0.05)
                .collect();
            let names: Vec<String> = (0..p).map(|j| format!("s{j}")).collect();
            let prob = RidgeProblem::new(&x, &y, &names).unwrap();
            // Z, y* as the problem standardises them
            let s = &prob.std;
            let nf = n as f64;
            let z = DMatrix::from_fn(n, p, |i, j| {
                (x[(i, j)] - s.x_mean[j]) / (s.x_std[j] * nf.sqrt())
            });
            let ys = DVector::from_fn(n, |i, _| (y[i] - s.y_mean) / (s.y_std * nf.sqrt()));
            for k in [1e-3, 0.1, 1.0] {
                let a = z.transpose() * &z + DMatrix::identity(p, p) * k;
                let want = a.lu().solve(&(z.transpose() * &ys)).unwrap();
                let got = prob.standardised(k).unwrap();
                for (g, w) in got.iter().zip(want.iter()) {
                    assert!(
                        (g - w).abs() < 1e-9 * (1.0 + w.abs()),
                        "n={n} p={p} k={k}: {got:?} vs {want}"
                    );
                }
            }
        }
    }
}
