//! Thermal models evaluated on line: one reading at a time, with a small fixed state.
//!
//! A controller cannot hand a model the whole temperature log; it has the readings of this cycle
//! and the time since the last one. [`ThermalModel::stream`] turns a fitted model into a
//! [`ThermalStream`] whose [`ThermalStream::step`] advances every filter of the model by `dt`
//! with the new readings and whose [`ThermalStream::predict_um`] gives the drift now. It runs the
//! same recursions as the batch `predict` (the exact first-order-lag step
//! L ← L + (1 − e^(−Δt/τ))(u − L), `features::lag_filter`), so over a log it reproduces the batch
//! prediction to rounding (a test checks this on the real fl-thermal record).
//!
//! State and its start: the first `step` after creation (or [`ThermalStream::reset`]) sets every
//! filter to its input (the machine starts in equilibrium, like the batch filters at the start of
//! an experiment) and, for exp-ambient, takes these readings as the reference of the temperature
//! rises. A controller that starts with a warm machine must either feed the history first or
//! accept that the filters begin at equilibrium.
//!
//! Not every regressor can run on line: a temperature rate over a backward window needs the
//! readings of the whole window, so models with `rate` features are refused here.
//! `step` does not allocate (buffers are sized when the stream is built).

use crate::error::ThermalError;
use crate::exp_ambient::{ExpAmbientModel, GroupWeight, AMBIENT_REF_C, AMBIENT_SCALE_C};
use crate::features::Feature;
use crate::heat_input::HeatInputModel;
use crate::linear_model::LinearModel;
use crate::model::ThermalModel;

/// How a filter's input is made from a reading.
#[derive(Debug, Clone, PartialEq)]
enum Transform {
    /// The reading itself.
    Identity,
    /// (u / u_ref)^α (heat-input's power of the spindle speed).
    Power { reference: f64, alpha: f64 },
}

/// One first-order lag τ·dL/dt = f(u) − L on line; τ may switch with a second input
/// (heat-input: `tau_rest_min` when the switching input is 0).
#[derive(Debug, Clone, PartialEq)]
struct Lag {
    input: usize,
    transform: Transform,
    tau_run_min: f64,
    tau_rest_min: f64,
    switch: Option<usize>,
    state: f64,
}

impl Lag {
    fn value(&self, readings: &[f64]) -> f64 {
        let u = readings[self.input];
        match self.transform {
            Transform::Identity => u,
            Transform::Power { reference, alpha } => (u / reference).powf(alpha),
        }
    }

    fn start(&mut self, readings: &[f64]) {
        self.state = self.value(readings);
    }

    fn advance(&mut self, readings: &[f64], dt_min: f64) {
        let tau = match self.switch {
            Some(s) if !(readings[s] > 0.0) => self.tau_rest_min,
            _ => self.tau_run_min,
        };
        // exact step response of τ·dL/dt = u − L over dt (features::lag_filter)
        let alpha = 1.0 - (-dt_min / tau).exp();
        self.state += alpha * (self.value(readings) - self.state);
    }
}

/// The drift as an intercept plus coefficients times readings and lag states (linear and
/// heat-input models).
#[derive(Debug, Clone, PartialEq)]
struct LinearStream {
    intercept_um: f64,
    /// (input index, coefficient): terms on the readings themselves.
    direct: Vec<(usize, f64)>,
    /// (lag, coefficient).
    lags: Vec<(Lag, f64)>,
}

/// exp-ambient δ = k·x + b on line: rises from the first readings, ambient, position.
#[derive(Debug, Clone, PartialEq)]
struct ExpAmbientStream {
    model: Box<ExpAmbientModel>,
    /// (input index, weight) of the two rise groups.
    up: Vec<(usize, f64)>,
    nut: Vec<(usize, f64)>,
    ambient: usize,
    /// Readings at the start (references of the rises).
    reference: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq)]
enum Kind {
    Linear(LinearStream),
    ExpAmbient(ExpAmbientStream),
}

/// A thermal model running on line (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalStream {
    inputs: Vec<String>,
    kind: Kind,
    /// Readings of the last step (for direct terms and the exp-ambient rises).
    last: Vec<f64>,
    started: bool,
}

