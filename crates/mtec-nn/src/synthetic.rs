//! A small analytic thermal model of a rotary axis, for tests, examples and benchmarks of the
//! sequence models (not the virtual machine: `mtec-sim`'s `dbb-rotary` scenario is the real
//! simulation; this only has the same *shape*: experiments × angles × time, 9 temperatures and
//! the angle in, the five error motions EXC, EYC, EZC, EAC, EBC out).
//!
//! Model: a heat input q_e(t) (the axis duty cycle of experiment e) drives nine temperatures
//! through first-order lags, T_i(t) = T_amb + g_i · lag_{τ_i}(q)(t) (exact discretisation
//! x_{t+1} = a x_t + (1 − a) u_t, a = e^{−Δt/τ}); each error motion is linear in the
//! temperatures seen through a further structural lag τ_s (the drift lags the temperature),
//! plus a harmonic of the angle (the static error motion) and a thermal × angle coupling:
//! e_k(t, θ) = Σ_i A_ki · lag_{τ_s}(T_i − T_amb)(t) · (1 + 0.3 cos θ) + B_k cos θ + C_k sin 2θ + noise.

use crate::dataset::{Experiment, Sequence, ThermalDataset};
use mtec_thermal::ThermalData;
use rand::Rng;
use rand_distr::{Distribution, Normal};

/// Shape and noise of the synthetic data.
#[derive(Debug, Clone)]
pub struct RotaryThermalSpec {
    pub angles: usize,
    pub steps: usize,
    pub dt_min: f64,
    pub structural_lag_min: f64,
    pub temperature_noise_c: f64,
    pub error_noise_um: f64,
    pub seed: u64,
}

impl Default for RotaryThermalSpec {
    fn default() -> Self {
        RotaryThermalSpec {
            angles: 12,
            steps: 49,
            dt_min: 5.0,
            structural_lag_min: 60.0,
            temperature_noise_c: 0.02,
            error_noise_um: 0.2,
            seed: 1,
        }
    }
}

/// Heat input of experiment 1..=4 at time t (0..1): four different duty cycles.
fn duty(experiment: u32, t_min: f64) -> f64 {
    match experiment {
        1 => 1.0, // full speed throughout
        2 => 0.5, // half speed throughout
        3 => {
            if t_min < 150.0 {
                0.75
            } else {
                0.0
            }
        } // 3/4 speed, then stop and cool
        _ => {
            if t_min < 120.0 {
                1.0
            } else {
                0.2
            }
        } // full speed, then idle
    }
}

/// Experiments 1..=4 of the synthetic rotary thermal model as thermal data: one sequence per
/// (experiment, angle) in that order (sequence column `angle_deg`, the angle in degrees), the
/// rows of each every `dt_min` from 0; columns `t1_c`..`t9_c`, `cos_angle`, `sin_angle`;
/// targets `exc_um` (first), `eyc_um`, `ezc_um`, `eac_urad`, `ebc_urad`.
pub fn rotary_thermal(spec: &RotaryThermalSpec) -> ThermalData {
    let angle = |k: usize| 360.0 * k as f64 / spec.angles as f64;
    rotary_dataset(spec).to_thermal_data("angle_deg", &|_, k, t| (t as f64 * spec.dt_min, angle(k)))
}

/// [`rotary_thermal`] as the training representation.
pub(crate) fn rotary_dataset(spec: &RotaryThermalSpec) -> ThermalDataset {
    let mut rng = crate::rng::seeded(spec.seed);
    let gains_c = [4.0, 3.0, 6.0, 2.5, 5.0, 1.5, 3.5, 2.0, 4.5];
    // fast sensors, slow structure: the current temperatures do not tell how far the drift is
    let taus_min = [5.0, 8.0, 10.0, 12.0, 15.0, 6.0, 9.0, 20.0, 25.0];
    // A_ki in µm/°C, B_k, C_k in µm (µrad for EAC, EBC)
    let a: Vec<Vec<f64>> = (0..5)
        .map(|_| (0..9).map(|_| rng.random_range(-0.8..0.8)).collect())
        .collect();
    let b: Vec<f64> = (0..5).map(|_| rng.random_range(-3.0..3.0)).collect();
    let c: Vec<f64> = (0..5).map(|_| rng.random_range(-1.5..1.5)).collect();
    let t_noise = Normal::new(0.0, spec.temperature_noise_c.max(1e-12)).expect("valid std");
    let e_noise = Normal::new(0.0, spec.error_noise_um.max(1e-12)).expect("valid std");
    let ambient_c = 20.0;
    let mut experiments = Vec::new();
    for id in 1..=4u32 {
        // temperatures and lagged temperatures over time (shared by every angle)
        let mut temp = vec![0.0f64; 9];
        let mut lagged = vec![0.0f64; 9];
        let mut temps_t = Vec::new();
        let mut lagged_t = Vec::new();
        for step in 0..spec.steps {
            temps_t.push(temp.clone());
            lagged_t.push(lagged.clone());
            let q = duty(id, step as f64 * spec.dt_min);
            let a_s = (-spec.dt_min / spec.structural_lag_min).exp();
            for i in 0..9 {
                let a_i = (-spec.dt_min / taus_min[i]).exp();
                lagged[i] = a_s * lagged[i] + (1.0 - a_s) * temp[i];
                temp[i] = a_i * temp[i] + (1.0 - a_i) * gains_c[i] * q;
            }
        }
        let mut sequences = Vec::new();
        for k in 0..spec.angles {
            let theta = 2.0 * std::f64::consts::PI * k as f64 / spec.angles as f64;
            let mut features = Vec::new();
            let mut targets = Vec::new();
            for step in 0..spec.steps {
                let mut f: Vec<f64> = temps_t[step]
                    .iter()
                    .map(|d| ambient_c + d + t_noise.sample(&mut rng))
                    .collect();
                f.push(theta.cos());
                f.push(theta.sin());
                features.push(f);
                let e: Vec<f64> = (0..5)
                    .map(|ch| {
                        let thermal: f64 = (0..9).map(|i| a[ch][i] * lagged_t[step][i]).sum();
                        thermal * (1.0 + 0.3 * theta.cos())
                            + b[ch] * theta.cos()
                            + c[ch] * (2.0 * theta).sin()
                            + e_noise.sample(&mut rng)
                    })
                    .collect();
                targets.push(e);
            }
            sequences.push(Sequence {
                features,
                targets,
                warmup: 0,
            });
        }
        experiments.push(Experiment { id, sequences });
    }
    let mut feature_names: Vec<String> = (1..=9).map(|i| format!("t{i}_c")).collect();
    feature_names.push("cos_angle".into());
    feature_names.push("sin_angle".into());
    ThermalDataset {
        feature_names,
        target_names: ["exc_um", "eyc_um", "ezc_um", "eac_urad", "ebc_urad"]
            .map(String::from)
            .to_vec(),
        experiments,
    }
}
