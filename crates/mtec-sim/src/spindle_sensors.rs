//! Scenario `spindle-sensors`: eight temperature sensors on a turning centre's headstock and bed,
//! strongly collinear (VIF ≫ 10), and the radial thermal drift of the spindle — the setting of
//! the source's ridge-regression sensor-placement study (8 sensors, ~120 samples at 1 min).
//!
//! Physics: a lumped thermal network (see [`crate::thermal_network`]) of front bearing, rear
//! bearing, spindle motor, headstock housing, and bed, driven by the spindle speed. The radial
//! drift of the spindle nose (X, µm) is the thermal expansion of the headstock height between
//! bed and spindle axis minus the bending of the bed top under its own gradient:
//! δ = α·H·ΔT_housing + α·h_f·ΔT_front − α·B·ΔT_bed  (α = 11.5 µm/(m·K) steel, H = 250 mm housing
//! height, h_f = 60 mm bearing seat, B = 500 mm of bed), temperatures rises from the cold start.
//! Sensors read a weighted mix of the bodies next to them (a sensor sits on a surface between
//! bodies) plus 0.02 °C noise; the drift probe has 0.3 µm noise.
//!
//! Files: `thermal.csv` (`experiment,time_min,s1_c…s8_c,ambient_c,radial_um`): experiment 1 is
//! the training run (120 min, speed steps, the shop warming 1.2 °C/h), experiment 2 an unseen
//! duty cycle (with a stop) in a cooling shop (−0.6 °C/h) for testing. Both start at 21 °C.
//! `truth.json` holds the network, the sensor mixing weights, and the noise-free drift.

use crate::output::{OutputFile, ScenarioOutput, SimError};
use crate::thermal_network::{AmbientProfile, Body, DutyCycle, HeatSource, Link, ThermalNetwork};
use mtec_io::CsvWriter;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// Thermal expansion of steel, µm per mm per K.
const ALPHA_UM_PER_MM_K: f64 = 11.5e-3;
const HOUSING_MM: f64 = 250.0;
const BEARING_SEAT_MM: f64 = 60.0;
const BED_MM: f64 = 500.0;

/// Bodies: 0 front bearing, 1 rear bearing, 2 motor, 3 housing, 4 bed.
fn network() -> ThermalNetwork {
    ThermalNetwork {
        bodies: vec![
            Body::new("front_bearing", 9.0e3, 1.0),
            Body::new("rear_bearing", 7.0e3, 0.8),
            Body::new("motor", 2.0e4, 3.0),
            Body::new("housing", 2.4e5, 6.0),
            Body::new("bed", 1.5e6, 12.0),
        ],
        links: vec![
            Link::new(0, 3, 9.0),
            Link::new(1, 3, 6.0),
            Link::new(2, 3, 4.0),
            Link::new(2, 1, 2.0),
            Link::new(3, 4, 10.0),
        ],
        sources: vec![
            HeatSource {
                body: 0,
                idle_w: 0.0,
                rated_w: 150.0,
                rated_speed: 4000.0,
                exponent: 1.5,
            },
            HeatSource {
                body: 1,
                idle_w: 0.0,
                rated_w: 90.0,
                rated_speed: 4000.0,
                exponent: 1.5,
            },
            HeatSource {
                body: 2,
                idle_w: 5.0,
                rated_w: 160.0,
                rated_speed: 4000.0,
                exponent: 1.0,
            },
        ],
    }
}

/// Sensor mixing weights over the five bodies (each row sums to 1).
pub const SENSOR_WEIGHTS: [[f64; 5]; 8] = [
    [0.85, 0.0, 0.0, 0.15, 0.0], // s1 front bearing ring
    [0.55, 0.0, 0.0, 0.45, 0.0], // s2 front housing flange
    [0.0, 0.0, 0.0, 1.0, 0.0],   // s3 headstock top
    [0.0, 0.8, 0.0, 0.2, 0.0],   // s4 rear bearing cap
    [0.0, 0.2, 0.7, 0.1, 0.0],   // s5 motor flange
    [0.0, 0.0, 0.0, 0.6, 0.4],   // s6 headstock foot
    [0.0, 0.0, 0.0, 0.15, 0.85], // s7 bed under the headstock
    [0.0, 0.0, 0.0, 0.0, 1.0],   // s8 bed, far end
];