/// Index of `name` in `inputs`, added when absent.
fn input_index(inputs: &mut Vec<String>, name: &str) -> usize {
    match inputs.iter().position(|s| s == name) {
        Some(i) => i,
        None => {
            inputs.push(name.to_string());
            inputs.len() - 1
        }
    }
}

fn linear_stream(m: &LinearModel, inputs: &mut Vec<String>) -> Result<Kind, ThermalError> {
    if m.features.len() != m.coefficients.len() {
        return Err(ThermalError::Invalid(format!(
            "the model has {} features and {} coefficients",
            m.features.len(),
            m.coefficients.len()
        )));
    }
    let mut s = LinearStream {
        intercept_um: m.intercept_um,
        direct: Vec::new(),
        lags: Vec::new(),
    };
    for (f, &c) in m.features.iter().zip(&m.coefficients) {
        match f {
            Feature::Temp { sensor } => s.direct.push((input_index(inputs, sensor), c)),
            Feature::Lag { sensor, tau_min } => s.lags.push((
                Lag {
                    input: input_index(inputs, sensor),
                    transform: Transform::Identity,
                    tau_run_min: *tau_min,
                    tau_rest_min: *tau_min,
                    switch: None,
                    state: 0.0,
                },
                c,
            )),
            Feature::HeatLag {
                input,
                alpha,
                tau_min,
                rest_tau_min,
            } => {
                let u = input_index(inputs, input);
                // L[(n/n_ref)^α] with τ running, τ_rest at rest (features::switched_lag)
                s.lags.push((
                    Lag {
                        input: u,
                        transform: Transform::Power {
                            reference: crate::features::INPUT_REF,
                            alpha: *alpha,
                        },
                        tau_run_min: *tau_min,
                        tau_rest_min: *rest_tau_min,
                        switch: Some(u),
                        state: 0.0,
                    },
                    c,
                ))
            }
            Feature::Rate { .. } => {
                return Err(ThermalError::Invalid(format!(
                    "feature `{}` needs the readings of a whole window and cannot run on line; \
                     refit without rate features",
                    f.name()
                )))
            }
        }
    }
    Ok(Kind::Linear(s))
}

fn heat_input_stream(m: &HeatInputModel, inputs: &mut Vec<String>) -> Result<Kind, ThermalError> {
    if m.taus_min.len() != m.heat_coefficients_um.len()
        || m.ambient_sensors.len() != m.ambient_coefficients_um_per_c.len()
        || (m.ambient_lag_min.is_some()
            && m.ambient_lag_coefficients_um_per_c.len() != m.ambient_sensors.len())
    {
        return Err(ThermalError::Invalid(
            "the heat-input model's coefficient lists do not match its time constants and \
             ambient sensors"
                .into(),
        ));
    }
    let u = input_index(inputs, &m.input);
    let mut s = LinearStream {
        intercept_um: m.intercept_um,
        direct: Vec::new(),
        lags: Vec::new(),
    };
    for (&tau, &c) in m.taus_min.iter().zip(&m.heat_coefficients_um) {
        // L_τ[(n/n_ref)^α] with s·τ at rest (features::switched_lag)
        s.lags.push((
            Lag {
                input: u,
                transform: Transform::Power {
                    reference: m.input_ref,
                    alpha: m.alpha,
                },
                tau_run_min: tau,
                tau_rest_min: m.rest_tau_factor * tau,
                switch: Some(u),
                state: 0.0,
            },
            c,
        ));
    }
    for (a, sensor) in m.ambient_sensors.iter().enumerate() {
        let j = input_index(inputs, sensor);
        s.direct.push((j, m.ambient_coefficients_um_per_c[a]));
        if let Some(tau) = m.ambient_lag_min {
            s.lags.push((
                Lag {
                    input: j,
                    transform: Transform::Identity,
                    tau_run_min: tau,
                    tau_rest_min: tau,
                    switch: None,
                    state: 0.0,
                },
                m.ambient_lag_coefficients_um_per_c[a],
            ));
        }
    }
    Ok(Kind::Linear(s))
}

fn group(weights: &[GroupWeight], inputs: &mut Vec<String>) -> Vec<(usize, f64)> {
    weights
        .iter()
        .map(|g| (input_index(inputs, &g.sensor), g.weight))
        .collect()
}

