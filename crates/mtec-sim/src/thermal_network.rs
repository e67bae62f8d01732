//! A lumped-capacitance thermal network: machine bodies with heat capacity, thermal conductances
//! between them and to the ambient air, heat sources driven by a duty cycle, and an ambient
//! temperature that drifts. Integrated with backward (implicit) Euler, which is unconditionally
//! stable for any time step.
//!
//! Equation of body i (lumped heat balance):
//!   C_i dT_i/dt = Σ_j G_ij (T_j − T_i) + G_i,amb (T_amb(t) − T_i) + P_i(t)
//! Backward Euler over a step h:
//!   (C_i/h + Σ_j G_ij + G_i,amb) T_i' − Σ_j G_ij T_j' = C_i/h T_i + G_i,amb T_amb(t+h) + P_i(t+h)

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// One lumped body (spindle housing, motor, ball-screw nut, column, bed, ...).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Body {
    pub name: String,
    /// Heat capacity C in J/K.
    pub capacity_j_per_k: f64,
    /// Conductance to the ambient air G_amb in W/K (convection, radiation lumped).
    pub to_ambient_w_per_k: f64,
}

impl Body {
    /// A body with heat capacity C (J/K) and conductance to the ambient air (W/K).
    pub fn new(name: &str, capacity_j_per_k: f64, to_ambient_w_per_k: f64) -> Self {
        Body {
            name: name.into(),
            capacity_j_per_k,
            to_ambient_w_per_k,
        }
    }
}

/// A conductance between two bodies (indices into `ThermalNetwork::bodies`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Link {
    pub a: usize,
    pub b: usize,
    pub conductance_w_per_k: f64,
}

impl Link {
    /// A conductance (W/K) between bodies `a` and `b`.
    pub fn new(a: usize, b: usize, conductance_w_per_k: f64) -> Self {
        Link {
            a,
            b,
            conductance_w_per_k,
        }
    }
}

/// A heat source in a body whose power follows the duty: P = idle_w + per_speed_w · (speed / rated)^exponent.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HeatSource {
    pub body: usize,
    pub idle_w: f64,
    pub rated_w: f64,
    /// Speed (rpm, or mm/min for a feed axis) at which the source dissipates `idle_w + rated_w`.
    pub rated_speed: f64,
    /// Exponent of the speed dependence (≈1 for motor losses, ≈1.5–2 for bearing friction).
    pub exponent: f64,
}

impl HeatSource {
    /// Power in W at a speed.
    pub fn power_w(&self, speed: f64) -> f64 {
        if speed <= 0.0 {
            return self.idle_w;
        }
        self.idle_w + self.rated_w * (speed / self.rated_speed).powf(self.exponent)
    }
}

/// A piecewise-constant duty cycle: speed held for a duration, one segment after another.
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
pub struct DutyCycle {
    /// (duration in min, speed) segments; after the last one the speed is 0.
    pub segments: Vec<(f64, f64)>,
}

impl DutyCycle {
    /// A cycle from (duration_min, speed) pairs.
    pub fn new(segments: Vec<(f64, f64)>) -> Self {
        DutyCycle { segments }
    }
    /// Speed at time t (min).
    pub fn speed_at(&self, t_min: f64) -> f64 {
        let mut start = 0.0;
        for &(d, s) in &self.segments {
            if t_min >= start && t_min < start + d {
                return s;
            }
            start += d;
        }
        0.0
    }
    /// Total duration in min.
    pub fn duration_min(&self) -> f64 {
        self.segments.iter().map(|s| s.0).sum()
    }
}

/// Ambient air temperature: a mean, a slow linear drift, and a daily sine (workshop day/night).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AmbientProfile {
    pub mean_c: f64,
    pub drift_c_per_h: f64,
    pub daily_amplitude_c: f64,
    /// Phase of the daily sine in hours (time of the maximum minus 6 h).
    pub phase_h: f64,
}

impl AmbientProfile {
    /// A constant ambient temperature.
    pub fn constant(mean_c: f64) -> Self {
        AmbientProfile {
            mean_c,
            drift_c_per_h: 0.0,
            daily_amplitude_c: 0.0,
            phase_h: 0.0,
        }
    }
    /// Ambient temperature at time t (min).
    pub fn at(&self, t_min: f64) -> f64 {
        let h = t_min / 60.0;
        self.mean_c
            + self.drift_c_per_h * h
            + self.daily_amplitude_c
                * (2.0 * std::f64::consts::PI * (h - self.phase_h) / 24.0).sin()
    }
}

