//! The common fit/predict interface (linfa style: a fitter is a value with its options, `fit`
//! returns a model, a model `predict`s). Every model kind implements these two traits; the
//! validation ([`crate::validate`]) and the registry ([`crate::registry`]) work through them.

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::metrics::Metrics;

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

/// A boxed fitter (auto's candidates of several kinds) is a fitter.
impl<F: Fit + ?Sized> Fit for Box<F> {
    type Model = F::Model;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<F::Model, ThermalError> {
        (**self).fit_rows(data, rows)
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
