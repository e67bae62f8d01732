//! Sensor selection by the ridge trace, and the comparison table of the source method.
//!
//! The source (ridge regression for temperature-sensor placement) reads the ridge trace by eye.
//! mtec makes each reading a rule with a number, applied to the standardised coefficients
//! β*_j(k) on the trace grid (k₀ = 0 and 99 values log-spaced from 10⁻⁴ to 1):
//!
//! - **chosen k** (where the coefficients stabilise): let c_i be the angle between the
//!   coefficient vectors β*(k_i) and β*(k_{i+1}) — the trace turning, not shrinking (ridge
//!   shrinks every coefficient as k grows; instability is coefficients trading weight and
//!   changing sign). After the step where c_i peaks (the collinear directions being damped), k is
//!   the first grid value with c_i < `stable_step` (0.01 rad per grid step, i.e. per 10 % change
//!   of k); when the trace never turns faster than that, k is the smallest k > 0 on the grid.
//! - S = max_j |β*_j(k*)| is the scale; coefficient j is **small** when |β*_j(k*)| < `small`·S
//!   (0.15) and **unstable** when its swing over k ≤ k*, max − min of β*_j, exceeds
//!   `unstable`·S (0.5).
//! - rule `stable-small`: drop every sensor that is stable and small;
//!   rule `unstable-to-zero`: drop every sensor that is unstable and small at k* (it fell to zero
//!   quickly as k grew);
//!   rule `unstable`: when neither fired, drop the one sensor with the largest swing;
//!   rule `sign-change` (last resort, when none of the three fired): drop the one sensor whose
//!   coefficient changes sign along the whole trace (k > 0) with the largest swing there. The
//!   swing of the first three rules is read over k ≤ k* only, and k* can be the second grid
//!   point; a coefficient that crosses zero later on the trace is the source's "unstable"
//!   coefficient all the same (Hoerl & Kennard read sign changes as the mark of collinearity).
//!   Added because spindle-sensors seed 3 stopped at five sensors with s7 going from −0.14 to
//!   +0.15 along the trace.
//! - repeat on the remaining sensors (new trace, new k*) until no rule fires.
//!
//! Tried and rejected on the `spindle-sensors` scenario over seeds 1–8: dropping one sensor per
//! step instead of all that a rule names, lower thresholds, and continuing while max VIF > 10 —
//! the last always ends at two sensors and loses test accuracy. Also rejected (second round):
//! `stable_step` 0.005/0.015/0.02, `small` 0.2/0.25, `unstable` 0.3; k* as "the trace never turns
//! faster than `stable_step` again" or "stays below it for 5/10/25 grid steps"; one k* from the
//! full trace for every step; the swing read without k = 0; the final k by generalised
//! cross-validation. Each fixed one seed and broke others: the selection among near-equivalent
//! collinear subsets is decided by sampling noise of a 120-row run, not by a threshold.
//!
//! Known limit (measured on seeds 1–8, see `tests/scenarios.rs`): a sensor that carries no drift
//! but moves with one that does over the whole training run (spindle-sensors: the rear bearing
//! s4 with the front bearing s1 while the spindle never stops) gets a stable, equal share of the
//! ridge trace and is kept; no rule can drop it, because the run holds no information that tells
//! the two apart. Seeds 3 and 7 keep s4 and predict the unseen duty cycle (with a stop) 12–14 %
//! worse than the full model; without s4 they are within 6 %. Train on a run that also stops the
//! spindle (or contains whatever separates the sensors) when selecting sensors for a machine.
//!
//! The comparison table then fits: the full MLR (all sensors), the ridge model at the final k*
//! on the selected sensors, and the MLR on the n sensors with the largest simple correlation
//! |r(T_j, y)| (n = number of selected sensors).

use crate::error::ThermalError;
use crate::linear::{ols, vif, RidgeProblem};
use crate::metrics::Metrics;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Number of k values on the ridge trace.
pub const TRACE_POINTS: usize = 100;

/// Thresholds of the ridge-trace rules (module docs).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct SelectOptions {
    pub stable_step: f64,
    pub small: f64,
    pub unstable: f64,
}

impl Default for SelectOptions {
    fn default() -> Self {
        SelectOptions {
            stable_step: 0.01,
            small: 0.15,
            unstable: 0.5,
        }
    }
}

/// The trace grid: 0, then 99 values log-spaced over [1e-4, 1].
pub fn k_grid() -> Vec<f64> {
    let mut ks = vec![0.0];
    let m = TRACE_POINTS - 1;
    for i in 0..m {
        ks.push(10f64.powf(-4.0 + 4.0 * i as f64 / (m - 1) as f64));
    }
    ks
}

