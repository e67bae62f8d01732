//! Any thermal model mtec can store: [`ThermalModel`], one variant per stored form — linear
//! ([`crate::linear_model`]), exp-ambient ([`crate::exp_ambient`]), heat-input
//! ([`crate::heat_input`]) — what the kinds fit to and the model file holds
//! ([`crate::model_file`]).

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::exp_ambient::ExpAmbientModel;
use crate::features::Feature;
use crate::heat_input::HeatInputModel;
use serde::{Deserialize, Serialize};

// The fit/predict interface, the linear models and the exp-ambient fitter were defined here;
// they live in the modules below this one now and keep these paths.
pub use crate::exp_ambient::ExpAmbient;
pub use crate::fit::{Fit, Predict};
pub use crate::linear::{cancellation_warning, LARGE_STANDARDISED_COEFFICIENT};
pub use crate::linear_model::{
    forward_k, KChoice, LinearMethod, LinearModel, Mlr, Ridge, RidgeEquation, RidgeSelect,
};

/// Any thermal model mtec can store.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum ThermalModel {
    Linear(LinearModel),
    /// Boxed: the model carries many coefficient vectors (keeps the enum small).
    ExpAmbient(Box<ExpAmbientModel>),
    HeatInput(HeatInputModel),
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

impl ThermalModel {
    /// What the fit found suspicious.
    pub fn warnings(&self) -> Vec<String> {
        match self {
            ThermalModel::Linear(m) => m.warnings.clone(),
            ThermalModel::HeatInput(m) => m.warnings.clone(),
            ThermalModel::ExpAmbient(m) => m.warnings.clone(),
        }
    }
    /// Whether the model filters its inputs through time (lags, heat lags, rates): its first
    /// predictions depend on how the filters were started.
    pub fn has_state(&self) -> bool {
        match self {
            ThermalModel::Linear(m) => m
                .features
                .iter()
                .any(|f| !matches!(f, Feature::Temp { .. })),
            ThermalModel::HeatInput(_) => true,
            ThermalModel::ExpAmbient(_) => false,
        }
    }
}
