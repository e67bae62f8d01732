//! What a fitted thermal model is, in words and terms, read from the model itself: the report
//! describes the model that was fitted (its kind, the columns it reads, its equation's terms),
//! never the method a project file asked for (issue 24: a heat-input model was reported as a
//! ridge-trace selection, and its main input, the spindle speed, appeared nowhere).

use crate::features::Feature;
use crate::guard::model_columns;
use crate::linear_model::LinearMethod;
use crate::model::ThermalModel;

/// One term of the model's equation: its name, value and unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    pub name: String,
    pub value: f64,
    pub unit: String,
}

/// A fitted model in words (one paragraph), the columns it reads and its terms.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSummary {
    /// `linear (mlr)`, `heat-input`, `exp-ambient`, …
    pub kind: String,
    pub description: String,
    /// Every column the model reads, in its order.
    pub inputs: Vec<String>,
    pub terms: Vec<Term>,
}

fn method_name(m: LinearMethod) -> &'static str {
    match m {
        LinearMethod::Mlr => "mlr",
        LinearMethod::Ridge => "ridge",
        LinearMethod::RidgeSelect => "ridge-select",
        LinearMethod::LagSelect => "lag-select",
        LinearMethod::LaggedRidge => "lagged-ridge",
        LinearMethod::Dynamic => "dynamic",
        LinearMethod::Pls => "pls",
    }
}

fn method_words(m: LinearMethod) -> &'static str {
    match m {
        LinearMethod::Mlr => "multiple linear regression (least squares)",
        LinearMethod::Ridge => "ridge regression",
        LinearMethod::RidgeSelect => {
            "ridge regression on the sensors kept by the ridge-trace selection (VIF, elimination \
             steps, chosen k)"
        }
        LinearMethod::LagSelect => "least squares on sensors and first-order lags of them",
        LinearMethod::LaggedRidge => {
            "ridge regression on forward-selected temperatures and their first-order lags"
        }
        LinearMethod::Dynamic => {
            "ridge regression on forward-selected temperatures, their first-order lags and the \
             lagged heat input"
        }
        LinearMethod::Pls => "partial least squares on the sensors (latent components)",
    }
}

/// The unit of a coefficient of `f` (the drift is in µm).
fn feature_unit(f: &Feature) -> &'static str {
    match f {
        Feature::Temp { .. } | Feature::Lag { .. } => "µm/°C",
        Feature::Rate { .. } => "µm/(°C/min)",
        Feature::HeatLag { .. } => "µm per unit of lagged heat",
    }
}

fn list(v: &[String]) -> String {
    v.join(", ")
}

