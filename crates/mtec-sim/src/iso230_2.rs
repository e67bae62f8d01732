//! Scenario `iso230-2`: laser-interferometer positioning runs of one linear axis (X, 0–500 mm)
//! following the ISO 230-2 test cycle: 11 targets at irregular spacing (so that periodic errors
//! are not sampled at one phase), 5 bidirectional runs (linear cycle: each run approaches every
//! target going up, then every target coming down).
//!
//! The axis: pitch error (a linear slope from ball-screw lead error, plus a periodic term of the
//! screw and a slight bow), lost motion b (the table stops short of each target by b/2 in the
//! direction of approach), a slow run-to-run drift, and interferometer noise.

use mtec_io::CsvWriter;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::json;

/// The simulated axis and measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct PositioningAxis {
    /// Ball-screw lead error (µm/m).
    pub slope_um_per_m: f64,
    /// Periodic pitch error amplitude (µm) and period (mm).
    pub periodic_um: f64,
    pub period_mm: f64,
    /// Peak deviation of a bow over the travel (µm).
    pub bow_um: f64,
    pub travel_mm: f64,
    /// Lost motion (µm).
    pub backlash_um: f64,
    /// Laser noise, one standard deviation (µm).
    pub noise_um: f64,
    pub runs: usize,
}

impl Default for PositioningAxis {
    fn default() -> Self {
        PositioningAxis {
            slope_um_per_m: 18.0,
            periodic_um: 1.2,
            period_mm: 40.0,
            bow_um: 2.0,
            travel_mm: 500.0,
            backlash_um: 3.5,
            noise_um: 0.2,
            runs: 5,
        }
    }
}

/// Irregular target positions as ISO 230-2 asks: nominal spacing plus offsets (mm).
pub fn targets_mm(travel_mm: f64) -> Vec<f64> {
    const OFFSETS: [f64; 11] = [0.0, 3.7, -2.1, 4.9, -4.3, 1.6, -3.2, 2.8, -1.4, 4.1, 0.0];
    let n = OFFSETS.len();
    (0..n)
        .map(|i| travel_mm * i as f64 / (n - 1) as f64 + OFFSETS[i])
        .collect()
}

impl PositioningAxis {
    /// Positioning error of the axis at x (µm), without lost motion.
    pub fn pitch_error_um(&self, x_mm: f64) -> f64 {
        let u = x_mm / self.travel_mm;
        self.slope_um_per_m * x_mm / 1000.0
            + self.periodic_um * (2.0 * std::f64::consts::PI * x_mm / self.period_mm).sin()
            + 4.0 * self.bow_um * u * (1.0 - u)
    }
    /// Noise-free deviation when approaching from below (`up`) or above.
    pub fn deviation_um(&self, x_mm: f64, up: bool) -> f64 {
        // the table stops b/2 short of the target in the direction of approach
        let lost = if up {
            -self.backlash_um / 2.0
        } else {
            self.backlash_um / 2.0
        };
        self.pitch_error_um(x_mm) + lost
    }
}

/// The run file and the truth.
pub fn simulate(axis: &PositioningAxis, seed: u64) -> (String, serde_json::Value) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, axis.noise_um).expect("finite noise");
    let targets = targets_mm(axis.travel_mm);
    let mut w = CsvWriter::commented(
        [
            format!("ISO 230-2 positioning runs of axis X simulated by mtec (scenario iso230-2, seed {seed})"),
            "linear cycle: each run goes up through all targets, then down".to_string(),
        ],
        ["target_mm", "run", "direction", "deviation_um"],
    );
    for run in 1..=axis.runs {
        for &t in &targets {
            let v = axis.deviation_um(t, true) + noise.sample(&mut rng);
            w.row([
                t.to_string(),
                run.to_string(),
                "+".into(),
                format!("{v:.4}"),
            ]);
        }
        for &t in targets.iter().rev() {
            let v = axis.deviation_um(t, false) + noise.sample(&mut rng);
            w.row([
                t.to_string(),
                run.to_string(),
                "-".into(),
                format!("{v:.4}"),
            ]);
        }
    }
    let csv = w.finish();
    let up: Vec<f64> = targets
        .iter()
        .map(|&t| axis.deviation_um(t, true))
        .collect();
    let down: Vec<f64> = targets
        .iter()
        .map(|&t| axis.deviation_um(t, false))
        .collect();
    let truth = json!({
        "format": "mtec.truth/1",
        "scenario": "iso230-2",
        "axis": "X",
        "targets_mm": targets,
        "mean_up_um": up,
        "mean_down_um": down,
        "reversal_um": -axis.backlash_um,
        "s_um": axis.noise_um,
        "runs_per_direction": axis.runs,
        "model": {
            "slope_um_per_m": axis.slope_um_per_m, "periodic_um": axis.periodic_um,
            "period_mm": axis.period_mm, "bow_um": axis.bow_um, "backlash_um": axis.backlash_um,
            "noise_um": axis.noise_um,
            "deviation": "slope*x/1000 + periodic*sin(2*pi*x/period) + 4*bow*u*(1-u) -/+ backlash/2 (up/down), u = x/travel",
        },
    });
    (csv, truth)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_has_every_target_in_every_pass() {
        let axis = PositioningAxis::default();
        let (csv, truth) = simulate(&axis, 3);
        let rows = csv.lines().filter(|l| !l.starts_with('#')).count() - 1;
        assert_eq!(rows, 11 * 2 * 5);
        assert_eq!(truth["mean_up_um"].as_array().unwrap().len(), 11);
        // up and down means differ by the lost motion at every target
        let up = truth["mean_up_um"][4].as_f64().unwrap();
        let down = truth["mean_down_um"][4].as_f64().unwrap();
        assert!((up - down + axis.backlash_um).abs() < 1e-12);
        // targets strictly increasing
        let t = targets_mm(500.0);
        assert!(t.windows(2).all(|w| w[1] > w[0]));
    }
}
