//! Error functions: the value of one error element as a function of its axis position
//! (mm for linear axes, degrees for rotary axes), optionally changed by temperature.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The shape of an error function of the axis position `q`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Shape {
    /// A constant value (location errors, or a position-independent offset).
    Constant { value: f64 },
    /// value = Σ_k coeffs[k] · q^k (q in mm or deg). Evaluated by Horner's rule.
    Polynomial { coeffs: Vec<f64> },
    /// value = a0 + Σ_k (cos[k−1]·cos(kθ) + sin[k−1]·sin(kθ)), θ = q in degrees (rotary axes).
    Fourier {
        a0: f64,
        cos: Vec<f64>,
        sin: Vec<f64>,
    },
    /// Piecewise-linear through (positions[i], values[i]), positions strictly increasing; held
    /// constant outside the table (a controller table's behaviour).
    Table {
        positions: Vec<f64>,
        values: Vec<f64>,
    },
}

/// A linear temperature dependence of an error element (thermal errors build on it):
/// value += (per_k + per_k_per_mm · q) · (T[sensor] − ref_c).
/// Example: ball-screw expansion on EXX = 11.5e-3 µm/(mm·K) · x · ΔT → `per_k_per_mm = 0.0115`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalTerm {
    pub sensor: String,
    pub ref_c: f64,
    #[serde(default)]
    pub per_k: f64,
    #[serde(default)]
    pub per_k_per_mm: f64,
}

/// An error function: a shape in the axis position plus an optional thermal term.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorFunction {
    #[serde(flatten)]
    pub shape: Shape,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<ThermalTerm>,
}

/// Temperatures by sensor name (°C), for evaluating thermal terms.
pub type Temperatures = BTreeMap<String, f64>;

/// Why an error function is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FunctionError {
    #[error(
        "a table needs as many positions as values and at least one of each (got {0} and {1})"
    )]
    TableLength(usize, usize),
    #[error("table positions must be strictly increasing (position {0} is not)")]
    TableOrder(usize),
    #[error("the function has a non-finite coefficient")]
    NotFinite,
}

impl ErrorFunction {
    /// A constant.
    pub fn constant(value: f64) -> Self {
        ErrorFunction {
            shape: Shape::Constant { value },
            thermal: None,
        }
    }
    /// A polynomial Σ c_k q^k.
    pub fn polynomial(coeffs: Vec<f64>) -> Self {
        ErrorFunction {
            shape: Shape::Polynomial { coeffs },
            thermal: None,
        }
    }
    /// A Fourier series in degrees.
    pub fn fourier(a0: f64, cos: Vec<f64>, sin: Vec<f64>) -> Self {
        ErrorFunction {
            shape: Shape::Fourier { a0, cos, sin },
            thermal: None,
        }
    }
    /// A piecewise-linear table.
    pub fn table(positions: Vec<f64>, values: Vec<f64>) -> Self {
        ErrorFunction {
            shape: Shape::Table { positions, values },
            thermal: None,
        }
    }
    /// Adds a thermal term.
    pub fn with_thermal(mut self, t: ThermalTerm) -> Self {
        self.thermal = Some(t);
        self
    }