/// Standardised ridge coefficients of every sensor at every k.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RidgeTrace {
    pub sensors: Vec<String>,
    pub k: Vec<f64>,
    /// `coefficients[i][j]`: sensor j at k[i].
    pub coefficients: Vec<Vec<f64>>,
}

impl RidgeTrace {
    /// Computes the trace from one factorisation. At k = 0 an exactly singular design gives the
    /// minimum-norm limit instead of failing.
    pub fn compute(problem: &RidgeProblem, sensors: &[String], ks: &[f64]) -> RidgeTrace {
        let coefficients = ks
            .iter()
            .map(|&k| {
                problem
                    .standardised(k)
                    .or_else(|_| problem.standardised(1e-12))
                    .expect("positive k never fails")
            })
            .collect();
        RidgeTrace {
            sensors: sensors.to_vec(),
            k: ks.to_vec(),
            coefficients,
        }
    }

    /// The k where the coefficients stabilise (module docs) and its grid index.
    pub fn stable_k(&self, stable_step: f64) -> (usize, f64) {
        let m = self.k.len();
        // c_i: angle (rad) between β*(k_i) and β*(k_{i+1}); pure shrinkage does not turn it
        let c: Vec<f64> = (0..m - 1)
            .map(|i| {
                let a = &self.coefficients[i];
                let b = &self.coefficients[i + 1];
                let na = a.iter().map(|v| v * v).sum::<f64>().sqrt();
                let nb = b.iter().map(|v| v * v).sum::<f64>().sqrt();
                let cos = a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() / (na * nb).max(1e-300);
                cos.clamp(-1.0, 1.0).acos()
            })
            .collect();
        let peak = (0..c.len())
            .max_by(|&i, &j| c[i].total_cmp(&c[j]))
            .unwrap_or(0);
        if c[peak] < stable_step {
            return (1, self.k[1]);
        }
        let idx = (peak + 1..c.len())
            .find(|&i| c[i] < stable_step)
            .unwrap_or(m - 1);
        (idx, self.k[idx])
    }

    /// CSV text: `k,<sensor>…` with one row per k.
    pub fn to_csv(&self) -> String {
        let header = std::iter::once("k").chain(self.sensors.iter().map(|s| s.as_str()));
        let mut w = mtec_io::CsvWriter::new(header);
        for (k, row) in self.k.iter().zip(&self.coefficients) {
            let k = format!("{k:.6e}");
            w.row(std::iter::once(k).chain(row.iter().map(|v| format!("{v:.9e}"))));
        }
        w.finish()
    }
}

/// One elimination step: which rule removed which sensors, at which k.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EliminationStep {
    pub rule: String,
    pub removed: Vec<String>,
    pub k: f64,
    /// Standardised coefficient of each removed sensor at k and its swing over k ≤ k*.
    pub coefficient_at_k: Vec<f64>,
    pub swing: Vec<f64>,
    pub remaining: Vec<String>,
}

/// One row of the comparison table.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ComparisonRow {
    pub model: String,
    pub sensors: Vec<String>,
    pub metrics: Metrics,
}

/// VIF of one sensor.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct VifRow {
    pub sensor: String,
    /// `None` means infinite (exactly dependent).
    pub vif: Option<f64>,
    pub severe: bool,
}

/// Everything `mtec thermal select` reports.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Selection {
    pub vif: Vec<VifRow>,
    pub trace: RidgeTrace,
    pub steps: Vec<EliminationStep>,
    pub selected: Vec<String>,
    pub k: f64,
    /// The standardised and the de-standardised equation of the selected ridge model.
    pub standardised_coefficients: Vec<f64>,
    pub intercept_um: f64,
    pub coefficients: Vec<f64>,
    pub comparison: Vec<ComparisonRow>,
    pub options: SelectOptions,
    /// The selection explains much less than all sensors did (see [`COLLAPSE_R2_DROP`]).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub warnings: Vec<String>,
}

/// Fall of the training R² (full MLR → ridge-selected) above which the selection is reported as
/// a collapse: the rules removed sensors that carried the drift.
pub const COLLAPSE_R2_DROP: f64 = 0.1;

/// The collapse warning of a comparison table (full MLR row first, ridge-selected second).
fn collapse_warning(comparison: &[ComparisonRow]) -> Option<String> {
    let full = comparison.iter().find(|r| r.model == "full MLR")?;
    let sel = comparison
        .iter()
        .find(|r| r.model.starts_with("ridge-selected"))?;
    let (a, b) = (full.metrics.r2?, sel.metrics.r2?);
    (a - b > COLLAPSE_R2_DROP).then(|| {
        format!(
            "ridge-select collapsed: the {} selected sensors ({}) explain R² = {b:.2} of the training drift against {a:.2} with all {} sensors; the ridge-trace rules removed sensors that carry the drift (use lag-select, --model auto, or choose sensors yourself)",
            sel.sensors.len(),
            sel.sensors.join(", "),
            full.sensors.len()
        )
    })
}

