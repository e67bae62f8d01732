//! Scenario `circular-test`: an ISO 230-4 ballbar test of two linear axes (XY plane) simulated
//! in time from physical faults, with the truth a ballbar analysis should recover.
//!
//! Signal path of each axis i (X, Y), integrated in time along the programmed circle:
//!   command cᵢ(t) → servo (first-order lag, time constant τᵢ: τᵢ ṁᵢ = cᵢ − mᵢ, integrated
//!   exactly for a piecewise-linear command) → lost motion (play operator of gap gᵢ(position),
//!   the table stays put until the drive has taken up the gap) → table position qᵢ →
//!   geometry: scale error sᵢ·qᵢ, squareness e_x += α·q_y, cyclic error Aᵢ sin(2π qᵢ/Pᵢ + φᵢ).
//! The ballbar reads |tool − pivot| − R, the pivot being off the programmed centre by the set-up
//! error; Gaussian noise is added to each reading. Each direction starts 45° before the
//! recorded full circle (lead-in) so that servo and backlash are in their steady state.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::json;
use std::f64::consts::PI;
use std::fmt::Write;

/// The faults injected into the two axes (names follow the ballbar diagnostics).
#[derive(Debug, Clone, PartialEq)]
pub struct CircularFaults {
    pub scale_x_ppm: f64,
    pub scale_y_ppm: f64,
    /// e_x = α·y (µm/m).
    pub squareness_um_per_m: f64,
    /// Lost motion of X at x = +R and x = −R (µm); linear in between.
    pub backlash_x_pos_um: f64,
    pub backlash_x_neg_um: f64,
    pub backlash_y_pos_um: f64,
    pub backlash_y_neg_um: f64,
    /// Servo time constants (ms).
    pub servo_lag_x_ms: f64,
    pub servo_lag_y_ms: f64,
    /// Cyclic error of X: amplitude (µm), pitch (mm), phase (rad).
    pub cyclic_x_um: f64,
    pub cyclic_x_pitch_mm: f64,
    pub cyclic_x_phase_rad: f64,
    /// Pivot ball position relative to the programmed centre (µm).
    pub pivot_offset_um: [f64; 2],
    /// Standard deviation of the ballbar noise (µm).
    pub noise_um: f64,
}

impl CircularFaults {
    /// The faults of the `circular-test` scenario: realistic magnitudes for a machining centre.
    pub fn scenario() -> Self {
        CircularFaults {
            scale_x_ppm: 25.0,
            scale_y_ppm: -15.0,
            squareness_um_per_m: 40.0,
            backlash_x_pos_um: 6.0,
            backlash_x_neg_um: 6.0,
            backlash_y_pos_um: 5.0,
            backlash_y_neg_um: 3.0,
            servo_lag_x_ms: 16.0,
            servo_lag_y_ms: 14.0,
            cyclic_x_um: 1.5,
            cyclic_x_pitch_mm: 10.0,
            cyclic_x_phase_rad: 0.7,
            pivot_offset_um: [12.0, -7.0],
            noise_um: 0.15,
        }
    }
    /// A fault-free machine (equal servo lags, nothing else) with the same noise and set-up.
    pub fn fault_free() -> Self {
        CircularFaults {
            scale_x_ppm: 0.0,
            scale_y_ppm: 0.0,
            squareness_um_per_m: 0.0,
            backlash_x_pos_um: 0.0,
            backlash_x_neg_um: 0.0,
            backlash_y_pos_um: 0.0,
            backlash_y_neg_um: 0.0,
            servo_lag_x_ms: 15.0,
            servo_lag_y_ms: 15.0,
            cyclic_x_um: 0.0,
            cyclic_x_pitch_mm: 10.0,
            cyclic_x_phase_rad: 0.0,
            pivot_offset_um: [12.0, -7.0],
            noise_um: 0.15,
        }
    }
}

/// The programmed test.
#[derive(Debug, Clone, PartialEq)]
pub struct CircularSetup {
    pub radius_mm: f64,
    pub feed_mm_min: f64,
    /// Recorded samples per direction over 360°.
    pub samples_per_rev: usize,
}

impl Default for CircularSetup {
    fn default() -> Self {
        CircularSetup {
            radius_mm: 100.0,
            feed_mm_min: 1000.0,
            samples_per_rev: 1800,
        }
    }
}

/// Lost motion: the table `q` stays within ±gap/2 of the drive `m`, moving only when pushed.
fn play(q: f64, m: f64, gap: f64) -> f64 {
    q.clamp(m - gap / 2.0, m + gap / 2.0)
}