impl ThermalModel {
    /// The model as a [`ThermalStream`] (module docs); refuses models with features that cannot
    /// run on line.
    pub fn stream(&self) -> Result<ThermalStream, ThermalError> {
        let mut inputs = Vec::new();
        let kind = match self {
            ThermalModel::Linear(m) => linear_stream(m, &mut inputs)?,
            ThermalModel::HeatInput(m) => heat_input_stream(m, &mut inputs)?,
            ThermalModel::ExpAmbient(m) => {
                let up = group(&m.up_weights(), &mut inputs);
                let nut = group(&m.nut_weights(), &mut inputs);
                let ambient = input_index(&mut inputs, "ambient_c");
                Kind::ExpAmbient(ExpAmbientStream {
                    model: m.clone(),
                    up,
                    nut,
                    ambient,
                    reference: Vec::new(),
                })
            }
        };
        let n = inputs.len();
        let mut s = ThermalStream {
            inputs,
            kind,
            last: vec![0.0; n],
            started: false,
        };
        if let Kind::ExpAmbient(e) = &mut s.kind {
            e.reference = vec![0.0; n];
        }
        Ok(s)
    }
}

impl ThermalStream {
    /// The readings [`ThermalStream::step`] takes, in order: sensor columns (`t3_c`), heat inputs
    /// (`spindle_rpm`), `ambient_c` for exp-ambient.
    pub fn inputs(&self) -> &[String] {
        &self.inputs
    }

    /// Whether the drift depends on the axis position (exp-ambient: δ = k·x + b).
    pub fn needs_position(&self) -> bool {
        matches!(self.kind, Kind::ExpAmbient(_))
    }

    /// Whether a first reading has been taken since creation or [`ThermalStream::reset`].
    pub fn started(&self) -> bool {
        self.started
    }

    /// Forgets the state: the next step starts the filters again (module docs).
    pub fn reset(&mut self) {
        self.started = false;
    }

    /// Advances the state by `dt_min` minutes with `readings` (in [`ThermalStream::inputs`]
    /// order). The first step after creation or reset starts the filters at these readings and
    /// ignores `dt_min`. Refuses a wrong count, non-finite readings, and a negative or
    /// non-finite `dt_min` (the state is then unchanged).
    pub fn step(&mut self, readings: &[f64], dt_min: f64) -> Result<(), ThermalError> {
        if readings.len() != self.inputs.len() {
            return Err(ThermalError::Invalid(format!(
                "{} readings given, the model takes {}",
                readings.len(),
                self.inputs.len()
            )));
        }
        if readings.iter().any(|v| !v.is_finite()) {
            return Err(ThermalError::Invalid("a reading is not finite".into()));
        }
        if self.started && !(dt_min >= 0.0 && dt_min.is_finite()) {
            return Err(ThermalError::Invalid(format!(
                "the time step must be finite and ≥ 0 (got {dt_min} min)"
            )));
        }
        match &mut self.kind {
            Kind::Linear(s) => {
                for (lag, _) in &mut s.lags {
                    if self.started {
                        lag.advance(readings, dt_min);
                    } else {
                        lag.start(readings);
                    }
                }
            }
            Kind::ExpAmbient(e) => {
                if !self.started {
                    e.reference.copy_from_slice(readings);
                }
            }
        }
        self.last.copy_from_slice(readings);
        self.started = true;
        Ok(())
    }

    /// The drift now (µm) at axis position `position_mm` (used by exp-ambient only). 0 before
    /// the first step.
    pub fn predict_um(&self, position_mm: f64) -> f64 {
        if !self.started {
            return 0.0;
        }
        match &self.kind {
            Kind::Linear(s) => {
                s.intercept_um
                    + s.direct.iter().map(|&(j, c)| c * self.last[j]).sum::<f64>()
                    + s.lags.iter().map(|(l, c)| c * l.state).sum::<f64>()
            }
            Kind::ExpAmbient(e) => {
                let rise = |g: &[(usize, f64)]| {
                    g.iter()
                        .map(|&(j, w)| w * (self.last[j] - e.reference[j]))
                        .sum::<f64>()
                };
                let u = (self.last[e.ambient] - AMBIENT_REF_C) / AMBIENT_SCALE_C;
                e.model.delta_um(u, rise(&e.up), rise(&e.nut), position_mm)
            }
        }
    }
}
