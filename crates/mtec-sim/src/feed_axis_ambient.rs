//! Scenario `feed-axis-ambient`: the Z feed axis of a vertical machining centre warming up at
//! four ambient temperatures (15, 20, 25, 30 °C), its position-dependent thermal error measured
//! along the axis every 10 min — the data the ambient-adaptive exponential model is fitted to.
//!
//! Physics: a lumped thermal network (see [`crate::thermal_network`]) of the upper (fixed)
//! bearing of the ball screw, the servo motor, the nut, the screw shaft and the column head,
//! driven by the axis feed. Friction heat of bearing and nut depends on the lubricant's
//! viscosity, so on the ambient temperature: their powers scale with
//! f(T_a) = 1 + 0.03·(20 − T_a) (more heat in a cold shop). The Z error at position x (mm from
//! the fixed bearing) is the screw's expansion from the fixed end plus the growth of the column
//! head that carries the bearing: δ(x) = α·x·ΔT_screw + α·L_c·ΔT_column, with α = 11.5 µm/(m·K)
//! and L_c = 300 mm; rises are from the start of the run, when the machine was in equilibrium
//! with the room. Sensors on the bearing housing (`up_c`), the nut (`nut_c`), the motor and the
//! column read their bodies (with a little mixing) plus 0.02 °C noise; the laser reading has
//! 0.3 µm noise.
//!
//! Files: `thermal.csv` (`experiment,time_min,up_c,nut_c,motor_c,column_c,ambient_c,position_mm,ez_um`),
//! one experiment per ambient level, 25 times × 11 positions (0–500 mm) each.

use crate::output::{OutputFile, ScenarioOutput, SimError};
use crate::thermal_network::{AmbientProfile, Body, DutyCycle, HeatSource, Link, ThermalNetwork};
use mtec_io::CsvWriter;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

const ALPHA_UM_PER_MM_K: f64 = 11.5e-3;
const COLUMN_MM: f64 = 300.0;
/// Ambient levels of the four runs (°C).
pub const AMBIENT_LEVELS_C: [f64; 4] = [15.0, 20.0, 25.0, 30.0];
const FEED_MM_PER_MIN: f64 = 8000.0;

/// Friction factor of the lubricated contacts at an ambient temperature (module docs).
pub fn friction_factor(ambient_c: f64) -> f64 {
    1.0 + 0.03 * (20.0 - ambient_c)
}

/// Bodies: 0 upper bearing, 1 motor, 2 nut, 3 screw, 4 column head.
fn network(ambient_c: f64) -> ThermalNetwork {
    let f = friction_factor(ambient_c);
    let src = |body, w: f64, e| HeatSource {
        body,
        idle_w: 0.0,
        rated_w: w,
        rated_speed: 10000.0,
        exponent: e,
    };
    ThermalNetwork {
        bodies: vec![
            Body::new("upper_bearing", 4.0e3, 1.0),
            Body::new("motor", 1.5e4, 3.0),
            Body::new("nut", 2.5e3, 1.5),
            Body::new("screw", 1.5e4, 3.0),
            Body::new("column_head", 3.0e5, 12.0),
        ],
        links: vec![
            Link::new(0, 4, 4.0),
            Link::new(0, 3, 2.0),
            Link::new(1, 0, 3.0),
            Link::new(2, 3, 5.0),
            Link::new(3, 4, 0.5),
        ],
        sources: vec![
            src(0, 30.0 * f, 1.5),
            src(1, 40.0, 1.0),
            src(2, 30.0 * f, 1.5),
        ],
    }
}

const SENSOR_WEIGHTS: [(&str, [f64; 5]); 4] = [
    ("up_c", [0.85, 0.0, 0.0, 0.0, 0.15]),
    ("nut_c", [0.0, 0.0, 0.9, 0.1, 0.0]),
    ("motor_c", [0.1, 0.9, 0.0, 0.0, 0.0]),
    ("column_c", [0.0, 0.0, 0.0, 0.0, 1.0]),
];

