//! Morris elementary effects (Morris 1991, Technometrics 33(2):161–174) with the μ* measure of
//! Campolongo, Cariboni & Saltelli (2007, Environ. Model. Softw. 22:1509–1518).
//!
//! Sampling: r trajectories of D+1 points on a p-level grid {0, 1/(p−1), …, 1} of the unit
//! hypercube; each trajectory starts at a random grid point and moves one input at a time, in a
//! random order, by ±Δ with Δ = p/(2(p−1)) (Morris's recommended step, p even). Grid values are
//! mapped through the quantile function of each input; for unbounded distributions (normal) the
//! levels 0 and 1 would map to ∓∞, so every unit value u is first moved to the centre of its
//! level cell, ε + (1 − 2ε)·u with ε = 1/(2p) (a documented choice: the design keeps its
//! structure and covers the same probability range as a p-bin histogram).
//!
//! Analysis: the elementary effect of input i on a trajectory is
//! EE_i = (f(x + Δe_i) − f(x)) / Δ  (Morris 1991 eq. 1; Δ in unit-hypercube scale, as SALib),
//! μ = mean EE_i, μ* = mean |EE_i|, σ = standard deviation of EE_i (ddof 1).
//! The confidence interval of μ* is SALib's bootstrap (`_compute_mu_star_confidence`): B
//! replicates each redraw the r trajectories with replacement, μ*_conf = z_{(1+c)/2}·sd of the
//! replicate μ* (see `interval`). One resampling of the trajectories serves every input and
//! every output, so that μ* aggregated over poses has an interval too.

use crate::interval::{bootstrap_half_widths, Bootstrap};
use crate::problem::{check_outputs, Problem, SampleMatrix};
use crate::SensitivityError;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};

/// Morris design settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MorrisSettings {
    /// Number of trajectories r (≥ 2).
    pub trajectories: usize,
    /// Number of grid levels p (even, ≥ 2; default 4).
    pub levels: usize,
    /// Bootstrap of μ*'s interval (SALib's defaults: 100 resamples at 0.95).
    pub bootstrap: Bootstrap,
}

impl Default for MorrisSettings {
    fn default() -> Self {
        MorrisSettings {
            trajectories: 100,
            levels: 4,
            bootstrap: Bootstrap::default(),
        }
    }
}

/// A Morris design: the sample matrix and, per trajectory step, which input moved and by how
/// much in the unit hypercube (needed by the analysis).
#[derive(Debug, Clone, PartialEq)]
pub struct MorrisDesign {
    pub samples: SampleMatrix,
    /// For trajectory t and step k (1..=D): (input index, signed step in unit scale).
    pub steps: Vec<(usize, f64)>,
}

fn check(settings: &MorrisSettings) -> Result<(), SensitivityError> {
    if settings.trajectories < 2 {
        return Err(SensitivityError::Settings(
            "Morris needs at least 2 trajectories".into(),
        ));
    }
    // p = 4 to 10 in practice (Saltelli et al., *Global Sensitivity Analysis: The Primer*,
    // 2008, §3.3); as p grows the step Δ = p/(2(p − 1)) tends to 1/2, half of every range,
    // where a periodic input's effects cancel (Ishigami's x2 then reads as having none)
    if settings.levels < 2 || settings.levels % 2 != 0 || settings.levels > 100 {
        return Err(SensitivityError::Settings(format!(
            "Morris needs an even number of levels from 2 to 100 (got {})",
            settings.levels
        )));
    }
    Ok(())
}

/// Draws r trajectories of D+1 points each.
pub fn sample(
    problem: &Problem,
    settings: &MorrisSettings,
    seed: u64,
) -> Result<MorrisDesign, SensitivityError> {
    check(settings)?;
    let d = problem.dim();
    crate::problem::check_design_size(
        settings.trajectories.checked_mul(d + 1),
        d,
        &format!("Morris r = {} trajectories", settings.trajectories),
    )?;
    let p = settings.levels;
    let delta = p as f64 / (2.0 * (p - 1) as f64);
    let eps = 0.5 / p as f64;
    let unbounded: Vec<bool> = problem
        .distributions
        .iter()
        .map(|d| matches!(d, crate::Distribution::Normal { .. }))
        .collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut data = Vec::with_capacity(settings.trajectories * (d + 1) * d);
    let mut steps = Vec::with_capacity(settings.trajectories * d);
    let lower_levels = p / 2; // levels k/(p−1) with k < p/2 satisfy k/(p−1) + Δ ≤ 1
    for _ in 0..settings.trajectories {
        let mut x: Vec<f64> = Vec::with_capacity(d);
        let mut dir: Vec<f64> = Vec::with_capacity(d);
        for _ in 0..d {
            let base = rng.random_range(0..lower_levels) as f64 / (p - 1) as f64;
            if rng.random::<bool>() {
                x.push(base);
                dir.push(delta);
            } else {
                x.push(base + delta);
                dir.push(-delta);
            }
        }
        let mut order: Vec<usize> = (0..d).collect();
        order.shuffle(&mut rng);
        let mut push = |u: &[f64]| {
            let mut row: Vec<f64> = u
                .iter()
                .zip(&unbounded)
                .map(|(&v, &unb)| if unb { eps + (1.0 - 2.0 * eps) * v } else { v })
                .collect();
            problem.scale_row(&mut row);
            data.extend_from_slice(&row);
        };
        push(&x);
        for &i in &order {
            x[i] += dir[i];
            push(&x);
            steps.push((i, dir[i]));
        }
    }
    Ok(MorrisDesign {
        samples: SampleMatrix::from_rows(d, data)?,
        steps,
    })
}

