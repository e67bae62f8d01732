//! Confidence intervals of sensitivity indices: the bootstrap over base samples (Sobol, Morris;
//! Efron & Tibshirani 1993, as SALib does it) and the spread of independent replicates (EFAST).
//!
//! Both give a symmetric half width around the estimate, reported as `*_conf` like SALib:
//! - **bootstrap** (Sobol, Morris): B replicates, each redrawing the N base samples (Sobol base
//!   points, Morris trajectories) with replacement; half width z_{(1+c)/2}·sd_B, with sd_B the
//!   standard deviation (ddof 1) of the B replicate estimates, SALib's "normal" interval
//!   (`Z * S1_boot.std(ddof=1)` in `SALib.analyze.sobol`, `_compute_mu_star_confidence` in
//!   `SALib.analyze.morris`). The estimate itself is the full-sample one.
//! - **replicates** (EFAST): R independent designs (new random phases), estimate = their mean,
//!   half width t_{R−1,(1+c)/2}·sd_R/√R, the Student-t interval of a mean of R i.i.d. estimates
//!   (exact when the replicate estimates are normal).
//!
//! Index estimates aggregated over several poses with fixed weights w_p (Gamboa et al. 2014,
//! see `error_model`) get their interval from the same weighted sum of the per-pose replicate
//! estimates: replicate k of the aggregate is Σ_p w_p S^(k,p) / Σ_p w_p, where the replicates of
//! every pose share the same resampled base samples (the poses share one sample of the inputs).

use crate::SensitivityError;
use rand::{Rng, SeedableRng};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Settings of a bootstrap (Sobol, Morris): SALib's `num_resamples`, `conf_level`, `seed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bootstrap {
    /// Number of bootstrap replicates B (0 or 1: no intervals; SALib's default 100).
    pub resamples: usize,
    /// Confidence level c of the intervals, in (0, 1) (default 0.95).
    pub confidence: f64,
    /// Seed of the replicate draws.
    pub seed: u64,
}

impl Default for Bootstrap {
    fn default() -> Self {
        Bootstrap {
            resamples: 100,
            confidence: 0.95,
            seed: 1,
        }
    }
}

/// Most bootstrap replicates (each holds an estimate of every input).
pub const MAX_RESAMPLES: usize = 10_000;

impl Bootstrap {
    /// Whether intervals are computed (B ≥ 2); checks the confidence level.
    pub fn active(&self) -> Result<bool, SensitivityError> {
        check_confidence(self.confidence)?;
        if self.resamples > MAX_RESAMPLES {
            return Err(SensitivityError::Settings(format!(
                "{} bootstrap resamples: at most {MAX_RESAMPLES} (SALib's default is 100)",
                self.resamples
            )));
        }
        Ok(self.resamples >= 2)
    }

    /// The base samples of replicate `k` of `n`: n indices drawn with replacement from one
    /// generator seeded by (seed, k), so a replicate does not depend on thread scheduling and
    /// every output (pose, channel) of one analysis resamples the same base samples.
    pub fn rows(&self, k: usize, n: usize) -> Vec<usize> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(
            self.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k as u64,
        );
        (0..n).map(|_| rng.random_range(0..n)).collect()
    }
}

/// Refuses a confidence level outside (0, 1).
pub fn check_confidence(c: f64) -> Result<(), SensitivityError> {
    if c > 0.0 && c < 1.0 {
        Ok(())
    } else {
        Err(SensitivityError::Settings(format!(
            "confidence level {c:?} is not in (0, 1)"
        )))
    }
}

/// Sample standard deviation (ddof 1) of column `i` of replicate estimates `reps[k][i]`.
fn column_sd(reps: &[Vec<f64>], i: usize) -> f64 {
    let r = reps.len() as f64;
    let mean = reps.iter().map(|v| v[i]).sum::<f64>() / r;
    (reps.iter().map(|v| (v[i] - mean).powi(2)).sum::<f64>() / (r - 1.0)).sqrt()
}

/// Bootstrap half widths z_{(1+c)/2}·sd_B per index (SALib's normal bootstrap interval).
pub fn bootstrap_half_widths(reps: &[Vec<f64>], confidence: f64) -> Vec<f64> {
    let z = crate::distribution::standard_normal_quantile(0.5 + confidence / 2.0);
    let d = reps.first().map_or(0, Vec::len);
    (0..d).map(|i| z * column_sd(reps, i)).collect()
}

/// Student-t quantile t_{ν}(p) (statrs' inverse CDF).
pub fn student_t_quantile(p: f64, dof: f64) -> f64 {
    StudentsT::new(0.0, 1.0, dof)
        .expect("dof > 0")
        .inverse_cdf(p)
}

/// Replicate half widths t_{R−1,(1+c)/2}·sd_R/√R per index (interval of the mean of R
/// independent replicate estimates).
pub fn replicate_half_widths(reps: &[Vec<f64>], confidence: f64) -> Vec<f64> {
    let r = reps.len() as f64;
    let t = student_t_quantile(0.5 + confidence / 2.0, r - 1.0);
    let d = reps.first().map_or(0, Vec::len);
    (0..d).map(|i| t * column_sd(reps, i) / r.sqrt()).collect()
}

/// Mean per index of replicate estimates.
pub fn replicate_mean(reps: &[Vec<f64>]) -> Vec<f64> {
    let d = reps.first().map_or(0, Vec::len);
    let r = reps.len() as f64;
    (0..d)
        .map(|i| reps.iter().map(|v| v[i]).sum::<f64>() / r)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_match_the_tables() {
        // Student-t table (e.g. NIST/SEMATECH e-Handbook §1.3.6.7.2): t_{0.975} for ν = 9, 4, 1
        for (nu, want) in [(9.0, 2.262157), (4.0, 2.776445), (1.0, 12.706205)] {
            let t = student_t_quantile(0.975, nu);
            assert!((t - want).abs() < 1e-5, "ν = {nu}: {t}");
        }
    }

    #[test]
    fn half_widths_of_known_replicates() {
        // replicates 1, 2, 3 of one index: sd 1, mean 2
        let reps = vec![vec![1.0], vec![2.0], vec![3.0]];
        assert_eq!(replicate_mean(&reps), vec![2.0]);
        let z = bootstrap_half_widths(&reps, 0.95)[0];
        assert!((z - 1.959964).abs() < 1e-5, "{z}");
        let t = replicate_half_widths(&reps, 0.95)[0];
        assert!((t - 4.302653 / 3f64.sqrt()).abs() < 1e-5, "{t}");
        assert!(check_confidence(1.0).is_err() && check_confidence(0.0).is_err());
    }
}
