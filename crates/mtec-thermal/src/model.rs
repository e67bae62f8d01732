//! The common fit/predict interface (linfa style: a fitter is a value with its options, `fit`
//! returns a model, a model `predict`s), the linear thermal models, and the versioned JSON file.

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::exp_ambient::ExpAmbientModel;
use crate::features::{design, fit_time_constants, temp_features, Feature};
use crate::linear::{ols, RidgeProblem};
use crate::metrics::Metrics;
use crate::select::{k_grid, select_sensors, RidgeTrace, SelectOptions};
use serde::{Deserialize, Serialize};

/// The format tag of a model file.
pub const MODEL_FORMAT: &str = "mtec.thermal-model/1";

/// Something that fits a thermal model to data (options live in the fitter).
pub trait Fit {
    type Model: Predict;
    /// Fits to the rows `rows` of `data` (the target must be present). Features that look back
    /// in time (lags, rates) are computed on the whole record first, so leaving a block out of
    /// the fit does not break their history.
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<Self::Model, ThermalError>;
    /// Fits to every row of `data`.
    fn fit(&self, data: &ThermalData) -> Result<Self::Model, ThermalError> {
        self.fit_rows(data, &(0..data.len()).collect::<Vec<_>>())
    }
}

/// A fitted thermal model.
pub trait Predict {
    /// Predicted drift (µm) for every row of `data`.
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError>;
    /// Number of regressors (for adjusted R² and F).
    fn predictors(&self) -> usize;
    /// Metrics against the target of `data`.
    fn evaluate(&self, data: &ThermalData) -> Result<Metrics, ThermalError> {
        let y = data.target_um()?;
        Ok(Metrics::new(y, &self.predict(data)?, self.predictors()))
    }
}

/// Which linear method produced a model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinearMethod {
    Mlr,
    Ridge,
    RidgeSelect,
    LagSelect,
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

/// Adds a first-order lag feature per sensor and fits the time constants (see `features`).
fn with_lags(
    data: &ThermalData,
    rows: &[usize],
    base: Vec<Feature>,
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
    fit_time_constants(data, rows, &mut f)?;
    Ok(f)
}

/// The temperature features of `sensors` (all when empty), with their fitted lags when `lag`.
fn sensor_features(
    data: &ThermalData,
    rows: &[usize],
    sensors: &[String],
    lag: bool,
) -> Result<Vec<Feature>, ThermalError> {
    let features = temp_features(data, sensors)?;
    if lag {
        with_lags(data, rows, features)
    } else {
        Ok(features)
    }
}

/// The target on the given rows.
pub fn target_rows(data: &ThermalData, rows: &[usize]) -> Result<Vec<f64>, ThermalError> {
    let y = data.target_um()?;
    Ok(rows.iter().map(|&i| y[i]).collect())
}

/// Multiple linear regression (OLS) on the named sensors (all when empty).
#[derive(Debug, Clone, Default)]
pub struct Mlr {
    pub sensors: Vec<String>,
    /// Add a fitted first-order lag of each sensor.
    pub lag: bool,
}

impl Fit for Mlr {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = &target_rows(data, rows)?;
        let features = sensor_features(data, rows, &self.sensors, self.lag)?;
        let x = design(data, &features)?.select_rows(rows.iter());
        let names: Vec<String> = features.iter().map(|f| f.name()).collect();
        let fit = ols(&x, y, &names)?;
        Ok(LinearModel {
            method: LinearMethod::Mlr,
            features,
            intercept_um: fit.intercept,
            coefficients: fit.coefficients,
            std_errors: Some(fit.std_errors),
            ridge: None,
        })
    }
}

fn ridge_model(
    method: LinearMethod,
    data: &ThermalData,
    rows: &[usize],
    y: &[f64],
    features: Vec<Feature>,
    k: Option<f64>,
    opt: SelectOptions,
) -> Result<LinearModel, ThermalError> {
    let x = design(data, &features)?.select_rows(rows.iter());
    let names: Vec<String> = features.iter().map(|f| f.name()).collect();
    let prob = RidgeProblem::new(&x, y, &names)?;
    let k = match k {
        Some(k) => k,
        None => {
            RidgeTrace::compute(&prob, &names, &k_grid())
                .stable_k(opt.stable_step)
                .1
        }
    };
    let beta = prob.standardised(k)?;
    let (b0, b) = prob.destandardise(&beta);
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
    })
}

