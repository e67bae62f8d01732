//! Sobol indices by the Saltelli 2010 design with the Saltelli (S1) and Jansen (ST) estimators
//! (Saltelli et al. 2010, "Variance based sensitivity analysis of model output. Design and
//! estimator for the total sensitivity index", Comput. Phys. Commun. 181:259–270).
//!
//! Sampling: two N×D matrices A and B from one 2D-dimensional quasi-random sequence (A = first D
//! coordinates, B = last D), and for each input i the matrix A_B^(i) = A with column i taken
//! from B. Rows are laid out as SALib does (for each base point j: A_j, A_B^(1)_j … A_B^(D)_j,
//! B_j), so N·(D+2) evaluations. The base sequence is the Owen-scrambled Sobol sequence of
//! `sobol_burley` (Burley 2020; Joe–Kuo direction numbers) when N ≤ 2¹⁶ and 2D ≤ 256, otherwise
//! plain pseudo-random points (documented choice: the estimators stay unbiased, only their
//! convergence is slower).
//!
//! Estimators (Table 2 of the paper): V_i = (1/N) Σ_j f(B)_j (f(A_B^(i))_j − f(A)_j)  (S1,
//! Saltelli 2010 eq. (b)), V_Ti = (1/2N) Σ_j (f(A)_j − f(A_B^(i))_j)²  (ST, Jansen 1999, eq. (f)),
//! both divided by the variance of f over A and B together. Confidence intervals by bootstrap
//! over base points: each replicate redraws N base points with replacement; the reported half
//! width is z·sd of the replicates (SALib's convention), and the percentile interval is also kept.

use crate::interval::bootstrap_half_widths;
use crate::problem::{check_outputs, Indices, Problem, Replicates, SampleMatrix};
use crate::SensitivityError;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// Largest base sample count the scrambled Sobol sequence supports.
pub const MAX_SOBOL_POINTS: usize = 1 << 16;

/// Draws the Saltelli 2010 design with N base points: N·(D+2) rows.
pub fn sample(problem: &Problem, n: usize, seed: u64) -> Result<SampleMatrix, SensitivityError> {
    if n < 2 {
        return Err(SensitivityError::Settings(
            "Sobol needs at least 2 base points".into(),
        ));
    }
    let d = problem.dim();
    crate::problem::check_design_size(
        (d + 2).checked_mul(n),
        d,
        &format!("Sobol N = {n} (N·(D + 2) rows)"),
    )?;
    let quasi = n <= MAX_SOBOL_POINTS && 2 * d <= sobol_burley::NUM_DIMENSIONS as usize;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let seed32 = (seed ^ (seed >> 32)) as u32;
    let mut base = vec![0.0; 2 * d];
    let mut data = Vec::with_capacity(n * (d + 2) * d);
    for j in 0..n {
        for (k, u) in base.iter_mut().enumerate() {
            *u = if quasi {
                // f32 output on a 2⁻²⁴ grid: take the cell centre so that u ∈ (0, 1) strictly.
                sobol_burley::sample(j as u32, k as u32, seed32) as f64 + 0.5 / (1u64 << 24) as f64
            } else {
                loop {
                    let u: f64 = rng.random();
                    if u > 0.0 {
                        break u;
                    }
                }
            };
        }
        let (a, b) = base.split_at(d);
        let mut push = |row: &[f64]| {
            let mut r = row.to_vec();
            problem.scale_row(&mut r);
            data.extend_from_slice(&r);
        };
        push(a);
        for i in 0..d {
            let mut ab = a.to_vec();
            ab[i] = b[i];
            push(&ab);
        }
        push(b);
    }
    SampleMatrix::from_rows(d, data)
}

pub use crate::interval::Bootstrap;

/// Sobol indices with bootstrap intervals.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SobolIndices {
    #[serde(flatten)]
    pub indices: Indices,
    /// Percentile bootstrap intervals [low, high] of S1 and ST per input.
    pub s1_interval: Vec<[f64; 2]>,
    pub st_interval: Vec<[f64; 2]>,
}

