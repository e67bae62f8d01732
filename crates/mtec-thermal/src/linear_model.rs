//! The linear thermal models: the stored form [`LinearModel`] (y = b₀ + Σ b_j f_j on features:
//! temperatures, lags, rates, heat lags), which every linear kind fits to, and the fitters of the
//! source methods on the sensors — multiple linear regression ([`Mlr`]), ridge regression
//! ([`Ridge`], k by forward folds or given) and ridge-trace sensor selection ([`RidgeSelect`]).
//! The least-squares arithmetic is in [`crate::linear`].

use crate::data::{target_rows, ThermalData};
use crate::error::ThermalError;
use crate::features::{design, fit_time_constants, temp_features, Feature};
use crate::fit::{Fit, Predict};
use crate::linear::{cancellation_warning, ols, RidgeProblem};
use crate::options::BlockSpec;
use crate::select::{k_grid, select_sensors, RidgeTrace, SelectOptions};
use crate::validate::{forward_folds_of, ridge_forward_scores, thin_folds, SELECTION_DT_MIN};
use serde::{Deserialize, Serialize};

/// Which linear method produced a model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinearMethod {
    Mlr,
    Ridge,
    RidgeSelect,
    LagSelect,
    /// Forward-selected temperatures and their first-order lags, ridge k by forward folds.
    LaggedRidge,
    /// Lagged ridge plus lagged heat inputs (spindle power with switched time constants).
    Dynamic,
    /// Partial least squares on the sensors ([`crate::pls`]).
    Pls,
}

/// Standardisation kept with a ridge model (its standardised equation is in these units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RidgeEquation {
    pub k: f64,
    pub standardised_coefficients: Vec<f64>,
    pub x_mean: Vec<f64>,
    pub x_std: Vec<f64>,
    pub y_mean_um: f64,
    pub y_std_um: f64,
}

/// A fitted linear model y = b₀ + Σ b_j f_j on features f_j (temperatures, lags, rates).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinearModel {
    pub method: LinearMethod,
    pub features: Vec<Feature>,
    pub intercept_um: f64,
    /// De-standardised coefficients, µm per feature unit.
    pub coefficients: Vec<f64>,
    /// OLS standard errors of [intercept, coefficients…] (MLR only).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub std_errors: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub ridge: Option<RidgeEquation>,
    /// What the fit found suspicious (grid-edge k, cancelling coefficients, collapse).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub warnings: Vec<String>,
}

/// Standardised coefficients b_j·s_j/s_y of a fitted equation on the rows `rows` of `x`.
fn standardised_of(x: &nalgebra::DMatrix<f64>, y: &[f64], b: &[f64]) -> Vec<f64> {
    let n = y.len() as f64;
    let sd = |v: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = v.collect();
        let m = v.iter().sum::<f64>() / n;
        (v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / n).sqrt()
    };
    let sy = sd(&mut y.iter().copied());
    (0..x.ncols())
        .map(|j| b[j] * sd(&mut x.column(j).iter().copied()) / sy)
        .collect()
}

impl Predict for LinearModel {
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        let x = design(data, &self.features)?;
        Ok((0..x.nrows())
            .map(|i| {
                self.intercept_um
                    + (0..x.ncols())
                        .map(|j| self.coefficients[j] * x[(i, j)])
                        .sum::<f64>()
            })
            .collect())
    }
    fn predictors(&self) -> usize {
        self.features.len()
    }
}

/// Adds a first-order lag feature per sensor and fits the time constants by the forward folds of
/// the training rows (see `features`).
fn with_lags(
    data: &ThermalData,
    rows: &[usize],
    base: Vec<Feature>,
    spec: &BlockSpec,
) -> Result<Vec<Feature>, ThermalError> {
    let mut f = base.clone();
    for b in &base {
        if let Feature::Temp { sensor } = b {
            f.push(Feature::Lag {
                sensor: sensor.clone(),
                tau_min: 30.0,
            });
        }
    }
    let folds = thin_folds(data, &forward_folds_of(data, rows, spec), SELECTION_DT_MIN);
    fit_time_constants(data, rows, &mut f, &folds)?;
    Ok(f)
}

/// The temperature features of `sensors` (all when empty), with their lags when `lag` (time
/// constants by the forward folds of `rows`, blocks by `spec`).
fn sensor_features(
    data: &ThermalData,
    rows: &[usize],
    sensors: &[String],
    lag: bool,
    spec: &BlockSpec,
) -> Result<Vec<Feature>, ThermalError> {
    let features = temp_features(data, sensors)?;
    if lag {
        with_lags(data, rows, features, spec)
    } else {
        Ok(features)
    }
}

/// Multiple linear regression (OLS) on the named sensors (all when empty).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Mlr {
    pub sensors: Vec<String>,
    /// Add a first-order lag of each sensor (τ chosen by forward folds).
    pub lag: bool,
    /// Validation blocks of the τ choice.
    pub blocks: BlockSpec,
}

impl Fit for Mlr {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = &target_rows(data, rows)?;
        let features = sensor_features(data, rows, &self.sensors, self.lag, &self.blocks)?;
        let x = design(data, &features)?.select_rows(rows.iter());
        let names: Vec<String> = features.iter().map(|f| f.name()).collect();
        let fit = ols(&x, y, &names)?;
        let warnings = cancellation_warning(&names, &standardised_of(&x, y, &fit.coefficients))
            .into_iter()
            .collect();
        Ok(LinearModel {
            method: LinearMethod::Mlr,
            features,
            intercept_um: fit.intercept,
            coefficients: fit.coefficients,
            std_errors: Some(fit.std_errors),
            ridge: None,
            warnings,
        })
    }
}