/// Ridge regression (standardised) on the named sensors; k from the ridge trace when `None`.
#[derive(Debug, Clone, Default)]
pub struct Ridge {
    pub sensors: Vec<String>,
    pub k: Option<f64>,
    pub lag: bool,
}

impl Fit for Ridge {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let y = &target_rows(data, rows)?;
        let features = sensor_features(data, rows, &self.sensors, self.lag)?;
        ridge_model(
            LinearMethod::Ridge,
            data,
            rows,
            y,
            features,
            self.k,
            SelectOptions::default(),
        )
    }
}

/// Ridge-trace sensor selection, then ridge regression on the selected sensors at the chosen k.
#[derive(Debug, Clone, Default)]
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
        let features = sensor_features(data, rows, &sel.selected, self.lag)?;
        // with lags the selection's k (read without them) no longer applies: the lagged design
        // gets its own k where its ridge trace stabilises
        let k = if self.lag { None } else { Some(sel.k) };
        ridge_model(
            LinearMethod::RidgeSelect,
            data,
            rows,
            y,
            features,
            k,
            self.options,
        )
    }
}

/// The exp-ambient feed-axis model fitter (see [`crate::exp_ambient`]).
#[derive(Debug, Clone, Default)]
pub struct ExpAmbient {
    pub up_sensor: String,
    pub nut_sensor: String,
    /// When not empty, ΔT_up is the first principal component of these sensors' rises (and
    /// `up_sensor` is ignored).
    pub up_sensors: Vec<String>,
    /// Likewise for ΔT_nut.
    pub nut_sensors: Vec<String>,
}

impl Fit for ExpAmbient {
    type Model = ExpAmbientModel;
    fn fit_rows(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> Result<ExpAmbientModel, ThermalError> {
        let pick = |group: &[String], one: &str| {
            if group.is_empty() {
                vec![one.to_string()]
            } else {
                group.to_vec()
            }
        };
        ExpAmbientModel::fit_groups(
            &data.rows(rows),
            &pick(&self.up_sensors, &self.up_sensor),
            &pick(&self.nut_sensors, &self.nut_sensor),
        )
    }
}

impl Predict for ExpAmbientModel {
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        ExpAmbientModel::predict(self, data)
    }
    fn predictors(&self) -> usize {
        self.parameters()
    }
}

/// Any thermal model mtec can store.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum ThermalModel {
    Linear(LinearModel),
    /// Boxed: the model carries many coefficient vectors (keeps the enum small).
    ExpAmbient(Box<ExpAmbientModel>),
    HeatInput(crate::heat_input::HeatInputModel),
}

impl Predict for ThermalModel {
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        match self {
            ThermalModel::Linear(m) => m.predict(data),
            ThermalModel::ExpAmbient(m) => m.predict(data),
            ThermalModel::HeatInput(m) => m.predict(data),
        }
    }
    fn predictors(&self) -> usize {
        match self {
            ThermalModel::Linear(m) => m.predictors(),
            ThermalModel::ExpAmbient(m) => m.predictors(),
            ThermalModel::HeatInput(m) => m.predictors(),
        }
    }
}

/// Which rows a model was trained (and tested) on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Split {
    pub train_experiments: Vec<String>,
    pub test_experiments: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub train_until_min: Option<f64>,
    pub train_rows: usize,
    pub test_rows: usize,
}

/// The JSON model file: `{"format": "mtec.thermal-model/1", "target": …, "model": {…}, …}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    pub format: String,
    pub target: String,
    pub model: ThermalModel,
    pub split: Split,
    pub train_metrics: Metrics,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub test_metrics: Option<Metrics>,
}

impl ModelFile {
    /// Checks the format tag after reading.
    pub fn check_format(&self) -> Result<(), ThermalError> {
        if self.format != MODEL_FORMAT {
            return Err(ThermalError::Invalid(format!(
                "`format` is `{}`: this mtec reads `{MODEL_FORMAT}`",
                self.format
            )));
        }
        Ok(())
    }
}