/// Noise-free Z error (µm) at position x from body rises (module docs equation).
fn error_um(x_mm: f64, rise: &[f64]) -> f64 {
    ALPHA_UM_PER_MM_K * (x_mm * rise[3] + COLUMN_MM * rise[4])
}

/// Runs the scenario.
pub fn run(seed: u64) -> Result<ScenarioOutput, SimError> {
    let mut rng = StdRng::seed_from_u64(seed);
    let temp_noise = Normal::new(0.0, 0.02).map_err(|e| SimError::Invalid(e.to_string()))?;
    let laser_noise = Normal::new(0.0, 0.3).map_err(|e| SimError::Invalid(e.to_string()))?;
    let mut csv = CsvWriter::commented(
        ["feed-axis-ambient: Z-axis thermal error at four ambient temperatures (mtec-sim)"],
        [
            "experiment",
            "time_min",
            "up_c",
            "nut_c",
            "motor_c",
            "column_c",
            "ambient_c",
            "position_mm",
            "ez_um",
        ],
    );
    let mut runs = Vec::new();
    for (e, &amb) in AMBIENT_LEVELS_C.iter().enumerate() {
        let net = network(amb);
        let init = vec![amb; net.bodies.len()];
        let duty = DutyCycle::new(vec![(240.0, FEED_MM_PER_MIN)]);
        let hist = net.simulate(
            &init,
            &duty,
            &AmbientProfile::constant(amb),
            240.0,
            10.0,
            10.0,
        );
        let mut truth_rows = Vec::new();
        for (k, t) in hist.time_min.iter().enumerate() {
            let temps = &hist.temps_c[k];
            let rise: Vec<f64> = temps.iter().zip(&init).map(|(a, b)| a - b).collect();
            let sensors: Vec<f64> = SENSOR_WEIGHTS
                .iter()
                .map(|(_, w)| {
                    w.iter().zip(temps).map(|(w, t)| w * t).sum::<f64>()
                        + temp_noise.sample(&mut rng)
                })
                .collect();
            let amb_read = hist.ambient_c[k] + temp_noise.sample(&mut rng);
            for p in 0..=10 {
                let x = 50.0 * p as f64;
                let d = error_um(x, &rise);
                truth_rows.push([*t, x, d]);
                let mut row = vec![(e + 1).to_string(), format!("{t:.1}")];
                row.extend(sensors.iter().map(|s| format!("{s:.3}")));
                row.push(format!("{amb_read:.3}"));
                row.push(format!("{x:.1}"));
                row.push(format!("{:.3}", d + laser_noise.sample(&mut rng)));
                csv.row(row);
            }
        }
        runs.push(serde_json::json!({
            "experiment": (e + 1).to_string(),
            "ambient_c": amb,
            "friction_factor": friction_factor(amb),
            "time_min_position_mm_ez_um_noise_free": truth_rows,
        }));
    }
    Ok(ScenarioOutput {
        files: vec![OutputFile {
            name: "thermal.csv".into(),
            contents: csv.finish(),
        }],
        truth: serde_json::json!({
            "scenario": "feed-axis-ambient",
            "target": "ez_um",
            "error_equation": "alpha*(x*dT_screw + L_c*dT_column_head)",
            "alpha_um_per_mm_k": ALPHA_UM_PER_MM_K,
            "column_mm": COLUMN_MM,
            "feed_mm_per_min": FEED_MM_PER_MIN,
            "sensor_weights_over_bodies": SENSOR_WEIGHTS.iter().map(|(n, w)| serde_json::json!({"sensor": n, "weights": w})).collect::<Vec<_>>(),
            "network_at_20c": network(20.0),
            "temperature_noise_c": 0.02,
            "laser_noise_um": 0.3,
            "runs": runs,
        }),
    })
}