/// Simulates one direction (d = +1 ccw, −1 cw); returns (angle_deg, dl_um) of the recorded samples.
fn run_direction(
    setup: &CircularSetup,
    f: &CircularFaults,
    d: f64,
    rng: &mut rand::rngs::StdRng,
) -> Vec<(f64, f64)> {
    let r_mm = setup.radius_mm;
    let omega = setup.feed_mm_min / 60.0 / r_mm; // rad/s
    let lead_in = PI / 4.0;
    let sub = 20; // integration sub-steps per recorded sample
    let dtheta = 2.0 * PI / setup.samples_per_rev as f64;
    let h = dtheta / sub as f64 / omega; // s
    let gap_x = |x: f64| {
        let t = (x / r_mm).clamp(-1.0, 1.0);
        (f.backlash_x_pos_um * (1.0 + t) + f.backlash_x_neg_um * (1.0 - t)) / 2.0 / 1000.0
    };
    let gap_y = |y: f64| {
        let t = (y / r_mm).clamp(-1.0, 1.0);
        (f.backlash_y_pos_um * (1.0 + t) + f.backlash_y_neg_um * (1.0 - t)) / 2.0 / 1000.0
    };
    let cmd = |theta: f64| [r_mm * theta.cos(), r_mm * theta.sin()];
    let tau = [f.servo_lag_x_ms / 1000.0, f.servo_lag_y_ms / 1000.0];
    let noise = Normal::new(0.0, f.noise_um.max(0.0)).expect("finite noise");

    let theta0 = -d * lead_in;
    let c0 = cmd(theta0);
    let v0 = [
        -d * omega * r_mm * theta0.sin(),
        d * omega * r_mm * theta0.cos(),
    ];
    // steady state of a first-order lag on a ramp: m = c − τ·ċ; table lags by half the gap
    let mut m = [c0[0] - tau[0] * v0[0], c0[1] - tau[1] * v0[1]];
    let mut q = [
        m[0] - v0[0].signum() * gap_x(m[0]) / 2.0,
        m[1] - v0[1].signum() * gap_y(m[1]) / 2.0,
    ];
    let total_steps = ((lead_in + 2.0 * PI) / dtheta).round() as usize * sub;
    let first_record = (lead_in / dtheta).round() as usize * sub;
    let mut out = Vec::with_capacity(setup.samples_per_rev);
    let mut theta = theta0;
    for step in 0..=total_steps {
        if step >= first_record && (step - first_record) % sub == 0 {
            let k = (step - first_record) / sub;
            if k < setup.samples_per_rev {
                let ex = f.scale_x_ppm * 1e-6 * q[0]
                    + f.squareness_um_per_m * 1e-6 * q[1]
                    + f.cyclic_x_um / 1000.0
                        * (2.0 * PI * q[0] / f.cyclic_x_pitch_mm + f.cyclic_x_phase_rad).sin();
                let ey = f.scale_y_ppm * 1e-6 * q[1];
                let tool = [q[0] + ex, q[1] + ey];
                let piv = [f.pivot_offset_um[0] / 1000.0, f.pivot_offset_um[1] / 1000.0];
                let len = (tool[0] - piv[0]).hypot(tool[1] - piv[1]);
                let dl_um = (len - r_mm) * 1000.0 + noise.sample(rng);
                out.push((theta.to_degrees().rem_euclid(360.0), dl_um));
            }
        }
        // advance: command is a ramp over the sub-step (linearised chord of the arc)
        let c_a = cmd(theta);
        let theta_b = theta + d * omega * h;
        let c_b = cmd(theta_b);
        for i in 0..2 {
            let s = (c_b[i] - c_a[i]) / h;
            let e = (-h / tau[i]).exp();
            // exact solution of τ ṁ = c_a + s t − m over [0, h]
            m[i] = c_a[i] + s * h - s * tau[i] + (m[i] - c_a[i] + s * tau[i]) * e;
        }
        q = [play(q[0], m[0], gap_x(m[0])), play(q[1], m[1], gap_y(m[1]))];
        theta = theta_b;
    }
    out
}

