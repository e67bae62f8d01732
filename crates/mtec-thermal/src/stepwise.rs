//! Forward stepwise linear models scored forward in time: the candidate families of `auto`
//! (mlr, ridge, lagged ridge, dynamic) as one fitter with different feature pools.
//!
//! Each step adds the one feature of the pool that most lowers the pooled forward-fold RMSE
//! ([`crate::validate::forward_folds`] on the training rows: fit on the blocks before, score the
//! next) of the ridge regression on the chosen features, at the best k of the family's grid.
//! The selection stops when a step improves the score by less than 2 %, at `2·max_sensors + 3`
//! features, and never uses more than `max_sensors` distinct temperature sensors (the heat input
//! does not count). Then each lag's time constant is refined on the fine grid
//! [`crate::features::tau_grid`] by the same score (the τ and the coefficients are fitted
//! together: every τ tried refits the coefficients), and k is chosen again.
//!
//! Pools (every feature causal and computable on line from the current inputs and one filter
//! state per lag: a streaming evaluator advances them with Δt):
//! - `mlr`: the temperatures, k = 0 (ordinary least squares);
//! - `ridge`: the temperatures, k ∈ [`RIDGE_KS`];
//! - `lagged-ridge`: the temperatures and their first-order lags, τ ∈ [`LAG_TAUS`];
//! - `dynamic`: lagged ridge plus lags of the heat input p = (n/1000)^α of the input column
//!   (α ∈ {1, 1.5, 2}, τ ∈ [`LAG_TAUS`], at rest τ or 3τ: a turning spindle sheds heat faster
//!   than a still one; [`Feature::HeatLag`]).
//!
//! Shrinkage: the ridge families choose k by the forward folds, and every model reports
//! cancelling large coefficients ([`crate::linear::cancellation_warning`]).

use crate::data::{input_column, target_rows, ThermalData};
use crate::error::ThermalError;
use crate::features::{tau_grid, temp_features, Feature};
use crate::fit::Fit;
use crate::linear::{cancellation_warning, RidgeProblem};
use crate::linear_model::{LinearMethod, LinearModel, RidgeEquation};
use crate::options::BlockSpec;
use crate::validate::{
    forward_folds_of, ridge_forward_scores, thin_folds, ForwardFold, SELECTION_DT_MIN,
};
use serde::{Deserialize, Serialize};

/// Time constants (min) of the lag features in the pools.
pub const LAG_TAUS: [f64; 5] = [10.0, 30.0, 90.0, 270.0, 810.0];
/// Exponents α of the heat input p = (n/1000)^α.
pub const HEAT_ALPHAS: [f64; 3] = [1.0, 1.5, 2.0];
/// Rest-to-running time-constant ratios of the heat lags.
pub const REST_FACTORS: [f64; 2] = [1.0, 3.0];
/// Ridge k grid of the ridge families (correlation form).
pub const RIDGE_KS: [f64; 5] = [1e-4, 1e-3, 1e-2, 1e-1, 1.0];

/// A candidate family (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    Mlr,
    Ridge,
    LaggedRidge,
    Dynamic,
}

impl Family {
    pub fn name(self) -> &'static str {
        match self {
            Family::Mlr => "mlr",
            Family::Ridge => "ridge",
            Family::LaggedRidge => "lagged-ridge",
            Family::Dynamic => "dynamic",
        }
    }
    fn ks(self) -> Vec<f64> {
        match self {
            Family::Mlr => vec![0.0],
            _ => RIDGE_KS.to_vec(),
        }
    }
    fn method(self) -> LinearMethod {
        match self {
            Family::Mlr => LinearMethod::Mlr,
            Family::Ridge => LinearMethod::Ridge,
            Family::LaggedRidge => LinearMethod::LaggedRidge,
            Family::Dynamic => LinearMethod::Dynamic,
        }
    }
}

/// The fitter (module docs).
#[derive(Debug, Clone)]
pub struct Stepwise {
    pub family: Family,
    /// Candidate temperature sensors (every `_c` sensor when empty).
    pub sensors: Vec<String>,
    /// Heat-input column (e.g. `spindle_rpm`, attached with [`crate::heat_input::with_input`]):
    /// the `dynamic` pool's input, and the duty-cycle steps of the validation blocks.
    pub input: Option<String>,
    pub max_sensors: usize,
    pub block_min: Option<f64>,
}

/// The pool of a family on `data`.
fn pool(s: &Stepwise, data: &ThermalData) -> Result<Vec<Feature>, ThermalError> {
    let temps = temp_features(data, &s.sensors)?;
    let mut out = temps.clone();
    if matches!(s.family, Family::LaggedRidge | Family::Dynamic) {
        for t in &temps {
            for &tau in &LAG_TAUS {
                out.push(Feature::Lag {
                    sensor: t.sensor().to_string(),
                    tau_min: tau,
                });
            }
        }
    }
    if s.family == Family::Dynamic {
        let input = s.input.as_deref().ok_or_else(|| {
            ThermalError::Invalid("the dynamic family needs a heat-input column (--input)".into())
        })?;
        if input_column(data, input).is_none() {
            return Err(ThermalError::MissingColumn(input.to_string()));
        }
        for &alpha in &HEAT_ALPHAS {
            for &tau in &LAG_TAUS {
                for &r in &REST_FACTORS {
                    out.push(Feature::HeatLag {
                        input: input.to_string(),
                        alpha,
                        tau_min: tau,
                        rest_tau_min: r * tau,
                    });
                }
            }
        }
    }
    Ok(out)
}

/// The temperature sensor a feature reads (`None` for the heat input).
fn temperature_of(f: &Feature) -> Option<&str> {
    match f {
        Feature::HeatLag { .. } => None,
        other => Some(other.sensor()),
    }
}

