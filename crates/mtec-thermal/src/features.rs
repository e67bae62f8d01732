//! Regressors built from the temperature log: the temperatures themselves, and thermal-dynamics
//! features (beyond the source methods) that let a linear model follow a duty cycle it has not
//! seen.
//!
//! Thermal drift lags the temperatures a sensor sees: the structure between a sensor and the
//! point whose displacement is measured is a thermal low-pass. Two features capture it:
//! - `lag`: a first-order lag of a sensor, L[i] = L[i−1] + (1 − e^(−Δt/τ))(T[i] − L[i−1]),
//!   the exact discretisation of τ·dL/dt = T − L for a temperature held over each interval;
//!   L starts at the experiment's first reading (the machine starts in equilibrium);
//! - `rate`: the temperature rate dT/dt (°C/min) as the backward difference over a window w,
//!   (T(t) − T(t − w))/w, clamped at the start of the experiment.
//!
//! A third follows the heat source instead of a sensor: the heat lag, a first-order lag of the
//! heat input p = (n/n_ref)^α of a non-temperature column n (the spindle speed) with its own
//! time constant at rest ([`switched_lag`], which the `heat-input` kind builds on).
//!
//! All are causal: they use only past readings, so a controller can compute them on line.
//! The time constants are fitted (see [`fit_time_constants`]): coordinate descent over a log
//! grid of τ minimising the pooled forward-fold RMSE of the linear model that uses the features
//! (fit on the blocks before, score the next: [`crate::validate::forward_folds`]); only when the
//! training rows hold fewer than two blocks, its training SSE.

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::linear::ols;
use crate::validate::{ridge_forward_scores, ForwardFold};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// One regressor of a linear thermal model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Feature {
    /// The sensor's temperature (°C).
    Temp { sensor: String },
    /// First-order lag of the sensor with time constant `tau_min`.
    Lag { sensor: String, tau_min: f64 },
    /// Temperature rate over a backward window (°C/min).
    Rate { sensor: String, window_min: f64 },
    /// First-order lag of the heat input p = (n/1000)^α of a non-temperature column n (e.g.
    /// `spindle_rpm`), with time constant `tau_min` while n > 0 and `rest_tau_min` at rest:
    /// [`switched_lag`]. On line: one filter state, advanced with the current
    /// n and Δt by the same exact step.
    HeatLag {
        input: String,
        alpha: f64,
        tau_min: f64,
        rest_tau_min: f64,
    },
}

impl Feature {
    /// Short name for tables: `t3_c`, `lag(t3_c, 42.0 min)`, `rate(t3_c, 5 min)`.
    pub fn name(&self) -> String {
        match self {
            Feature::Temp { sensor } => sensor.clone(),
            Feature::Lag { sensor, tau_min } => format!("lag({sensor},{tau_min:.1}min)"),
            Feature::Rate { sensor, window_min } => format!("rate({sensor},{window_min}min)"),
            Feature::HeatLag {
                input,
                alpha,
                tau_min,
                rest_tau_min,
            } => format!("heat({input}^{alpha},{tau_min:.1}/{rest_tau_min:.1}min)"),
        }
    }

    /// The column the feature reads (a temperature sensor, or the heat-input column).
    pub fn sensor(&self) -> &str {
        match self {
            Feature::Temp { sensor }
            | Feature::Lag { sensor, .. }
            | Feature::Rate { sensor, .. } => sensor,
            Feature::HeatLag { input, .. } => input,
        }
    }

    /// Values of the feature on every row of `data`.
    pub fn values(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        if let Feature::HeatLag {
            input,
            alpha,
            tau_min,
            rest_tau_min,
        } = self
        {
            let n = crate::data::input_column(data, input)
                .ok_or_else(|| ThermalError::MissingColumn(input.clone()))?;
            let p: Vec<f64> = n.iter().map(|v| (v / INPUT_REF).powf(*alpha)).collect();
            return Ok(switched_lag(data, &p, &n, *tau_min, *rest_tau_min));
        }
        let t = data.sensor(data.sensor_index(self.sensor())?);
        Ok(match self {
            Feature::Temp { .. } => t,
            Feature::Lag { tau_min, .. } => lag_filter(data, &t, *tau_min),
            Feature::Rate { window_min, .. } => rate(data, &t, *window_min),
            Feature::HeatLag { .. } => unreachable!("returned above"),
        })
    }
}

/// First-order lag along each experiment (module docs).
pub fn lag_filter(data: &ThermalData, t: &[f64], tau_min: f64) -> Vec<f64> {
    let mut out = vec![0.0; t.len()];
    for (a, b) in data.segments() {
        out[a] = t[a];
        for i in a + 1..b {
            let dt = data.time_min[i] - data.time_min[i - 1];
            // exact step response of τ·dL/dt = T − L over dt
            let alpha = 1.0 - (-dt / tau_min).exp();
            out[i] = out[i - 1] + alpha * (t[i] - out[i - 1]);
        }
    }
    out
}

/// Backward-difference rate over a window, within each experiment (module docs).
pub fn rate(data: &ThermalData, t: &[f64], window_min: f64) -> Vec<f64> {
    let mut out = vec![0.0; t.len()];
    for (a, b) in data.segments() {
        let mut j = a;
        for i in a..b {
            while j < i && data.time_min[i] - data.time_min[j + 1] >= window_min {
                j += 1;
            }
            let dt = data.time_min[i] - data.time_min[j];
            out[i] = if dt > 0.0 { (t[i] - t[j]) / dt } else { 0.0 };
        }
    }
    out
}

