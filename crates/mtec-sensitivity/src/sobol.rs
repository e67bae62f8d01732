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

use crate::problem::{check_outputs, Indices, Problem, SampleMatrix};
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

/// Settings of the bootstrap of [`analyze`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bootstrap {
    /// Number of bootstrap replicates (0: no intervals).
    pub resamples: usize,
    /// Confidence level of the intervals, e.g. 0.95.
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
    if !(variance > 0.0) {
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
            variance,
        },
        s1_interval: Vec::new(),
        st_interval: Vec::new(),
    };
    if bootstrap.resamples >= 2 {
        if !(bootstrap.confidence > 0.0 && bootstrap.confidence < 1.0) {
            return Err(SensitivityError::Settings(format!(
                "confidence level {} is not in (0, 1)",
                bootstrap.confidence
            )));
        }
        let replicates: Vec<(Vec<f64>, Vec<f64>)> = (0..bootstrap.resamples)
            .into_par_iter()
            .map(|r| {
                let mut rng = rand::rngs::StdRng::seed_from_u64(
                    bootstrap.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ r as u64,
                );
                let rows: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
                let (a, b, _) = estimate(y, d, &rows);
                (a, b)
            })
            .collect();
        let z = crate::distribution::standard_normal_quantile(0.5 + bootstrap.confidence / 2.0);
        let alpha = (1.0 - bootstrap.confidence) / 2.0;
        let summarize = |pick: &dyn Fn(&(Vec<f64>, Vec<f64>)) -> &Vec<f64>| {
            let mut conf = vec![0.0; d];
            let mut interval = vec![[0.0; 2]; d];
            for i in 0..d {
                let mut v: Vec<f64> = replicates.iter().map(|rep| pick(rep)[i]).collect();
                let mean = v.iter().sum::<f64>() / v.len() as f64;
                let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64)
                    .sqrt();
                conf[i] = z * sd;
                v.sort_by(f64::total_cmp);
                interval[i] = [percentile(&v, alpha), percentile(&v, 1.0 - alpha)];
            }
            (conf, interval)
        };
        let (c1, i1) = summarize(&|r| &r.0);
        let (ct, it) = summarize(&|r| &r.1);
        out.indices.s1_conf = Some(c1);
        out.indices.st_conf = Some(ct);
        out.s1_interval = i1;
        out.st_interval = it;
    }
    Ok(out)
}

/// Linear-interpolation percentile of sorted values (numpy's default method).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    sorted[lo] + (pos - lo as f64) * (sorted[hi] - sorted[lo])
}