/// The same feature with another time constant (heat lags keep their rest ratio).
fn with_tau(f: &Feature, tau: f64) -> Option<Feature> {
    match f {
        Feature::Lag { sensor, .. } => Some(Feature::Lag {
            sensor: sensor.clone(),
            tau_min: tau,
        }),
        Feature::HeatLag {
            input,
            alpha,
            tau_min,
            rest_tau_min,
        } => Some(Feature::HeatLag {
            input: input.clone(),
            alpha: *alpha,
            tau_min: tau,
            rest_tau_min: tau * rest_tau_min / tau_min,
        }),
        _ => None,
    }
}

/// Best (pooled forward RMSE, k) of the columns over the grid.
fn score(cols: &[&[f64]], y: &[f64], folds: &[ForwardFold], ks: &[f64]) -> (f64, f64) {
    ridge_forward_scores(cols, y, folds, ks)
        .into_iter()
        .zip(ks)
        .map(|((r, _), k)| (if r.is_finite() { r } else { f64::INFINITY }, *k))
        .fold((f64::INFINITY, ks[0]), |a, b| if b.0 < a.0 { b } else { a })
}

impl Fit for Stepwise {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        if self.max_sensors == 0 {
            return Err(ThermalError::Invalid(
                "max_sensors must be at least 1".into(),
            ));
        }
        let y_rows = target_rows(data, rows)?;
        let yall = data.target_um()?;
        let spec = BlockSpec {
            block_min: self.block_min,
            input: self.input.clone(),
        };
        let folds = thin_folds(data, &forward_folds_of(data, rows, &spec), SELECTION_DT_MIN);
        if folds.is_empty() {
            return Err(ThermalError::Undetermined(format!(
                "{}: forward selection needs at least two validation blocks in the training rows (a longer record, experiments, or --block-min)",
                self.family.name()
            )));
        }
        let ks = self.family.ks();
        let pool = pool(self, data)?;
        let cols: Vec<Vec<f64>> = pool
            .iter()
            .map(|f| f.values(data))
            .collect::<Result<_, _>>()?;
        let max_features = 2 * self.max_sensors + 3;
        let mut chosen: Vec<usize> = Vec::new();
        let (mut best, mut best_k) = (f64::INFINITY, ks[0]);
        while chosen.len() < max_features {
            let sensors: Vec<&str> = chosen
                .iter()
                .filter_map(|&i| temperature_of(&pool[i]))
                .collect();
            let mut step: Option<(f64, f64, usize)> = None;
            for c in 0..pool.len() {
                if chosen.contains(&c) {
                    continue;
                }
                if let Some(t) = temperature_of(&pool[c]) {
                    let mut distinct: Vec<&str> = sensors.clone();
                    distinct.push(t);
                    distinct.sort();
                    distinct.dedup();
                    if distinct.len() > self.max_sensors {
                        continue;
                    }
                }
                let set: Vec<&[f64]> = chosen
                    .iter()
                    .chain(std::iter::once(&c))
                    .map(|&i| cols[i].as_slice())
                    .collect();
                let (r, k) = score(&set, yall, &folds, &ks);
                if step.is_none_or(|s| r < s.0) {
                    step = Some((r, k, c));
                }
            }
            match step {
                Some((r, k, c)) if r < 0.98 * best => {
                    best = r;
                    best_k = k;
                    chosen.push(c);
                }
                _ => break,
            }
        }
        if chosen.is_empty() {
            return Err(ThermalError::Undetermined(format!(
                "{}: no feature could be fitted on the forward folds",
                self.family.name()
            )));
        }
        // refine each time constant on the fine grid, coefficients refitted for every τ
        let mut features: Vec<Feature> = chosen.iter().map(|&i| pool[i].clone()).collect();
        let mut fcols: Vec<Vec<f64>> = chosen.iter().map(|&i| cols[i].clone()).collect();
        for j in 0..features.len() {
            for tau in tau_grid() {
                let Some(f) = with_tau(&features[j], tau) else {
                    break;
                };
                if features.contains(&f) {
                    continue;
                }
                let col = f.values(data)?;
                let set: Vec<&[f64]> = fcols
                    .iter()
                    .enumerate()
                    .map(|(i, c)| if i == j { col.as_slice() } else { c.as_slice() })
                    .collect();
                let (r, k) = score(&set, yall, &folds, &ks);
                if r < best {
                    best = r;
                    best_k = k;
                    features[j] = f;
                    fcols[j] = col;
                }
            }
        }
        // final fit on every training row at the chosen k
        let x = nalgebra::DMatrix::from_fn(rows.len(), features.len(), |r, j| fcols[j][rows[r]]);
        let names: Vec<String> = features.iter().map(|f| f.name()).collect();
        let prob = RidgeProblem::new(&x, &y_rows, &names)?;
        let beta = prob.standardised(best_k)?;
        let (b0, b) = prob.destandardise(&beta);
        let mut warnings: Vec<String> = cancellation_warning(&names, &beta).into_iter().collect();
        if ks.len() > 1 && best_k == ks[ks.len() - 1] {
            warnings.push(format!(
                "{}: k = {best_k}, the largest k on the grid, predicts the forward folds best: the data asks for more shrinkage than the grid allows",
                self.family.name()
            ));
        }
        Ok(LinearModel {
            method: self.family.method(),
            features,
            intercept_um: b0,
            coefficients: b,
            std_errors: None,
            ridge: Some(RidgeEquation {
                k: best_k,
                standardised_coefficients: beta,
                x_mean: prob.std.x_mean.clone(),
                x_std: prob.std.x_std.clone(),
                y_mean_um: prob.std.y_mean,
                y_std_um: prob.std.y_std,
            }),
            warnings,
        })
    }
}