/// The design matrix of a feature list on `data` (rows × features).
pub fn design(data: &ThermalData, features: &[Feature]) -> Result<DMatrix<f64>, ThermalError> {
    let mut x = DMatrix::zeros(data.len(), features.len());
    for (j, f) in features.iter().enumerate() {
        for (i, v) in f.values(data)?.into_iter().enumerate() {
            x[(i, j)] = v;
        }
    }
    Ok(x)
}

/// Plain temperature features of the named sensors (every `_c` sensor when `sensors` is empty:
/// an attached input column such as `spindle_rpm` is not a temperature).
pub fn temp_features(data: &ThermalData, sensors: &[String]) -> Result<Vec<Feature>, ThermalError> {
    if sensors.is_empty() {
        return Ok(data
            .sensor_names
            .iter()
            .filter(|s| s.ends_with("_c"))
            .map(|s| Feature::Temp { sensor: s.clone() })
            .collect());
    }
    sensors
        .iter()
        .map(|s| {
            let j = data.sensor_index(s)?;
            Ok(Feature::Temp {
                sensor: data.sensor_names[j].clone(),
            })
        })
        .collect()
}

/// The τ grid searched (min): 24 values log-spaced from 2 to 1000 min.
pub fn tau_grid() -> Vec<f64> {
    (0..24)
        .map(|i| 2.0 * 500f64.powf(i as f64 / 23.0))
        .collect()
}

/// Fits the time constants of the `Lag` features in `features` (in place) by coordinate descent
/// over [`tau_grid`]: each sweep sets each τ in turn to the grid value that minimises the score
/// of the OLS model on all features; two sweeps. The score is the pooled RMSE over the forward
/// `folds` of the training rows (coefficients refitted on each fold's training blocks for every τ
/// tried: τ chosen by how the model predicts blocks it has not seen, not by how it fits them);
/// with no fold, the training SSE on `rows`. Returns the final score.
pub fn fit_time_constants(
    data: &ThermalData,
    rows: &[usize],
    features: &mut [Feature],
    folds: &[ForwardFold],
) -> Result<f64, ThermalError> {
    let grid = tau_grid();
    let names: Vec<String> = features.iter().map(|f| f.name()).collect();
    let yall = data.target_um()?;
    let y: Vec<f64> = rows.iter().map(|&i| yall[i]).collect();
    let mut cols: Vec<Vec<f64>> = features
        .iter()
        .map(|f| f.values(data))
        .collect::<Result<_, _>>()?;
    let score = |cols: &[Vec<f64>]| -> f64 {
        if !folds.is_empty() {
            let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
            // k = 0: ordinary least squares on each fold
            return ridge_forward_scores(&refs, yall, folds, &[0.0])[0].0;
        }
        let x = DMatrix::from_fn(rows.len(), cols.len(), |r, j| cols[j][rows[r]]);
        match ols(&x, &y, &names) {
            Ok(fit) => (0..x.nrows())
                .map(|i| {
                    let f = fit.intercept
                        + (0..x.ncols())
                            .map(|j| fit.coefficients[j] * x[(i, j)])
                            .sum::<f64>();
                    (y[i] - f).powi(2)
                })
                .sum(),
            Err(_) => f64::INFINITY,
        }
    };
    let mut best = score(&cols);
    for _sweep in 0..2 {
        for j in 0..features.len() {
            let Feature::Lag { sensor, tau_min } = features[j].clone() else {
                continue;
            };
            let t = data.sensor(data.sensor_index(&sensor)?);
            let mut best_tau = tau_min;
            for &tau in &grid {
                cols[j] = lag_filter(data, &t, tau);
                let s = score(&cols);
                if s < best {
                    best = s;
                    best_tau = tau;
                }
            }
            cols[j] = lag_filter(data, &t, best_tau);
            features[j] = Feature::Lag {
                sensor,
                tau_min: best_tau,
            };
        }
    }
    if !best.is_finite() {
        return Err(ThermalError::Undetermined(
            "no time constant gives a solvable regression (are the lag features collinear with the temperatures?)".into(),
        ));
    }
    Ok(best)
}

/// Reference speed of the power input p = (n/n_ref)^α (rpm).
pub const INPUT_REF: f64 = 1000.0;

/// First-order lag with a time constant that depends on whether the input runs over the
/// interval: τ·dL/dt = p − L with τ = `tau_run_min` when n > 0 and `tau_rest_min` when n = 0,
/// discretised exactly for p and n held over each interval (the value at its end, like
/// [`lag_filter`]); L starts at the experiment's first value.
pub fn switched_lag(
    data: &ThermalData,
    p: &[f64],
    input: &[f64],
    tau_run_min: f64,
    tau_rest_min: f64,
) -> Vec<f64> {
    let mut out = vec![0.0; p.len()];
    for (a, b) in data.segments() {
        out[a] = p[a];
        for i in a + 1..b {
            let dt = data.time_min[i] - data.time_min[i - 1];
            let tau = if input[i] > 0.0 {
                tau_run_min
            } else {
                tau_rest_min
            };
            // exact step response of τ·dL/dt = p − L over dt
            out[i] = out[i - 1] + (1.0 - (-dt / tau).exp()) * (p[i] - out[i - 1]);
        }
    }
    out
}
