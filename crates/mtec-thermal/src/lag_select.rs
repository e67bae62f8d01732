//! Forward selection of a few sensors with thermal-dynamics features, scored by leaving whole
//! blocks out (beyond the source methods).
//!
//! Each step adds the one sensor, and the form of its feature set, that most lowers the
//! forward-fold RMSE ([`crate::validate::forward_folds`]: fit on the blocks before, score the
//! next) of the OLS model on the training rows: either the temperature alone or the temperature
//! plus its first-order lag with τ from the grid of [`tau_grid`] (a fitted time constant: the one
//! that predicts the next blocks best). Blocks are the time blocks of `block_min`, or the
//! experiments, or the duty-cycle steps of the `input` column
//! ([`crate::validate::duty_cycle_blocks`]). The selection stops at `max_sensors` or when a step
//! improves the score by less than 2 %.
//!
//! Why this criterion: a sensor set chosen on training SSE follows the duty cycle it was fitted
//! on; chosen on the blocks that follow it has to predict one it has not seen, which is the job.
//! (Until issue 17 the score was leave-one-block-out, which let the selection see each block's
//! future: `mlr --lag` scored 1.95 µm there and drifted 59 µm on the next duty cycle.)

use crate::data::{target_rows, ThermalData};
use crate::error::ThermalError;
use crate::features::{design, lag_filter, tau_grid, Feature};
use crate::fit::Fit;
use crate::linear::ols;
use crate::linear_model::{LinearMethod, LinearModel};
use crate::options::BlockSpec;
use crate::validate::{
    forward_folds_of, ridge_forward_scores, thin_folds, ForwardFold, SELECTION_DT_MIN,
};
use serde::{Deserialize, Serialize};

/// A scored candidate step: score, its features, their columns, the sensor index.
type Candidate = (f64, Vec<Feature>, Vec<Vec<f64>>, usize);

/// The fitter (see module docs).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct LagSelect {
    /// Candidate sensors (all when empty).
    pub sensors: Vec<String>,
    pub max_sensors: usize,
    /// Length of a validation block in minutes; `None`: experiments, or the duty-cycle steps
    /// of `input` ([`crate::validate::duty_cycle_blocks`]).
    pub block_min: Option<f64>,
    /// Column whose steps mark the duty cycle (e.g. `spindle_rpm`, attached with
    /// [`crate::heat_input::with_input`]).
    pub input: Option<String>,
}

impl Default for LagSelect {
    fn default() -> Self {
        LagSelect {
            sensors: Vec::new(),
            max_sensors: 3,
            block_min: None,
            input: None,
        }
    }
}

/// Forward-fold RMSE of OLS (k = 0) on the columns `cols` (over every row).
fn forward_score(cols: &[&[f64]], y: &[f64], folds: &[ForwardFold]) -> f64 {
    if folds.is_empty() {
        return f64::INFINITY;
    }
    ridge_forward_scores(cols, y, folds, &[0.0])[0].0
}

impl Fit for LagSelect {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = target_rows(data, rows)?;
        let yall = data.target_um()?;
        let spec = BlockSpec {
            block_min: self.block_min,
            input: self.input.clone(),
        };
        let folds = thin_folds(data, &forward_folds_of(data, rows, &spec), SELECTION_DT_MIN);
        let candidates: Vec<usize> = if self.sensors.is_empty() {
            (0..data.sensor_names.len())
                .filter(|&j| data.sensor_names[j].ends_with("_c"))
                .collect()
        } else {
            self.sensors
                .iter()
                .map(|s| data.sensor_index(s))
                .collect::<Result<_, _>>()?
        };
        let taus = tau_grid();
        let pick = |v: Vec<f64>| -> Vec<f64> { v };
        let mut chosen: Vec<Feature> = Vec::new();
        let mut cols: Vec<Vec<f64>> = Vec::new();
        let mut best_score = f64::INFINITY;
        let mut used: Vec<usize> = Vec::new();
        for _ in 0..self.max_sensors.max(1) {
            let mut best: Option<Candidate> = None;
            for &j in candidates.iter().filter(|j| !used.contains(j)) {
                let name = data.sensor_names[j].clone();
                let t = data.sensor(j);
                let tcol = pick(t.clone());
                let mut options: Vec<(Vec<Feature>, Vec<Vec<f64>>)> = vec![(
                    vec![Feature::Temp {
                        sensor: name.clone(),
                    }],
                    vec![tcol.clone()],
                )];
                for &tau in &taus {
                    options.push((
                        vec![
                            Feature::Temp {
                                sensor: name.clone(),
                            },
                            Feature::Lag {
                                sensor: name.clone(),
                                tau_min: tau,
                            },
                        ],
                        vec![tcol.clone(), pick(lag_filter(data, &t, tau))],
                    ));
                }
                for (feats, new_cols) in options {
                    let all: Vec<&[f64]> = cols
                        .iter()
                        .chain(new_cols.iter())
                        .map(|c| c.as_slice())
                        .collect();
                    let s = forward_score(&all, yall, &folds);
                    if best.as_ref().is_none_or(|b| s < b.0) {
                        best = Some((s, feats, new_cols, j));
                    }
                }
            }
            let Some((s, feats, new_cols, j)) = best else {
                break;
            };
            if !(s < 0.98 * best_score) {
                break;
            }
            best_score = s;
            chosen.extend(feats);
            cols.extend(new_cols);
            used.push(j);
        }
        if chosen.is_empty() {
            return Err(ThermalError::Undetermined(
                "lag selection needs at least two validation blocks (experiments, duty-cycle steps of the input, or --block-min)"
                    .into(),
            ));
        }
        let x = design(data, &chosen)?.select_rows(rows.iter());
        let names: Vec<String> = chosen.iter().map(|f| f.name()).collect();
        let fit = ols(&x, &y, &names)?;
        Ok(LinearModel {
            method: LinearMethod::LagSelect,
            features: chosen,
            intercept_um: fit.intercept,
            coefficients: fit.coefficients,
            std_errors: Some(fit.std_errors),
            ridge: None,
            warnings: Vec::new(),
        })
    }
}

/// OLS on a given feature list (a structure chosen before, e.g. by [`LagSelect`] on the whole
/// training file): validation then refits only the coefficients.
#[derive(Debug, Clone)]
pub struct OlsOnFeatures {
    pub features: Vec<Feature>,
}

impl Fit for OlsOnFeatures {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = target_rows(data, rows)?;
        let x = design(data, &self.features)?.select_rows(rows.iter());
        let names: Vec<String> = self.features.iter().map(|f| f.name()).collect();
        let fit = ols(&x, &y, &names)?;
        Ok(LinearModel {
            method: LinearMethod::LagSelect,
            features: self.features.clone(),
            intercept_um: fit.intercept,
            coefficients: fit.coefficients,
            std_errors: Some(fit.std_errors),
            ridge: None,
            warnings: Vec::new(),
        })
    }
}
