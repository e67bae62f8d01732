//! Guard rails of a fitted model at prediction time: the training envelope (the range of every
//! input the model reads), the rows where an input leaves it, and the uncertainty of a
//! prediction from the forward-validation residuals.
//!
//! A linear thermal model extrapolates without a sign of it; the model file therefore keeps the
//! minimum and maximum of every column it reads over the training rows, and `predict` flags the
//! rows outside (with a margin of 5 % of the range, so sensor noise at the edge does not flag).
//! The uncertainty is the pooled RMSE of the forward folds (the error the model made on blocks
//! it had not seen), the honest size of its error on an unseen duty cycle; it is not a bound.

use crate::data::ThermalData;
use crate::features::Feature;
use crate::model::ThermalModel;
use serde::{Deserialize, Serialize};

/// Share of a column's training range allowed beyond it before a row is flagged.
pub const ENVELOPE_MARGIN: f64 = 0.05;

/// The training range of one input column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputRange {
    pub column: String,
    pub min: f64,
    pub max: f64,
}

impl InputRange {
    /// Whether `v` lies outside the range widened by [`ENVELOPE_MARGIN`] of its width.
    pub fn outside(&self, v: f64) -> bool {
        let m = ENVELOPE_MARGIN * (self.max - self.min);
        !(v >= self.min - m && v <= self.max + m)
    }
}

/// The columns a model reads (temperature sensors and non-temperature inputs), in order.
pub fn model_columns(model: &ThermalModel) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut add = |c: &str| {
        if !out.iter().any(|o| o == c) {
            out.push(c.to_string());
        }
    };
    match model {
        ThermalModel::Linear(m) => {
            for f in &m.features {
                match f {
                    Feature::HeatLag { input, .. } => add(input),
                    other => add(other.sensor()),
                }
            }
        }
        ThermalModel::HeatInput(m) => {
            add(&m.input);
            for s in &m.ambient_sensors {
                add(s);
            }
        }
        ThermalModel::ExpAmbient(m) => {
            let groups: Vec<&str> = m
                .up_group
                .iter()
                .chain(&m.nut_group)
                .map(|g| g.sensor.as_str())
                .collect();
            if groups.is_empty() {
                add(&m.up_sensor);
                add(&m.nut_sensor);
            }
            for g in groups {
                add(g);
            }
            add("ambient_c");
            add("position_mm");
        }
    }
    out
}

/// Values of a column by name: a sensor (with or without `_c`), an attached input, `ambient_c`
/// or `position_mm`.
fn column(data: &ThermalData, name: &str) -> Option<Vec<f64>> {
    match name {
        "ambient_c" => data.ambient_c.clone(),
        "position_mm" => data.position_mm.clone(),
        _ => crate::data::input_column(data, name)
            .or_else(|| data.sensor_index(name).ok().map(|j| data.sensor(j))),
    }
}

/// The training envelope of the model's columns over `rows`.
pub fn envelope(model: &ThermalModel, data: &ThermalData, rows: &[usize]) -> Vec<InputRange> {
    model_columns(model)
        .into_iter()
        .filter_map(|c| {
            let v = column(data, &c)?;
            let (lo, hi) = rows
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &i| {
                    (l.min(v[i]), h.max(v[i]))
                });
            lo.is_finite().then_some(InputRange {
                column: c,
                min: lo,
                max: hi,
            })
        })
        .collect()
}

/// For each row, the columns outside the envelope (empty: inside).
pub fn outside_envelope(envelope: &[InputRange], data: &ThermalData) -> Vec<Vec<String>> {
    let mut out = vec![Vec::new(); data.len()];
    for r in envelope {
        if let Some(v) = column(data, &r.column) {
            for (i, x) in v.iter().enumerate() {
                if r.outside(*x) {
                    out[i].push(r.column.clone());
                }
            }
        }
    }
    out
}