/// The network: bodies, links, sources.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ThermalNetwork {
    pub bodies: Vec<Body>,
    pub links: Vec<Link>,
    pub sources: Vec<HeatSource>,
}

/// Temperatures over time: `temps_c[k][i]` is body i at `time_min[k]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ThermalHistory {
    pub time_min: Vec<f64>,
    pub ambient_c: Vec<f64>,
    pub temps_c: Vec<Vec<f64>>,
    pub speed: Vec<f64>,
}

impl ThermalHistory {
    /// Temperature of body `i` over time.
    pub fn body(&self, i: usize) -> Vec<f64> {
        self.temps_c.iter().map(|t| t[i]).collect()
    }
}

impl ThermalNetwork {
    /// Index of a body by name.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Integrates from `initial_c` (one value per body) over `duty`, recording every `record_min`.
    /// The internal step is `step_s` seconds (implicit Euler: stable for any step; accuracy
    /// wants a step well below the smallest time constant C/G).
    pub fn simulate(
        &self,
        initial_c: &[f64],
        duty: &DutyCycle,
        ambient: &AmbientProfile,
        end_min: f64,
        record_min: f64,
        step_s: f64,
    ) -> ThermalHistory {
        let mut out = self.simulate_with(
            initial_c,
            |t| ambient.at(t),
            |time_min, rhs| {
                let speed = duty.speed_at(time_min - 1e-9);
                for s in &self.sources {
                    rhs[s.body] += s.power_w(speed);
                }
            },
            end_min,
            record_min,
            step_s,
        );
        out.speed = out.time_min.iter().map(|&t| duty.speed_at(t)).collect();
        out
    }

    /// Integrates from `initial_c` with any ambient `ambient_c(t_min)` and any heat input:
    /// `add_power(t_min, rhs)` adds the power (W) each body receives over the step that ends at
    /// `t_min` to `rhs[body]` (the network's own `sources` are not used, so several inputs, e.g.
    /// a spindle speed and axis feeds, can drive their own sources). Records every `record_min`
    /// (`speed` is left empty); the step is `step_s` seconds (backward Euler, module docs).
    pub fn simulate_with(
        &self,
        initial_c: &[f64],
        ambient_c: impl Fn(f64) -> f64,
        mut add_power: impl FnMut(f64, &mut DVector<f64>),
        end_min: f64,
        record_min: f64,
        step_s: f64,
    ) -> ThermalHistory {
        let n = self.bodies.len();
        let h = step_s;
        // System matrix of backward Euler (constant over time): A T' = C/h T + G_amb T_amb + P.
        let mut a = DMatrix::<f64>::zeros(n, n);
        for (i, b) in self.bodies.iter().enumerate() {
            a[(i, i)] += b.capacity_j_per_k / h + b.to_ambient_w_per_k;
        }
        for l in &self.links {
            a[(l.a, l.a)] += l.conductance_w_per_k;
            a[(l.b, l.b)] += l.conductance_w_per_k;
            a[(l.a, l.b)] -= l.conductance_w_per_k;
            a[(l.b, l.a)] -= l.conductance_w_per_k;
        }
        let lu = a.lu();
        let mut t = DVector::from_column_slice(initial_c);
        let mut out = ThermalHistory {
            time_min: vec![],
            ambient_c: vec![],
            temps_c: vec![],
            speed: vec![],
        };
        let record = |out: &mut ThermalHistory, time: f64, t: &DVector<f64>| {
            out.time_min.push(time);
            out.ambient_c.push(ambient_c(time));
            out.temps_c.push(t.iter().copied().collect());
        };
        record(&mut out, 0.0, &t);
        let steps_per_record = (record_min * 60.0 / h).round().max(1.0) as usize;
        let records = (end_min / record_min).round() as usize;
        let mut time_min = 0.0;
        let mut rhs = DVector::<f64>::zeros(n);
        for r in 1..=records {
            for _ in 0..steps_per_record {
                time_min += h / 60.0;
                let amb = ambient_c(time_min);
                for (i, b) in self.bodies.iter().enumerate() {
                    rhs[i] = b.capacity_j_per_k / h * t[i] + b.to_ambient_w_per_k * amb;
                }
                add_power(time_min, &mut rhs);
                t = lu
                    .solve(&rhs)
                    .expect("backward-Euler matrix is strictly diagonally dominant, hence regular");
            }
            record(&mut out, r as f64 * record_min, &t);
        }
        out
    }