/// Noise-free radial drift (µm) from body-temperature rises (module docs equation).
fn drift_um(rise: &[f64]) -> f64 {
    ALPHA_UM_PER_MM_K * (HOUSING_MM * rise[3] + BEARING_SEAT_MM * rise[0] - BED_MM * rise[4])
}

/// Runs the scenario.
pub fn run(seed: u64) -> Result<ScenarioOutput, SimError> {
    let net = network();
    let mut rng = StdRng::seed_from_u64(seed);
    let temp_noise = Normal::new(0.0, 0.02).map_err(|e| SimError::Invalid(e.to_string()))?;
    let probe_noise = Normal::new(0.0, 0.3).map_err(|e| SimError::Invalid(e.to_string()))?;
    let experiments = [
        (
            "1",
            DutyCycle::new(vec![(40.0, 2000.0), (40.0, 4000.0), (40.0, 1000.0)]),
            1.2,
        ),
        (
            "2",
            DutyCycle::new(vec![(30.0, 3000.0), (30.0, 0.0), (60.0, 3500.0)]),
            -0.6,
        ),
    ];
    let mut csv = CsvWriter::commented(
        ["spindle-sensors: radial spindle drift and 8 collinear temperature sensors (mtec-sim)"],
        [
            "experiment",
            "time_min",
            "s1_c",
            "s2_c",
            "s3_c",
            "s4_c",
            "s5_c",
            "s6_c",
            "s7_c",
            "s8_c",
            "ambient_c",
            "radial_um",
        ],
    );
    let mut truth_runs = Vec::new();
    let amb_c = &21.0;
    for (id, duty, amb_drift) in &experiments {
        let ambient = AmbientProfile {
            mean_c: *amb_c,
            drift_c_per_h: *amb_drift,
            daily_amplitude_c: 0.0,
            phase_h: 0.0,
        };
        let init = vec![*amb_c; net.bodies.len()];
        let hist = net.simulate(&init, duty, &ambient, 120.0, 1.0, 5.0);
        let mut drift = Vec::new();
        for (k, t) in hist.time_min.iter().enumerate() {
            let temps = &hist.temps_c[k];
            let rise: Vec<f64> = temps.iter().zip(&init).map(|(a, b)| a - b).collect();
            let d = drift_um(&rise);
            drift.push(d);
            let mut row = vec![id.to_string(), format!("{t:.1}")];
            for w in SENSOR_WEIGHTS {
                let s: f64 = w.iter().zip(temps).map(|(w, t)| w * t).sum();
                row.push(format!("{:.3}", s + temp_noise.sample(&mut rng)));
            }
            // the ambient reading's noise is drawn before the probe's
            row.push(format!(
                "{:.3}",
                hist.ambient_c[k] + temp_noise.sample(&mut rng)
            ));
            row.push(format!("{:.3}", d + probe_noise.sample(&mut rng)));
            csv.row(row);
        }
        truth_runs.push(serde_json::json!({
            "experiment": id,
            "duty_cycle_min_rpm": duty.segments,
            "ambient_start_c": amb_c,
            "ambient_drift_c_per_h": amb_drift,
            "radial_um_noise_free": drift,
        }));
    }
    Ok(ScenarioOutput {
        files: vec![OutputFile {
            name: "thermal.csv".into(),
            contents: csv.finish(),
        }],
        truth: serde_json::json!({
            "scenario": "spindle-sensors",
            "target": "radial_um",
            "drift_equation": "alpha*(H*dT_housing + h_f*dT_front_bearing - B*dT_bed)",
            "alpha_um_per_mm_k": ALPHA_UM_PER_MM_K,
            "housing_mm": HOUSING_MM,
            "bearing_seat_mm": BEARING_SEAT_MM,
            "bed_mm": BED_MM,
            "sensor_weights_over_bodies": SENSOR_WEIGHTS,
            "network": net,
            "temperature_noise_c": 0.02,
            "probe_noise_um": 0.3,
            "runs": truth_runs,
        }),
    })
}