fn columns(x: &DMatrix<f64>, idx: &[usize]) -> DMatrix<f64> {
    x.select_columns(idx.iter())
}

fn predict_linear(x: &DMatrix<f64>, b0: f64, b: &[f64]) -> Vec<f64> {
    (0..x.nrows())
        .map(|i| b0 + (0..b.len()).map(|j| b[j] * x[(i, j)]).sum::<f64>())
        .collect()
}

/// VIF table of all regressors.
pub fn vif_table(x: &DMatrix<f64>, names: &[String]) -> Result<Vec<VifRow>, ThermalError> {
    Ok(vif(x, names)?
        .into_iter()
        .zip(names)
        .map(|(v, s)| VifRow {
            sensor: s.clone(),
            vif: v.is_finite().then_some(v),
            severe: !v.is_finite() || v > 10.0,
        })
        .collect())
}

/// Runs the ridge-trace elimination on regressors `x` (columns named `names`) against `y`.
pub fn select_sensors(
    x: &DMatrix<f64>,
    y: &[f64],
    names: &[String],
    opt: SelectOptions,
) -> Result<Selection, ThermalError> {
    let ks = k_grid();
    let vif_rows = vif_table(x, names)?;
    let full_problem = RidgeProblem::new(x, y, names)?;
    let full_trace = RidgeTrace::compute(&full_problem, names, &ks);
    let mut keep: Vec<usize> = (0..names.len()).collect();
    let mut steps = Vec::new();
    loop {
        let kn: Vec<String> = keep.iter().map(|&j| names[j].clone()).collect();
        let prob = RidgeProblem::new(&columns(x, &keep), y, &kn)?;
        let trace = RidgeTrace::compute(&prob, &kn, &ks);
        let (ik, k) = trace.stable_k(opt.stable_step);
        if keep.len() == 1 {
            break;
        }
        let at_k = &trace.coefficients[ik];
        let scale = at_k.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
        let swing: Vec<f64> = (0..keep.len())
            .map(|j| {
                let vals = trace.coefficients[..=ik].iter().map(|r| r[j]);
                let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(v), h.max(v))
                });
                hi - lo
            })
            .collect();
        let small: Vec<bool> = at_k.iter().map(|b| b.abs() < opt.small * scale).collect();
        let unstable: Vec<bool> = swing.iter().map(|s| *s > opt.unstable * scale).collect();
        let mut drop: Vec<usize> = Vec::new();
        let mut rule = "";
        for (name, test) in [
            (
                "stable-small",
                (|s: bool, u: bool| s && !u) as fn(bool, bool) -> bool,
            ),
            ("unstable-to-zero", |s, u| s && u),
        ] {
            drop = (0..keep.len())
                .filter(|&j| test(small[j], unstable[j]))
                .collect();
            if !drop.is_empty() {
                rule = name;
                break;
            }
        }
        if drop.is_empty() {
            if let Some(j) = (0..keep.len())
                .filter(|&j| unstable[j])
                .max_by(|&a, &b| swing[a].total_cmp(&swing[b]))
            {
                drop = vec![j];
                rule = "unstable";
            }
        }
        if drop.is_empty() {
            // last resort (module docs): a coefficient that changes sign along the trace
            if let Some(j) = (0..keep.len())
                .filter(|&j| trace_sign_change(&trace, j))
                .max_by(|&a, &b| trace_swing(&trace, a).total_cmp(&trace_swing(&trace, b)))
            {
                drop = vec![j];
                rule = "sign-change";
            }
        }
        if drop.is_empty() {
            break;
        }
        if drop.len() == keep.len() {
            // never drop everything: keep the largest coefficient
            let best = (0..keep.len())
                .max_by(|&a, &b| at_k[a].abs().total_cmp(&at_k[b].abs()))
                .unwrap_or(0);
            drop.retain(|&j| j != best);
        }
        let removed: Vec<String> = drop.iter().map(|&j| kn[j].clone()).collect();
        let step_coef = drop.iter().map(|&j| at_k[j]).collect();
        let step_swing = drop.iter().map(|&j| swing[j]).collect();
        keep = keep
            .iter()
            .enumerate()
            .filter(|(j, _)| !drop.contains(j))
            .map(|(_, &c)| c)
            .collect();
        steps.push(EliminationStep {
            rule: rule.to_string(),
            removed,
            k,
            coefficient_at_k: step_coef,
            swing: step_swing,
            remaining: keep.iter().map(|&j| names[j].clone()).collect(),
        });
    }
    let selected: Vec<String> = keep.iter().map(|&j| names[j].clone()).collect();
    let xs = columns(x, &keep);
    let prob = RidgeProblem::new(&xs, y, &selected)?;
    let sel_trace = RidgeTrace::compute(&prob, &selected, &ks);
    let (_, k) = sel_trace.stable_k(opt.stable_step);
    let beta_std = prob.standardised(k)?;
    let (b0, b) = prob.destandardise(&beta_std);

    // comparison table
    let mut comparison = Vec::new();
    match ols(x, y, names) {
        Ok(full) => comparison.push(ComparisonRow {
            model: "full MLR".into(),
            sensors: names.to_vec(),
            metrics: Metrics::new(
                y,
                &predict_linear(x, full.intercept, &full.coefficients),
                names.len(),
            ),
        }),
        Err(ThermalError::RankDeficient { .. }) => {}
        Err(e) => return Err(e),
    }
    comparison.push(ComparisonRow {
        model: format!("ridge-selected (k = {k:.4})"),
        sensors: selected.clone(),
        metrics: Metrics::new(y, &predict_linear(&xs, b0, &b), keep.len()),
    });
    let top = correlation_top_n(x, y, keep.len());
    let xt = columns(x, &top);
    let top_names: Vec<String> = top.iter().map(|&j| names[j].clone()).collect();
    if let Ok(fit) = ols(&xt, y, &top_names) {
        comparison.push(ComparisonRow {
            model: format!("simple-correlation top-{}", top.len()),
            sensors: top_names,
            metrics: Metrics::new(
                y,
                &predict_linear(&xt, fit.intercept, &fit.coefficients),
                top.len(),
            ),
        });
    }
    let warnings = collapse_warning(&comparison).into_iter().collect();
    Ok(Selection {
        warnings,
        vif: vif_rows,
        trace: full_trace,
        steps,
        selected,
        k,
        standardised_coefficients: beta_std,
        intercept_um: b0,
        coefficients: b,
        comparison,
        options: opt,
    })
}