/// Morris measures of every input.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MorrisIndices {
    pub inputs: Vec<String>,
    pub mu: Vec<f64>,
    pub mu_star: Vec<f64>,
    pub sigma: Vec<f64>,
    /// Bootstrap half width of μ* at the bootstrap's confidence level (none with B < 2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_star_conf: Option<Vec<f64>>,
    /// The bootstrap replicates of μ* (`[k][i]`), for aggregation over poses; not in the JSON.
    #[serde(skip)]
    pub mu_star_replicates: Option<Vec<Vec<f64>>>,
}

/// The elementary effects of every input, `effects[i][t]` on trajectory t (Morris 1991 eq. 1).
pub fn elementary_effects(
    names: &[String],
    design: &MorrisDesign,
    y: &[f64],
) -> Result<Vec<Vec<f64>>, SensitivityError> {
    let d = names.len();
    if d == 0 || design.samples.n_cols != d || design.steps.len() % d != 0 {
        return Err(SensitivityError::Settings(
            "design does not match the inputs".into(),
        ));
    }
    let r = design.steps.len() / d;
    check_outputs(y, r * (d + 1))?;
    let mut effects = vec![Vec::with_capacity(r); d];
    for t in 0..r {
        for k in 0..d {
            let (i, step) = design.steps[t * d + k];
            let before = y[t * (d + 1) + k];
            let after = y[t * (d + 1) + k + 1];
            // Morris 1991 eq. 1: EE_i = (f(x + Δe_i) − f(x)) / Δ
            effects[i].push((after - before) / step);
        }
    }
    Ok(effects)
}

/// μ* of one input's elementary effects on resampled trajectories: replicate k is the mean
/// |EE| over the trajectories `rows[k]` (SALib's `resample_index[k]`).
pub fn mu_star_replicates_on(effects: &[f64], rows: &[Vec<usize>]) -> Vec<f64> {
    rows.iter()
        .map(|r| r.iter().map(|&t| effects[t].abs()).sum::<f64>() / r.len() as f64)
        .collect()
}

/// μ, μ* and σ from the outputs `y` of a design drawn by [`sample`], and μ*'s bootstrap
/// interval.
pub fn analyze(
    names: &[String],
    design: &MorrisDesign,
    y: &[f64],
    bootstrap: &Bootstrap,
) -> Result<MorrisIndices, SensitivityError> {
    let effects = elementary_effects(names, design, y)?;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mu: Vec<f64> = effects.iter().map(|e| mean(e)).collect();
    let mu_star = effects
        .iter()
        .map(|e| e.iter().map(|v| v.abs()).sum::<f64>() / e.len() as f64)
        .collect();
    let sigma = effects
        .iter()
        .zip(&mu)
        .map(|(e, m)| {
            (e.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (e.len() - 1) as f64).sqrt()
        })
        .collect();
    let (mu_star_conf, mu_star_replicates) = if bootstrap.active()? {
        let r = effects[0].len();
        let rows: Vec<Vec<usize>> = (0..bootstrap.resamples)
            .map(|k| bootstrap.rows(k, r))
            .collect();
        let per_input: Vec<Vec<f64>> = effects
            .iter()
            .map(|e| mu_star_replicates_on(e, &rows))
            .collect();
        // transpose to [replicate][input]
        let reps: Vec<Vec<f64>> = (0..rows.len())
            .map(|k| per_input.iter().map(|v| v[k]).collect())
            .collect();
        (
            Some(bootstrap_half_widths(&reps, bootstrap.confidence)),
            Some(reps),
        )
    } else {
        (None, None)
    };
    Ok(MorrisIndices {
        inputs: names.to_vec(),
        mu,
        mu_star,
        sigma,
        mu_star_conf,
        mu_star_replicates,
    })
}