/// S1 (Saltelli 2010) and ST (Jansen) of every input from the outputs on the rows `rows` of the
/// base points (with repetition allowed: the bootstrap passes resampled row lists).
fn estimate(y: &[f64], d: usize, rows: &[usize]) -> (Vec<f64>, Vec<f64>, f64) {
    let n = rows.len() as f64;
    let stride = d + 2;
    let fa = |j: usize| y[j * stride];
    let fb = |j: usize| y[j * stride + d + 1];
    let fab = |j: usize, i: usize| y[j * stride + 1 + i];
    // Variance of f over A and B together (as SALib: np.r_[A, B].var()).
    let mean = rows.iter().map(|&j| fa(j) + fb(j)).sum::<f64>() / (2.0 * n);
    let var = rows
        .iter()
        .map(|&j| (fa(j) - mean).powi(2) + (fb(j) - mean).powi(2))
        .sum::<f64>()
        / (2.0 * n);
    let mut s1 = vec![0.0; d];
    let mut st = vec![0.0; d];
    for i in 0..d {
        // Saltelli 2010, Table 2 (b): V_i = mean f(B)(f(A_B^i) − f(A))
        let v_i = rows
            .iter()
            .map(|&j| fb(j) * (fab(j, i) - fa(j)))
            .sum::<f64>()
            / n;
        // Jansen 1999, Table 2 (f): V_Ti = mean (f(A) − f(A_B^i))² / 2
        let v_ti = rows
            .iter()
            .map(|&j| (fa(j) - fab(j, i)).powi(2))
            .sum::<f64>()
            / (2.0 * n);
        s1[i] = v_i / var;
        st[i] = v_ti / var;
    }
    (s1, st, var)
}

/// Sobol indices from the outputs `y` of a design drawn by [`sample`] (or SALib's
/// `saltelli`/`sobol` sampler without second order).
pub fn analyze(
    names: &[String],
    y: &[f64],
    bootstrap: &Bootstrap,
) -> Result<SobolIndices, SensitivityError> {
    let d = names.len();
    if d == 0 || y.len() % (d + 2) != 0 {
        return Err(SensitivityError::Outputs(format!(
            "{} outputs are not a multiple of D + 2 = {}",
            y.len(),
            d + 2
        )));
    }
    let n = y.len() / (d + 2);
    check_outputs(y, n * (d + 2))?;
    // Centre the outputs on their overall mean (as SALib does by standardising): the indices
    // are invariant to the shift, but f(B) in the S1 estimator then has mean ≈ 0, which removes
    // the μ·mean(f(A_B) − f(A)) term from the estimator's variance.
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let centred: Vec<f64> = y.iter().map(|v| v - mean).collect();
    let y = &centred[..];
    let all: Vec<usize> = (0..n).collect();
    let (s1, st, variance) = estimate(y, d, &all);
    if variance.is_nan() || variance <= 0.0 {
        return Err(SensitivityError::Outputs(
            "the output does not vary over the design: indices are undefined".into(),
        ));
    }
    let mut out = SobolIndices {
        indices: Indices {
            inputs: names.to_vec(),
            s1,
            st,
            s1_conf: None,
            st_conf: None,
            replicates: None,
            variance,
        },
        s1_interval: Vec::new(),
        st_interval: Vec::new(),
    };
    if bootstrap.active()? {
        let rows: Vec<Vec<usize>> = (0..bootstrap.resamples)
            .map(|k| bootstrap.rows(k, n))
            .collect();
        let reps = replicates_on(y, d, &rows);
        let alpha = (1.0 - bootstrap.confidence) / 2.0;
        let percentiles = |r: &[Vec<f64>]| -> Vec<[f64; 2]> {
            (0..d)
                .map(|i| {
                    let mut v: Vec<f64> = r.iter().map(|x| x[i]).collect();
                    v.sort_by(f64::total_cmp);
                    [percentile(&v, alpha), percentile(&v, 1.0 - alpha)]
                })
                .collect()
        };
        out.s1_interval = percentiles(&reps.s1);
        out.st_interval = percentiles(&reps.st);
        out.indices.s1_conf = Some(bootstrap_half_widths(&reps.s1, bootstrap.confidence));
        out.indices.st_conf = Some(bootstrap_half_widths(&reps.st, bootstrap.confidence));
        out.indices.replicates = Some(reps);
    }
    Ok(out)
}

/// The bootstrap replicates of S1 and ST on given resamplings of the base points: replicate k
/// estimates from the base points `rows[k]` (SALib's `r[:, k]`). Exposed so that a test can feed
/// SALib's own resampling and compare the intervals exactly. `y` is centred on its mean first,
/// as in [`analyze`] (SALib standardises it).
pub fn replicates_on(y: &[f64], d: usize, rows: &[Vec<usize>]) -> Replicates {
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let centred: Vec<f64> = y.iter().map(|v| v - mean).collect();
    let y = &centred[..];
    let (s1, st) = rows
        .par_iter()
        .map(|r| {
            let (a, b, _) = estimate(y, d, r);
            (a, b)
        })
        .unzip();
    Replicates { s1, st }
}

/// Linear-interpolation percentile of sorted values (numpy's default method).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    sorted[lo] + (pos - lo as f64) * (sorted[hi] - sorted[lo])
}