/// Whether coefficient j changes sign along the trace for k > 0 (k = 0, OLS, is left out: with
/// near-dependent sensors its coefficients are noise).
fn trace_sign_change(trace: &RidgeTrace, j: usize) -> bool {
    let v = trace.coefficients[1..].iter().map(|r| r[j]);
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
        (l.min(x), h.max(x))
    });
    lo < 0.0 && hi > 0.0
}

/// max − min of coefficient j along the trace for k > 0.
fn trace_swing(trace: &RidgeTrace, j: usize) -> f64 {
    let v = trace.coefficients[1..].iter().map(|r| r[j]);
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
        (l.min(x), h.max(x))
    });
    hi - lo
}

/// Indices of the `n` regressors with the largest |Pearson correlation| with y (ties by order).
pub fn correlation_top_n(x: &DMatrix<f64>, y: &[f64], n: usize) -> Vec<usize> {
    let m = y.len() as f64;
    let ym = y.iter().sum::<f64>() / m;
    let mut r: Vec<(usize, f64)> = (0..x.ncols())
        .map(|j| {
            let c = x.column(j);
            let xm = c.sum() / m;
            let sxy: f64 = c.iter().zip(y).map(|(a, b)| (a - xm) * (b - ym)).sum();
            let sxx: f64 = c.iter().map(|a| (a - xm).powi(2)).sum();
            let syy: f64 = y.iter().map(|b| (b - ym).powi(2)).sum();
            (j, (sxy / (sxx * syy).sqrt()).abs())
        })
        .collect();
    r.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut idx: Vec<usize> = r.into_iter().take(n).map(|(j, _)| j).collect();
    idx.sort();
    idx
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(model: &str, sensors: usize, r2: f64) -> ComparisonRow {
        // y = [1, -1], ŷ chosen so that R² = r2 (SST = 2, SSE = 2(1 − r2))
        let e = (1.0 - r2).sqrt();
        ComparisonRow {
            model: model.into(),
            sensors: (0..sensors).map(|j| format!("t{j}")).collect(),
            metrics: Metrics::new(&[1.0, -1.0], &[1.0 - e, -1.0 + e], sensors),
        }
    }

    #[test]
    fn a_collapse_of_r2_warns_and_a_small_fall_does_not() {
        let w = collapse_warning(&[
            row("full MLR", 16, 0.94),
            row("ridge-selected (k = 0.1)", 2, 0.37),
        ])
        .expect("0.94 → 0.37 is a collapse");
        assert!(
            w.contains("R² = 0.37") && w.contains("0.94") && w.contains("16 sensors"),
            "{w}"
        );
        assert!(collapse_warning(&[
            row("full MLR", 16, 0.94),
            row("ridge-selected (k = 0.1)", 3, 0.90)
        ])
        .is_none());
    }
}
