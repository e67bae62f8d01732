//! Levenberg–Marquardt for small networks on the flattened parameter vector.
//!
//! Each iteration solves (Marquardt 1963; Hagan & Menhaj 1994, eq. 12, MATLAB `trainlm`)
//!     (JᵀJ + μ I) Δθ = −Jᵀ e
//! with J = ∂e/∂θ of the residual vector e. A step that lowers the sum of squared errors is
//! accepted and μ ← μ·μ_dec; otherwise μ ← μ·μ_inc and the step is retried. This is written
//! here rather than taken from the `levenberg-marquardt` crate because BPNN training needs to
//! stop on a *validation* criterion between iterations (early stopping), which that crate's
//! run-to-convergence interface does not offer; the linear algebra is nalgebra's Cholesky.

use crate::progress::StopReason;
use nalgebra::{DMatrix, DVector};

/// A least-squares problem: residuals e(θ) and their Jacobian J(θ) = ∂e/∂θ.
pub trait LmProblem {
    fn residuals(&self, theta: &[f64]) -> DVector<f64>;
    fn jacobian(&self, theta: &[f64]) -> DMatrix<f64>;
}

/// Knobs of the damping schedule (MATLAB `trainlm` defaults).
#[derive(Debug, Clone)]
pub struct LmConfig {
    pub max_iterations: usize,
    pub mu_initial: f64,
    pub mu_decrease: f64,
    pub mu_increase: f64,
    pub mu_max: f64,
    /// Stop when ‖Jᵀe‖∞ falls below this.
    pub min_gradient: f64,
}

impl Default for LmConfig {
    fn default() -> Self {
        LmConfig {
            max_iterations: 1000,
            mu_initial: 1e-3,
            mu_decrease: 0.1,
            mu_increase: 10.0,
            mu_max: 1e10,
            min_gradient: 1e-9,
        }
    }
}

/// What the per-iteration callback asks for.
pub enum Control {
    Continue,
    Stop(StopReason),
}

/// Result of a minimisation: the last accepted θ, its SSE, iterations and why it stopped.
#[derive(Debug, Clone)]
pub struct LmOutcome {
    pub theta: Vec<f64>,
    pub sse: f64,
    pub iterations: usize,
    pub stop_reason: StopReason,
}

/// Minimises ½‖e(θ)‖² from `theta0`; `on_iteration(iteration, θ, sse)` runs after every accepted
/// step and may stop the run (early stopping on validation lives there).
pub fn minimise<P: LmProblem>(
    problem: &P,
    theta0: &[f64],
    config: &LmConfig,
    mut on_iteration: impl FnMut(usize, &[f64], f64) -> Control,
) -> LmOutcome {
    let n = theta0.len();
    let mut theta = DVector::from_column_slice(theta0);
    let mut e = problem.residuals(theta.as_slice());
    let mut sse = e.norm_squared();
    let mut mu = config.mu_initial;
    let mut stop_reason = StopReason::MaxIterations(config.max_iterations);
    let mut iterations = 0;
    'outer: for it in 1..=config.max_iterations {
        iterations = it;
        let j = problem.jacobian(theta.as_slice());
        // Jᵀ as its own matrix: the product then goes through nalgebra's packed GEMM
        // (matrixmultiply) instead of one dot product per entry, 3–5× faster for a BPNN's J
        let jt = j.transpose();
        let jtj = &jt * &j;
        let g = &jt * &e; // gradient of ½‖e‖²
        if g.amax() < config.min_gradient {
            stop_reason = StopReason::SmallGradient(config.min_gradient);
            break;
        }
        loop {
            let mut a = jtj.clone();
            for k in 0..n {
                a[(k, k)] += mu;
            }
            let step = match a.cholesky() {
                Some(ch) => ch.solve(&(-&g)),
                None => {
                    mu *= config.mu_increase;
                    if mu > config.mu_max {
                        stop_reason = StopReason::DampingExceeded;
                        break 'outer;
                    }
                    continue;
                }
            };
            let trial = &theta + &step;
            let e_trial = problem.residuals(trial.as_slice());
            let sse_trial = e_trial.norm_squared();
            if sse_trial.is_finite() && sse_trial < sse {
                theta = trial;
                e = e_trial;
                sse = sse_trial;
                mu = (mu * config.mu_decrease).max(1e-20);
                break;
            }
            mu *= config.mu_increase;
            if mu > config.mu_max {
                stop_reason = StopReason::NoFurtherDecrease;
                break 'outer;
            }
        }
        if let Control::Stop(why) = on_iteration(it, theta.as_slice(), sse) {
            stop_reason = why;
            break;
        }
    }
    LmOutcome {
        theta: theta.as_slice().to_vec(),
        sse,
        iterations,
        stop_reason,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares: e = (10(θ1 − θ0²), 1 − θ0), minimum at (1, 1).
    struct Rosenbrock;
    impl LmProblem for Rosenbrock {
        fn residuals(&self, t: &[f64]) -> DVector<f64> {
            DVector::from_vec(vec![10.0 * (t[1] - t[0] * t[0]), 1.0 - t[0]])
        }
        fn jacobian(&self, t: &[f64]) -> DMatrix<f64> {
            DMatrix::from_row_slice(2, 2, &[-20.0 * t[0], 10.0, -1.0, 0.0])
        }
    }

    #[test]
    fn finds_the_rosenbrock_minimum() {
        let out = minimise(
            &Rosenbrock,
            &[-1.2, 1.0],
            &LmConfig::default(),
            |_, _, _| Control::Continue,
        );
        assert!((out.theta[0] - 1.0).abs() < 1e-8, "{out:?}");
        assert!((out.theta[1] - 1.0).abs() < 1e-8, "{out:?}");
        assert!(out.sse < 1e-16);
    }
}