    /// Steady-state temperatures at a constant speed and ambient temperature (solves the
    /// heat balance with dT/dt = 0): an independent check of the integrator.
    pub fn steady_state(&self, speed: f64, ambient_c: f64) -> Vec<f64> {
        let n = self.bodies.len();
        let mut a = DMatrix::<f64>::zeros(n, n);
        let mut rhs = DVector::<f64>::zeros(n);
        for (i, b) in self.bodies.iter().enumerate() {
            a[(i, i)] += b.to_ambient_w_per_k;
            rhs[i] += b.to_ambient_w_per_k * ambient_c;
        }
        for l in &self.links {
            a[(l.a, l.a)] += l.conductance_w_per_k;
            a[(l.b, l.b)] += l.conductance_w_per_k;
            a[(l.a, l.b)] -= l.conductance_w_per_k;
            a[(l.b, l.a)] -= l.conductance_w_per_k;
        }
        for s in &self.sources {
            rhs[s.body] += s.power_w(speed);
        }
        a.lu()
            .solve(&rhs)
            .map(|v| v.iter().copied().collect())
            .unwrap_or_else(|| vec![f64::NAN; n])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_body() -> ThermalNetwork {
        ThermalNetwork {
            bodies: vec![Body {
                name: "spindle".into(),
                capacity_j_per_k: 6000.0,
                to_ambient_w_per_k: 10.0,
            }],
            links: vec![],
            sources: vec![HeatSource {
                body: 0,
                idle_w: 0.0,
                rated_w: 100.0,
                rated_speed: 1000.0,
                exponent: 1.0,
            }],
        }
    }

    #[test]
    fn single_body_follows_the_analytic_first_order_response() {
        // T(t) = T_amb + P/G (1 − exp(−t G / C)); τ = C/G = 600 s = 10 min; P/G = 10 K.
        let net = one_body();
        let hist = net.simulate(
            &[20.0],
            &DutyCycle::new(vec![(60.0, 1000.0)]),
            &AmbientProfile::constant(20.0),
            60.0,
            1.0,
            1.0,
        );
        for (k, &t) in hist.time_min.iter().enumerate() {
            let exact = 20.0 + 10.0 * (1.0 - (-t / 10.0).exp());
            // backward Euler with h = 1 s against τ = 600 s: error ≲ h/(2τ) of the step response
            assert!(
                (hist.temps_c[k][0] - exact).abs() < 0.01,
                "t={t}: {} vs {exact}",
                hist.temps_c[k][0]
            );
        }
    }

    #[test]
    fn network_reaches_its_steady_state() {
        let net = ThermalNetwork {
            bodies: vec![
                Body {
                    name: "motor".into(),
                    capacity_j_per_k: 2000.0,
                    to_ambient_w_per_k: 2.0,
                },
                Body {
                    name: "column".into(),
                    capacity_j_per_k: 20000.0,
                    to_ambient_w_per_k: 8.0,
                },
            ],
            links: vec![Link {
                a: 0,
                b: 1,
                conductance_w_per_k: 5.0,
            }],
            sources: vec![HeatSource {
                body: 0,
                idle_w: 5.0,
                rated_w: 60.0,
                rated_speed: 3000.0,
                exponent: 1.0,
            }],
        };
        let ss = net.steady_state(3000.0, 20.0);
        let hist = net.simulate(
            &[20.0, 20.0],
            &DutyCycle::new(vec![(2000.0, 3000.0)]),
            &AmbientProfile::constant(20.0),
            2000.0,
            10.0,
            10.0,
        );
        let last = hist.temps_c.last().unwrap();
        assert!(
            (last[0] - ss[0]).abs() < 1e-3 && (last[1] - ss[1]).abs() < 1e-3,
            "{last:?} vs {ss:?}"
        );
        // energy balance at steady state: all 65 W leave through the ambient conductances
        let out = 2.0 * (ss[0] - 20.0) + 8.0 * (ss[1] - 20.0);
        assert!((out - 65.0).abs() < 1e-9);
    }

    #[test]
    fn duty_cycle_and_ambient() {
        let d = DutyCycle::new(vec![(10.0, 100.0), (5.0, 0.0), (5.0, 200.0)]);
        assert_eq!(d.speed_at(0.0), 100.0);
        assert_eq!(d.speed_at(12.0), 0.0);
        assert_eq!(d.speed_at(19.9), 200.0);
        assert_eq!(d.speed_at(25.0), 0.0);
        assert_eq!(d.duration_min(), 20.0);
        let a = AmbientProfile {
            mean_c: 20.0,
            drift_c_per_h: 0.1,
            daily_amplitude_c: 1.0,
            phase_h: 0.0,
        };
        assert!((a.at(360.0) - (20.0 + 0.6 + 1.0)).abs() < 1e-12);
    }
}
