//! The command correction: the command `p` at which the machine reaches the target.
//!
//! The machine with volumetric error `e` (µm) goes to `p + e(p)` when commanded to `p`. The
//! command that reaches the target `t` solves `p + e(p)·10⁻³ = t` (mm); the correction is
//! `c = p − t`. Fixed-point iteration `p_{k+1} = t − e(p_k)·10⁻³` converges whenever the error's
//! slope is below 1 µm per mm·10³ — real machines have slopes of µm per metre, so it contracts
//! by ~10⁻⁵ per step and converges in two or three steps. It stops when the step is below
//! [`CONVERGED_MM`] and reports non-convergence (and non-finite model values) as errors.

use crate::ErrorModel;

/// The step below which the command is taken as converged (1 nm).
pub const CONVERGED_MM: f64 = 1e-6;
/// Iterations allowed before non-convergence is reported.
pub const MAX_ITERATIONS: usize = 50;

/// Why no correction could be computed.
#[derive(Debug, Clone, PartialEq)]
pub enum SolveError {
    /// The iteration did not settle; `last_step_mm` is the size of the last step.
    NotConverged { last_step_mm: f64 },
    /// The model returned NaN or infinity at `p_mm`.
    NotFinite { p_mm: [f64; 3] },
    /// The correction is larger than the allowed bound.
    TooLarge { correction_um: f64, max_um: f64 },
}

impl std::fmt::Display for SolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SolveError::NotConverged { last_step_mm } => write!(
                f,
                "the correction did not converge in {MAX_ITERATIONS} iterations (last step {:.3e} mm): the error model is too steep here",
                last_step_mm
            ),
            SolveError::NotFinite { p_mm } => write!(
                f,
                "the error model returned a non-finite value at [{:.4}, {:.4}, {:.4}] mm",
                p_mm[0], p_mm[1], p_mm[2]
            ),
            SolveError::TooLarge {
                correction_um,
                max_um,
            } => write!(
                f,
                "correction of {correction_um:.1} um exceeds --max-correction-um {max_um}"
            ),
        }
    }
}

/// The correction `c` (mm) such that commanding `target + c` puts the tool at `target`:
/// solves `p + e(p)·10⁻³ = target` by fixed-point iteration.
pub fn correction_mm(
    model: &dyn ErrorModel,
    target_mm: [f64; 3],
    max_correction_um: f64,
) -> Result<[f64; 3], SolveError> {
    let mut p = target_mm;
    let mut step = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let e_um = model.error_um(p);
        if !e_um.iter().all(|v| v.is_finite()) {
            return Err(SolveError::NotFinite { p_mm: p });
        }
        // p_{k+1} = t − e(p_k)·1e-3
        let next = [
            target_mm[0] - e_um[0] * 1e-3,
            target_mm[1] - e_um[1] * 1e-3,
            target_mm[2] - e_um[2] * 1e-3,
        ];
        step = (0..3).map(|i| (next[i] - p[i]).abs()).fold(0.0, f64::max);
        p = next;
        if step < CONVERGED_MM {
            let c = [
                p[0] - target_mm[0],
                p[1] - target_mm[1],
                p[2] - target_mm[2],
            ];
            let norm_um = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * 1e3;
            if norm_um > max_correction_um {
                return Err(SolveError::TooLarge {
                    correction_um: norm_um,
                    max_um: max_correction_um,
                });
            }
            return Ok(c);
        }
    }
    Err(SolveError::NotConverged { last_step_mm: step })
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Linear;
    impl ErrorModel for Linear {
        // e = 10 µm + 20 µm/m · x  (a scale error of 20 ppm plus an offset)
        fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
            [10.0 + 0.02 * p[0], -5.0, 0.0]
        }
        fn describe(&self) -> String {
            "linear".into()
        }
    }

    #[test]
    fn linear_error_solved_in_closed_form() {
        // p + (10 + 0.02 p)·1e-3 = t  ⇒  p = (t − 0.01) / 1.00002 (worked by hand)
        let t = 300.0;
        let c = correction_mm(&Linear, [t, 0.0, 0.0], 500.0).unwrap();
        let p_exact = (t - 0.01) / 1.00002;
        assert!((t + c[0] - p_exact).abs() < 1e-9);
        assert!((c[1] - 0.005).abs() < 1e-12);
    }

    struct Steep;
    impl ErrorModel for Steep {
        fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
            [-2000.0 * p[0], 0.0, 0.0] // slope -2 mm/mm: the iteration diverges
        }
        fn describe(&self) -> String {
            "steep".into()
        }
    }

    #[test]
    fn divergence_and_bounds_are_reported() {
        assert!(matches!(
            correction_mm(&Steep, [1.0, 0.0, 0.0], 1e12),
            Err(SolveError::NotConverged { .. })
        ));
        assert!(matches!(
            correction_mm(&Linear, [30000.0, 0.0, 0.0], 500.0),
            Err(SolveError::TooLarge { .. })
        ));
    }
}
