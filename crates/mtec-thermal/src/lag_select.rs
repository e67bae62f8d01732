//! Forward selection of a few sensors with thermal-dynamics features, scored by leaving whole
//! blocks out (beyond the source methods).
//!
//! Each step adds the one sensor, and the form of its feature set, that most lowers the
//! leave-one-block-out RMSE of the OLS model on the training rows: either the temperature alone
//! or the temperature plus its first-order lag with τ from the grid of [`tau_grid`] (a fitted
//! time constant: the one that predicts the held-out blocks best). Blocks are the time blocks of
//! `block_min` (one run/rest cycle of a duty-cycle test) or, without it, the experiments. The
//! selection stops at `max_sensors` or when a step improves the score by less than 2 %.
//!
//! Why this criterion: a sensor set chosen on training SSE follows the duty cycle it was fitted
//! on; chosen on held-out blocks it has to follow one it has not seen, which is the job.

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::features::{design, lag_filter, tau_grid, Feature};
use crate::linear::ols;
use crate::model::{target_rows, Fit, LinearMethod, LinearModel};
use nalgebra::DMatrix;

/// A scored candidate step: score, its features, their columns, the sensor index.
type Candidate = (f64, Vec<Feature>, Vec<Vec<f64>>, usize);

/// The fitter (see module docs).
#[derive(Debug, Clone)]
pub struct LagSelect {
    /// Candidate sensors (all when empty).
    pub sensors: Vec<String>,
    pub max_sensors: usize,
    /// Length of a validation block in minutes; `None`: one block per experiment.
    pub block_min: Option<f64>,
}

impl Default for LagSelect {
    fn default() -> Self {
        LagSelect {
            sensors: Vec::new(),
            max_sensors: 3,
            block_min: None,
        }
    }
}

/// Block label of every row (time blocks from the record's start, or experiments).
fn block_labels(data: &ThermalData, block_min: Option<f64>) -> Vec<usize> {
    match block_min {
        Some(b) => {
            let t0 = data.time_min.first().copied().unwrap_or(0.0);
            data.time_min
                .iter()
                .map(|t| ((t - t0) / b).floor().max(0.0) as usize)
                .collect()
        }
        None => {
            let exps = data.experiments();
            data.experiment
                .iter()
                .map(|e| exps.iter().position(|x| x == e).unwrap_or(0))
                .collect()
        }
    }
}

/// Leave-one-block-out RMSE of OLS on the columns of `x` (rows already the training rows).
fn block_score(x: &DMatrix<f64>, y: &[f64], labels: &[usize]) -> f64 {
    let mut distinct: Vec<usize> = labels.to_vec();
    distinct.sort();
    distinct.dedup();
    if distinct.len() < 2 {
        return f64::INFINITY;
    }
    let names: Vec<String> = (0..x.ncols()).map(|j| format!("f{j}")).collect();
    let (mut sse, mut n) = (0.0, 0usize);
    for b in distinct {
        let tr: Vec<usize> = (0..y.len()).filter(|&i| labels[i] != b).collect();
        let te: Vec<usize> = (0..y.len()).filter(|&i| labels[i] == b).collect();
        let ytr: Vec<f64> = tr.iter().map(|&i| y[i]).collect();
        let Ok(fit) = ols(&x.select_rows(tr.iter()), &ytr, &names) else {
            return f64::INFINITY;
        };
        for &i in &te {
            let f = fit.intercept
                + (0..x.ncols())
                    .map(|j| fit.coefficients[j] * x[(i, j)])
                    .sum::<f64>();
            sse += (y[i] - f).powi(2);
            n += 1;
        }
    }
    (sse / n as f64).sqrt()
}

impl Fit for LagSelect {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = target_rows(data, rows)?;
        let all_labels = block_labels(data, self.block_min);
        let labels: Vec<usize> = rows.iter().map(|&i| all_labels[i]).collect();
        let candidates: Vec<usize> = if self.sensors.is_empty() {
            (0..data.sensor_names.len()).collect()
        } else {
            self.sensors
                .iter()
                .map(|s| data.sensor_index(s))
                .collect::<Result<_, _>>()?
        };
        let taus = tau_grid();
        let pick = |v: Vec<f64>| -> Vec<f64> { rows.iter().map(|&i| v[i]).collect() };
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
                    let all: Vec<&Vec<f64>> = cols.iter().chain(new_cols.iter()).collect();
                    let x = DMatrix::from_fn(rows.len(), all.len(), |i, c| all[c][i]);
                    let s = block_score(&x, &y, &labels);
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
                "lag selection needs at least two validation blocks (experiments or --block-min)"
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
        })
    }
}