    /// Checks the function can be evaluated everywhere.
    pub fn validate(&self) -> Result<(), FunctionError> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match &self.shape {
            Shape::Constant { value } if !value.is_finite() => {
                return Err(FunctionError::NotFinite)
            }
            Shape::Polynomial { coeffs } if !finite(coeffs) => {
                return Err(FunctionError::NotFinite)
            }
            Shape::Fourier { a0, cos, sin } if !(a0.is_finite() && finite(cos) && finite(sin)) => {
                return Err(FunctionError::NotFinite)
            }
            Shape::Table { positions, values } => {
                if positions.len() != values.len() || positions.is_empty() {
                    return Err(FunctionError::TableLength(positions.len(), values.len()));
                }
                if !(finite(positions) && finite(values)) {
                    return Err(FunctionError::NotFinite);
                }
                if let Some(i) = positions.windows(2).position(|w| w[1] <= w[0]) {
                    return Err(FunctionError::TableOrder(i + 1));
                }
            }
            _ => {}
        }
        if let Some(t) = &self.thermal {
            if !(t.ref_c.is_finite() && t.per_k.is_finite() && t.per_k_per_mm.is_finite()) {
                return Err(FunctionError::NotFinite);
            }
        }
        Ok(())
    }

    /// Value at axis position `q` without thermal effect (µm or µrad).
    #[inline]
    pub fn value(&self, q: f64) -> f64 {
        match &self.shape {
            Shape::Constant { value } => *value,
            Shape::Polynomial { coeffs } => coeffs.iter().rev().fold(0.0, |acc, c| acc * q + c),
            Shape::Fourier { a0, cos, sin } => {
                let th = q.to_radians();
                let mut v = *a0;
                for (k, c) in cos.iter().enumerate() {
                    v += c * ((k + 1) as f64 * th).cos();
                }
                for (k, s) in sin.iter().enumerate() {
                    v += s * ((k + 1) as f64 * th).sin();
                }
                v
            }
            Shape::Table { positions, values } => table_value(positions, values, q),
        }
    }

    /// Value at `q` with the thermal term evaluated at `temps` (a missing sensor means no drift).
    pub fn value_at(&self, q: f64, temps: &Temperatures) -> f64 {
        let mut v = self.value(q);
        if let Some(t) = &self.thermal {
            if let Some(tc) = temps.get(&t.sensor) {
                v += (t.per_k + t.per_k_per_mm * q) * (tc - t.ref_c);
            }
        }
        v
    }
}

fn table_value(p: &[f64], v: &[f64], q: f64) -> f64 {
    if p.is_empty() {
        return 0.0;
    }
    if q <= p[0] {
        return v[0];
    }
    if q >= p[p.len() - 1] {
        return v[v.len() - 1];
    }
    let i = p.partition_point(|&x| x <= q) - 1;
    let t = (q - p[i]) / (p[i + 1] - p[i]);
    v[i] + t * (v[i + 1] - v[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_evaluate_as_written() {
        assert_eq!(
            ErrorFunction::polynomial(vec![1.0, 2.0, 3.0]).value(2.0),
            1.0 + 4.0 + 12.0
        );
        let f = ErrorFunction::fourier(0.5, vec![1.0, 0.0], vec![0.0, 2.0]);
        assert!((f.value(90.0) - (0.5 + 0.0 + 2.0 * (180f64.to_radians()).sin())).abs() < 1e-12);
        let t = ErrorFunction::table(vec![0.0, 10.0, 20.0], vec![0.0, 5.0, 3.0]);
        assert_eq!(t.value(5.0), 2.5);
        assert_eq!(t.value(15.0), 4.0);
        assert_eq!(t.value(-1.0), 0.0);
        assert_eq!(t.value(99.0), 3.0);
        assert!(ErrorFunction::table(vec![0.0, 0.0], vec![1.0, 2.0])
            .validate()
            .is_err());
    }

    #[test]
    fn ball_screw_expansion() {
        // 11.5 µm/(m·K) over 600 mm and 2 K = 13.8 µm
        let f = ErrorFunction::constant(0.0).with_thermal(ThermalTerm {
            sensor: "nut".into(),
            ref_c: 20.0,
            per_k: 0.0,
            per_k_per_mm: 0.0115,
        });
        let temps = Temperatures::from([("nut".to_string(), 22.0)]);
        assert!((f.value_at(600.0, &temps) - 13.8).abs() < 1e-12);
    }

    #[test]
    fn json_form() {
        let f: ErrorFunction =
            serde_json::from_str(r#"{"type":"polynomial","coeffs":[0,0.01]}"#).unwrap();
        assert_eq!(f.value(100.0), 1.0);
    }
}