/// The trace file (ccw run then cw run) and the truth for a setup and faults.
pub fn simulate(
    setup: &CircularSetup,
    f: &CircularFaults,
    seed: u64,
) -> (String, serde_json::Value) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut csv = String::new();
    let _ = writeln!(
        csv,
        "# ISO 230-4 circular test simulated by mtec (scenario circular-test, seed {seed})"
    );
    let _ = writeln!(csv, "# radius_mm = {}", setup.radius_mm);
    let _ = writeln!(csv, "# plane = XY");
    let _ = writeln!(csv, "# feed_mm_min = {}", setup.feed_mm_min);
    let _ = writeln!(csv, "angle_deg,direction,dl_um");
    for (d, name) in [(1.0, "ccw"), (-1.0, "cw")] {
        for (a, dl) in run_direction(setup, f, d, &mut rng) {
            let _ = writeln!(csv, "{a:.4},{name},{dl:.4}");
        }
    }
    let truth = json!({
        "format": "mtec.truth/1",
        "scenario": "circular-test",
        "radius_mm": setup.radius_mm,
        "feed_mm_min": setup.feed_mm_min,
        "plane": "XY",
        "noise_um": f.noise_um,
        "diagnostics": {
            "centre_offset_X": -f.pivot_offset_um[0],
            "centre_offset_Y": -f.pivot_offset_um[1],
            "scale_mismatch": f.scale_x_ppm - f.scale_y_ppm,
            "squareness": f.squareness_um_per_m,
            "servo_mismatch": f.servo_lag_x_ms - f.servo_lag_y_ms,
            "backlash_X_pos": f.backlash_x_pos_um,
            "backlash_X_neg": f.backlash_x_neg_um,
            "backlash_Y_pos": f.backlash_y_pos_um,
            "backlash_Y_neg": f.backlash_y_neg_um,
            "cyclic_X": f.cyclic_x_um,
            "cyclic_X_pitch_mm": f.cyclic_x_pitch_mm,
            "cyclic_Y": 0.0,
            "lateral_play_X": 0.0,
            "lateral_play_Y": 0.0,
            "reversal_spike_X": 0.0,
            "reversal_spike_Y": 0.0,
            "straightness_X": 0.0,
            "straightness_Y": 0.0,
        },
        "units": {
            "centre_offset": "um (trace centre minus pivot)", "scale_mismatch": "ppm (X minus Y)",
            "squareness": "um/m (e_x = alpha * y)", "servo_mismatch": "ms (X lag minus Y lag)",
            "backlash": "um (lost motion at the + and - end of the axis)", "cyclic": "um amplitude",
        },
        "faults": {
            "scale_x_ppm": f.scale_x_ppm, "scale_y_ppm": f.scale_y_ppm,
            "servo_lag_x_ms": f.servo_lag_x_ms, "servo_lag_y_ms": f.servo_lag_y_ms,
            "cyclic_x_phase_rad": f.cyclic_x_phase_rad,
            "pivot_offset_um": f.pivot_offset_um,
        }
    });
    (csv, truth)
}

/// Runs the scenario: `circular.csv` with injected faults and `circular-fault-free.csv`.
pub fn scenario(seed: u64) -> (Vec<(String, String)>, serde_json::Value) {
    let setup = CircularSetup::default();
    let (faulty, mut truth) = simulate(&setup, &CircularFaults::scenario(), seed);
    let (clean, truth_clean) =
        simulate(&setup, &CircularFaults::fault_free(), seed.wrapping_add(1));
    truth["fault_free"] = truth_clean["diagnostics"].clone();
    truth["files"] = json!({"circular.csv": "faults injected", "circular-fault-free.csv": "no faults (equal servo lags), same set-up and noise"});
    (
        vec![
            ("circular.csv".to_string(), faulty),
            ("circular-fault-free.csv".to_string(), clean),
        ],
        truth,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_free_noise_free_trace_is_a_centred_circle_offset() {
        // With no faults and no noise the ballbar sees only the pivot offset c:
        // dl ≈ −c·n (first order) to within |c|²/(2R) ≈ 1e-6 µm.
        let mut f = CircularFaults::fault_free();
        f.noise_um = 0.0;
        f.servo_lag_x_ms = 0.0;
        f.servo_lag_y_ms = 0.0;
        let setup = CircularSetup {
            samples_per_rev: 360,
            ..Default::default()
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        for d in [1.0, -1.0] {
            let tr = run_direction(&setup, &f, d, &mut rng);
            assert_eq!(tr.len(), 360);
            for (a, dl) in tr {
                let t = a.to_radians();
                let expect = -(f.pivot_offset_um[0] * t.cos() + f.pivot_offset_um[1] * t.sin());
                assert!((dl - expect).abs() < 1e-3, "{a}: {dl} vs {expect}");
            }
        }
    }

    #[test]
    fn backlash_gives_a_step_of_the_gap_at_the_reversal() {
        // Only X backlash b: just before θ = 0 (ccw) dl ≈ −b/2, well after it dl ≈ +b/2.
        let mut f = CircularFaults::fault_free();
        f.noise_um = 0.0;
        f.servo_lag_x_ms = 0.0;
        f.servo_lag_y_ms = 0.0;
        f.pivot_offset_um = [0.0, 0.0];
        f.backlash_x_pos_um = 8.0;
        f.backlash_x_neg_um = 8.0;
        let setup = CircularSetup {
            samples_per_rev: 3600,
            ..Default::default()
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let tr = run_direction(&setup, &f, 1.0, &mut rng);
        let at = |deg: f64| tr.iter().find(|(a, _)| (a - deg).abs() < 1e-6).unwrap().1;
        assert!(
            (at(359.0) + 4.0 * 359f64.to_radians().cos()).abs() < 0.05,
            "{}",
            at(359.0)
        );
        assert!(
            (at(5.0) - 4.0 * 5f64.to_radians().cos()).abs() < 0.05,
            "{}",
            at(5.0)
        );
    }
}
