//! Latin hypercube sampling (McKay, Beckman & Conover 1979, *Technometrics* 21(2):239–245):
//! n points in [0, 1)^d such that every column has exactly one point in each of the n strata
//! [i/n, (i+1)/n). Point i, column j: x_ij = (π_j(i) + u_ij)/n, π_j an independent random
//! permutation of 0..n per column, u_ij uniform on [0, 1) (their eq. 3.1 with random positions
//! inside the cells).
//!
//! What mtec uses it for: EFAST's search curves are deterministic (a curve, not a sample, covers
//! each input), Sobol's base points are already a low-discrepancy sequence, and Morris moves on a
//! grid, so none of the three estimators takes its design from here. LHS draws the *poses* over
//! which `mtec sensitivity --sampling lhs` aggregates the indices: the workspace is the input
//! that the literature spreads by Latin hypercube when it ranks key geometric errors (every axis
//! covered evenly with few poses), see docs/methods.md.

use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};

/// n Latin-hypercube points in [0, 1)^d (row-major rows of d), deterministic by seed.
pub fn unit(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut rows = vec![vec![0.0; d]; n];
    let mut perm: Vec<usize> = (0..n).collect();
    for j in 0..d {
        perm.shuffle(&mut rng);
        for (i, row) in rows.iter_mut().enumerate() {
            // x_ij = (π_j(i) + u_ij) / n
            row[j] = (perm[i] as f64 + rng.random::<f64>()) / n as f64;
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_column_has_one_point_per_stratum() {
        let n = 37;
        let rows = unit(n, 5, 9);
        for j in 0..5 {
            let mut strata: Vec<usize> = rows
                .iter()
                .map(|r| (r[j] * n as f64).floor() as usize)
                .collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..n).collect::<Vec<_>>(), "column {j}");
        }
    }

    /// For an additive function LHS estimates the mean with a variance of o(1/n) (Stein 1987,
    /// *Technometrics* 29(2):143–151), where plain Monte Carlo has Var f / n: on
    /// f = Σ x_j² over [0, 1)^4 (Var f = 4·4/45), 200 repetitions of n = 20 points.
    #[test]
    fn the_mean_of_an_additive_function_varies_far_less_than_with_monte_carlo() {
        let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
        let (n, reps) = (20, 200);
        let means: Vec<f64> = (0..reps)
            .map(|s| unit(n, 4, s).iter().map(|r| f(r)).sum::<f64>() / n as f64)
            .collect();
        let m = means.iter().sum::<f64>() / reps as f64;
        let var = means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (reps - 1) as f64;
        let mc_var = 4.0 * 4.0 / 45.0 / n as f64;
        println!("mean {m:.5} (exact 4/3), var {var:.2e} vs Monte Carlo {mc_var:.2e}");
        assert!((m - 4.0 / 3.0).abs() < 0.01, "{m}");
        assert!(var < 0.05 * mc_var, "{var} vs {mc_var}");
    }
}