/// How a ridge model's k is chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum KChoice {
    /// Given.
    Fixed(f64),
    /// Where the ridge trace stabilises (the source method, [`RidgeTrace::stable_k`]).
    Trace,
    /// The k of [`k_grid`] with the lowest forward-fold RMSE on the training rows
    /// ([`crate::validate::forward_folds`]); the ridge trace when the rows hold fewer than two
    /// blocks.
    Forward(BlockSpec),
}

/// The k of `ks` with the lowest pooled forward RMSE of the design `features` (None: no fold).
pub fn forward_k(
    data: &ThermalData,
    rows: &[usize],
    features: &[Feature],
    spec: &BlockSpec,
    ks: &[f64],
) -> Result<Option<(f64, f64)>, ThermalError> {
    let folds = thin_folds(data, &forward_folds_of(data, rows, spec), SELECTION_DT_MIN);
    if folds.is_empty() {
        return Ok(None);
    }
    let cols: Vec<Vec<f64>> = features
        .iter()
        .map(|f| f.values(data))
        .collect::<Result<_, _>>()?;
    let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
    let scores = ridge_forward_scores(&refs, data.target_um()?, &folds, ks);
    Ok(scores
        .iter()
        .zip(ks)
        .filter(|((r, _), _)| r.is_finite())
        .min_by(|a, b| a.0 .0.total_cmp(&b.0 .0))
        .map(|((r, _), k)| (*k, *r)))
}

#[allow(clippy::too_many_arguments)]
fn ridge_model(
    method: LinearMethod,
    data: &ThermalData,
    rows: &[usize],
    y: &[f64],
    features: Vec<Feature>,
    k: KChoice,
    opt: SelectOptions,
) -> Result<LinearModel, ThermalError> {
    let x = design(data, &features)?.select_rows(rows.iter());
    let names: Vec<String> = features.iter().map(|f| f.name()).collect();
    let prob = RidgeProblem::new(&x, y, &names)?;
    let grid = k_grid();
    let kmax = grid[grid.len() - 1];
    let mut warnings = Vec::new();
    let by_trace = |warnings: &mut Vec<String>| {
        let (idx, k) = RidgeTrace::compute(&prob, &names, &grid).stable_k(opt.stable_step);
        if idx == grid.len() - 1 {
            warnings.push(format!(
                "ridge: the ridge trace does not settle on the k grid (0, 1e-4 … {kmax}); k = {kmax} is the end of the grid, not a stable point: the sensors are too collinear for this rule (try fewer sensors, or --k)"
            ));
        }
        k
    };
    let k = match k {
        KChoice::Fixed(k) => k,
        KChoice::Trace => by_trace(&mut warnings),
        KChoice::Forward(spec) => match forward_k(data, rows, &features, &spec, &grid)? {
            Some((k, _)) => {
                if k == kmax {
                    warnings.push(format!(
                        "ridge: k = {kmax}, the largest k on the grid, predicts the forward folds best: the data asks for more shrinkage than the grid allows (the model is close to the mean drift); use fewer sensors"
                    ));
                }
                k
            }
            None => by_trace(&mut warnings),
        },
    };
    let beta = prob.standardised(k)?;
    let (b0, b) = prob.destandardise(&beta);
    warnings.extend(cancellation_warning(&names, &beta));
    Ok(LinearModel {
        method,
        features,
        intercept_um: b0,
        coefficients: b,
        std_errors: None,
        ridge: Some(RidgeEquation {
            k,
            standardised_coefficients: beta,
            x_mean: prob.std.x_mean.clone(),
            x_std: prob.std.x_std.clone(),
            y_mean_um: prob.std.y_mean,
            y_std_um: prob.std.y_std,
        }),
        warnings,
    })
}

/// Ridge regression (standardised) on the named sensors; k, when `None`, the grid value that
/// predicts the forward folds of the training rows best (blocks by `blocks`), or where the
/// ridge trace stabilises when the rows hold fewer than two blocks.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Ridge {
    pub sensors: Vec<String>,
    pub k: Option<f64>,
    pub lag: bool,
    pub blocks: BlockSpec,
}

impl Fit for Ridge {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = &target_rows(data, rows)?;
        let features = sensor_features(data, rows, &self.sensors, self.lag, &self.blocks)?;
        ridge_model(
            LinearMethod::Ridge,
            data,
            rows,
            y,
            features,
            match self.k {
                Some(k) => KChoice::Fixed(k),
                None => KChoice::Forward(self.blocks.clone()),
            },
            SelectOptions::default(),
        )
    }
}

/// Ridge-trace sensor selection, then ridge regression on the selected sensors at the chosen k.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct RidgeSelect {
    pub sensors: Vec<String>,
    pub options: SelectOptions,
    pub lag: bool,
}

impl Fit for RidgeSelect {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = &target_rows(data, rows)?;
        let base = temp_features(data, &self.sensors)?;
        let names: Vec<String> = base.iter().map(|f| f.name()).collect();
        let sel = select_sensors(
            &design(data, &base)?.select_rows(rows.iter()),
            y,
            &names,
            self.options,
        )?;
        // blocks: experiments, or eight equal time blocks (ridge-select has no input column)
        let features = sensor_features(data, rows, &sel.selected, self.lag, &BlockSpec::default())?;
        // with lags the selection's k (read without them) no longer applies: the lagged design
        // gets its own k where its ridge trace stabilises
        let k = if self.lag {
            KChoice::Trace
        } else {
            KChoice::Fixed(sel.k)
        };
        let mut m = ridge_model(
            LinearMethod::RidgeSelect,
            data,
            rows,
            y,
            features,
            k,
            self.options,
        )?;
        m.warnings.extend(sel.warnings.iter().cloned());
        Ok(m)
    }
}