impl ThermalModel {
    /// The model in words and terms ([`ModelSummary`]).
    pub fn summary(&self) -> ModelSummary {
        let inputs = model_columns(self);
        match self {
            ThermalModel::Linear(m) => {
                let mut terms = vec![Term {
                    name: "intercept".into(),
                    value: m.intercept_um,
                    unit: "µm".into(),
                }];
                for (f, c) in m.features.iter().zip(&m.coefficients) {
                    terms.push(Term {
                        name: f.name(),
                        value: *c,
                        unit: feature_unit(f).into(),
                    });
                }
                let ridge = m
                    .ridge
                    .as_ref()
                    .map(|r| format!(", ridge parameter k = {:.3e}", r.k))
                    .unwrap_or_default();
                ModelSummary {
                    kind: format!("linear ({})", method_name(m.method)),
                    description: format!(
                        "Linear model fitted by {} on {} feature(s){ridge}: drift = intercept + \
                         Σ coefficient × feature. It reads {}.",
                        method_words(m.method),
                        m.features.len(),
                        list(&inputs)
                    ),
                    inputs,
                    terms,
                }
            }
            ThermalModel::HeatInput(m) => {
                let mut terms = vec![Term {
                    name: "intercept b0".into(),
                    value: m.intercept_um,
                    unit: "µm".into(),
                }];
                for (tau, c) in m.taus_min.iter().zip(&m.heat_coefficients_um) {
                    terms.push(Term {
                        name: format!("heat lag τ = {tau:.1} min"),
                        value: *c,
                        unit: "µm per unit of lagged heat".into(),
                    });
                }
                for (s, d) in m
                    .ambient_sensors
                    .iter()
                    .zip(&m.ambient_coefficients_um_per_c)
                {
                    terms.push(Term {
                        name: format!("ambient {s}"),
                        value: *d,
                        unit: "µm/°C".into(),
                    });
                }
                if let Some(tau) = m.ambient_lag_min {
                    for (s, e) in m
                        .ambient_sensors
                        .iter()
                        .zip(&m.ambient_lag_coefficients_um_per_c)
                    {
                        terms.push(Term {
                            name: format!("ambient lag({s}, {tau:.1} min)"),
                            value: *e,
                            unit: "µm/°C".into(),
                        });
                    }
                }
                let rest = if (m.rest_tau_factor - 1.0).abs() > 1e-12 {
                    format!(
                        " (× {} while the input is zero: slower cooling at rest)",
                        m.rest_tau_factor
                    )
                } else {
                    String::new()
                };
                ModelSummary {
                    kind: "heat-input".into(),
                    description: format!(
                        "Heat-input model: the drift is the response of the machine's thermal \
                         network to the heat of `{}` (heat ∝ ({}/{})^{:.2}) through first-order \
                         lags of {} min{rest}, plus the ambient sensor(s) {}. Fitted by ridge \
                         least squares (k = {:.3e}); the lags, the exponent and the ambient \
                         sensors were chosen by forward folds inside the training rows. It \
                         reads {}.",
                        m.input,
                        m.input,
                        m.input_ref,
                        m.alpha,
                        m.taus_min
                            .iter()
                            .map(|t| format!("{t:.1}"))
                            .collect::<Vec<_>>()
                            .join(", "),
                        if m.ambient_sensors.is_empty() {
                            "(none)".to_string()
                        } else {
                            list(&m.ambient_sensors)
                        },
                        m.k,
                        list(&inputs)
                    ),
                    inputs,
                    terms,
                }
            }
            ThermalModel::ExpAmbient(m) => {
                let mut terms = Vec::new();
                let mut poly = |name: &str, c: &[f64], unit: &str| {
                    for (i, v) in c.iter().enumerate() {
                        terms.push(Term {
                            name: format!("{name}[{i}]"),
                            value: *v,
                            unit: unit.into(),
                        });
                    }
                };
                poly("b_a", &m.b_a, "µm");
                poly("ln b_b", &m.ln_b_b, "ln °C");
                poly("k_a", &m.k_a, "µm/mm");
                poly("ln k_b", &m.ln_k_b, "ln °C");
                ModelSummary {
                    kind: "exp-ambient".into(),
                    description: format!(
                        "Ambient-adaptive axis model δ = k·x + b, b = b_a·(1 − exp(−ΔT_up/b_b)), \
                         k = k_a·(1 − exp(−ΔT_nut/k_b)), each coefficient a polynomial of degree \
                         {} in the ambient temperature; ΔT_up from {} and ΔT_nut from {}. It \
                         reads {}.",
                        m.degree,
                        m.up_sensor,
                        m.nut_sensor,
                        list(&inputs)
                    ),
                    inputs,
                    terms,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::heat_input::HeatInputModel;
    use crate::linear_model::LinearModel;

    #[test]
    fn a_heat_input_model_names_its_input_and_every_coefficient() {
        let m = ThermalModel::HeatInput(HeatInputModel {
            input: "spindle_rpm".into(),
            input_ref: 1000.0,
            alpha: 1.5,
            taus_min: vec![10.0, 60.0],
            rest_tau_factor: 3.0,
            ambient_sensors: vec!["t9_c".into()],
            k: 0.01,
            intercept_um: 1.0,
            heat_coefficients_um: vec![2.0, 3.0],
            ambient_coefficients_um_per_c: vec![0.5],
            ambient_lag_min: None,
            ambient_lag_coefficients_um_per_c: vec![],
            inner_cv_rmse_um: None,
            warnings: vec![],
        });
        let s = m.summary();
        assert_eq!(s.kind, "heat-input");
        assert!(
            s.inputs.iter().any(|c| c == "spindle_rpm"),
            "{:?}",
            s.inputs
        );
        assert!(s.description.contains("`spindle_rpm`"), "{}", s.description);
        assert!(
            s.description.contains("10.0, 60.0 min"),
            "{}",
            s.description
        );
        assert!(!s.description.contains("ridge-trace"));
        let values: Vec<f64> = s.terms.iter().map(|t| t.value).collect();
        assert_eq!(values, vec![1.0, 2.0, 3.0, 0.5]);
    }

    #[test]
    fn a_linear_model_lists_its_features_with_their_units() {
        let m = ThermalModel::Linear(LinearModel {
            method: LinearMethod::Mlr,
            features: vec![
                Feature::Temp {
                    sensor: "t1_c".into(),
                },
                Feature::Lag {
                    sensor: "t2_c".into(),
                    tau_min: 30.0,
                },
            ],
            intercept_um: -4.0,
            coefficients: vec![1.5, -0.5],
            std_errors: None,
            ridge: None,
            warnings: vec![],
        });
        let s = m.summary();
        assert_eq!(s.kind, "linear (mlr)");
        assert_eq!(s.inputs, vec!["t1_c".to_string(), "t2_c".to_string()]);
        assert_eq!(s.terms.len(), 3);
        assert_eq!(s.terms[2].name, "lag(t2_c,30.0min)");
        assert_eq!(s.terms[2].unit, "µm/°C");
        assert!(s.description.contains("multiple linear regression"));
    }
}
