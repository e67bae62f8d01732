//! Scenarios `circular-test` and `circular-test-arc`: an ISO 230-4 ballbar test of two linear
//! axes simulated in time from physical faults, with the truth a ballbar analysis should recover.
//!
//! Signal path of each axis i (axis 1 = "x", axis 2 = "y" of the plane), integrated in time along
//! the programmed circle or arc:
//!   command cᵢ(t) → servo (first-order lag, time constant τᵢ: τᵢ ṁᵢ = cᵢ − mᵢ, integrated
//!   exactly for a piecewise-linear command) → lost motion (play operator of gap gᵢ(position),
//!   the table stays put until the drive has taken up the gap) → table position qᵢ →
//!   geometry: scale error sᵢ·qᵢ, squareness e_x += α·q_y, cyclic error Aᵢ sin(2π qᵢ/Pᵢ + φᵢ),
//!   straightness e_y += S_x (q_x/R)², e_x += S_y (q_y/R)² →
//!   drive-direction effects: lateral play e_y −= sgn(ṁ_x)·p_x/2 (and e_x −= sgn(ṁ_y)·p_y/2),
//!   reversal spike e_i += Aᵢ·sgn(mᵢ)·exp(−(t − t_rev)/T) after drive i last reversed at t_rev.
//! The ballbar reads |tool − pivot| − R, the pivot being off the programmed centre by the set-up
//! error; Gaussian noise is added to each reading. Each direction starts 45° before the
//! recorded circle or arc (lead-in) so that servo and backlash are in their steady state; a
//! partial arc is recorded ccw from its start to its end and cw from its end to its start,
//! both ends included.

use mtec_io::CsvWriter;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::json;
use std::f64::consts::PI;

/// The faults injected into the two axes of the plane (names follow the ballbar diagnostics).
/// `x` is the plane's axis 1 and `y` its axis 2: X and Y in XY, Y and Z in YZ, Z and X in ZX.
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
    /// Cyclic error of Y: amplitude (µm), pitch (mm), phase (rad).
    pub cyclic_y_um: f64,
    pub cyclic_y_pitch_mm: f64,
    pub cyclic_y_phase_rad: f64,
    /// Reversal spike of X and Y (µm): when the axis' drive reverses, stick–slip leaves the
    /// axis this far outward (away from the centre of its travel), decaying as
    /// exp(−t/`reversal_spike_decay_ms`) while the position loop's integrator catches up.
    pub reversal_spike_x_um: f64,
    pub reversal_spike_y_um: f64,
    pub reversal_spike_decay_ms: f64,
    /// Lateral play of X (µm): the X carriage shifts along Y by −sgn(v_x)·p/2, flipping when
    /// X reverses; of Y: the Y carriage shifts along X by −sgn(v_y)·p/2.
    pub lateral_play_x_um: f64,
    pub lateral_play_y_um: f64,
    /// Straightness of X: a bow e_y = S·(x/R)² (S in µm, its value at x = ±R); of Y:
    /// e_x = S·(y/R)².
    pub straightness_x_um: f64,
    pub straightness_y_um: f64,
    /// Pivot ball position relative to the programmed centre (µm).
    pub pivot_offset_um: [f64; 2],
    /// Standard deviation of the ballbar noise (µm).
    pub noise_um: f64,
}

/// Decay time of a reversal spike (ms) that is 3° of travel — the diagnostics' spike width —
/// at the scenario's 1000 mm/min on R 100 mm: 3° · π/180 / (1000/60/100 rad/s).
pub const SPIKE_DECAY_MS: f64 = 3.0 * PI / 180.0 / (1000.0 / 60.0 / 100.0) * 1000.0;

impl CircularFaults {
    /// The faults of the `circular-test` scenario: realistic magnitudes for a machining centre.
    /// (Its files are the same as before the faults below `cyclic_x` were simulated: those are
    /// zero here; [`CircularFaults::every_fault`] adds them.)
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
            ..Self::none()
        }
    }

    /// Every fault the ballbar diagnostics know, at plausible magnitudes for a machining
    /// centre (the `circular-test-arc` scenario): the faults of [`CircularFaults::scenario`]
    /// plus a 1 µm cyclic error of Y with a 5 mm pitch (a ball screw's lead), reversal spikes
    /// of 2 µm (X) and 1.5 µm (Y) decaying over 3° of travel (a well-tuned axis shows 1–3 µm), lateral play of 2 µm (X) and
    /// 1.5 µm (Y) (a few µm is usual for worn guideways), and straightness bows of 3 µm (X)
    /// and −2 µm (Y) over ±100 mm (ISO 230-1 tolerances of a few µm per 200 mm).
    pub fn every_fault() -> Self {
        CircularFaults {
            cyclic_y_um: 1.0,
            cyclic_y_pitch_mm: 5.0,
            cyclic_y_phase_rad: 1.9,
            reversal_spike_x_um: 2.0,
            reversal_spike_y_um: 1.5,
            lateral_play_x_um: 2.0,
            lateral_play_y_um: 1.5,
            straightness_x_um: 3.0,
            straightness_y_um: -2.0,
            ..Self::scenario()
        }
    }

    /// A fault-free machine (equal servo lags, nothing else) with the same noise and set-up.
    pub fn fault_free() -> Self {
        CircularFaults {
            servo_lag_x_ms: 15.0,
            servo_lag_y_ms: 15.0,
            pivot_offset_um: [12.0, -7.0],
            noise_um: 0.15,
            ..Self::none()
        }
    }

    /// Nothing at all: no fault, no lag, no set-up error, no noise.
    pub fn none() -> Self {
        CircularFaults {
            scale_x_ppm: 0.0,
            scale_y_ppm: 0.0,
            squareness_um_per_m: 0.0,
            backlash_x_pos_um: 0.0,
            backlash_x_neg_um: 0.0,
            backlash_y_pos_um: 0.0,
            backlash_y_neg_um: 0.0,
            servo_lag_x_ms: 0.0,
            servo_lag_y_ms: 0.0,
            cyclic_x_um: 0.0,
            cyclic_x_pitch_mm: 10.0,
            cyclic_x_phase_rad: 0.0,
            cyclic_y_um: 0.0,
            cyclic_y_pitch_mm: 10.0,
            cyclic_y_phase_rad: 0.0,
            reversal_spike_x_um: 0.0,
            reversal_spike_y_um: 0.0,
            reversal_spike_decay_ms: SPIKE_DECAY_MS,
            lateral_play_x_um: 0.0,
            lateral_play_y_um: 0.0,
            straightness_x_um: 0.0,
            straightness_y_um: 0.0,
            pivot_offset_um: [0.0, 0.0],
            noise_um: 0.0,
        }
    }
}

/// The programmed test.
#[derive(Debug, Clone, PartialEq)]
pub struct CircularSetup {
    pub radius_mm: f64,
    pub feed_mm_min: f64,
    /// Recorded samples per direction over 360° (an arc gets its share, plus its end point).
    pub samples_per_rev: usize,
    /// `XY`, `YZ` or `ZX`: the plane's axis 1 and axis 2 (the faults' `x` and `y`).
    pub plane: &'static str,
    /// A partial arc (start, end) in degrees, traced ccw from start to end and cw back;
    /// `None`: the full circle.
    pub arc_deg: Option<[f64; 2]>,
    /// The scenario named in the file's first comment.
    pub scenario: &'static str,
}

impl Default for CircularSetup {
    fn default() -> Self {
        CircularSetup {
            radius_mm: 100.0,
            feed_mm_min: 1000.0,
            samples_per_rev: 1800,
            plane: "XY",
            arc_deg: None,
            scenario: "circular-test",
        }
    }
}

impl CircularSetup {
    /// The 220° arc of a vertical-plane test in ZX: from −110° to 110° (angle from Z towards X),
    /// the half of the circle above the centre and 20° below it on either side, as far as a
    /// ballbar can reach past the table.
    pub fn arc_220_zx() -> Self {
        CircularSetup {
            plane: "ZX",
            arc_deg: Some([-110.0, 110.0]),
            scenario: "circular-test-arc",
            ..Default::default()
        }
    }

    /// Names of axis 1 and axis 2.
    pub fn axes(&self) -> [String; 2] {
        let mut c = self.plane.chars();
        let a1 = c.next().unwrap_or('X').to_string();
        let a2 = c.next().unwrap_or('Y').to_string();
        [a1, a2]
    }

    /// Start (rad) and the number of recorded samples per direction.
    fn recorded(&self) -> (f64, f64, usize) {
        match self.arc_deg {
            None => (0.0, 2.0 * PI, self.samples_per_rev),
            Some([a, b]) => {
                let span = (b - a).rem_euclid(360.0);
                let n = (span / 360.0 * self.samples_per_rev as f64).round() as usize + 1;
                (a.to_radians(), span.to_radians(), n)
            }
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
    let spike_um = [f.reversal_spike_x_um, f.reversal_spike_y_um];
    let spike_tau = f.reversal_spike_decay_ms / 1000.0;

    // ccw records from the arc's start, cw from its end (the full circle: both from 0)
    let (arc_start, arc_span, n_rec) = setup.recorded();
    let rec_start = if d < 0.0 && setup.arc_deg.is_some() {
        arc_start + arc_span
    } else {
        arc_start
    };
    let theta0 = rec_start - d * lead_in;
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
    // direction of each drive, and time (s) and outward sign of its last reversal
    let mut drive_dir = [v0[0].signum(), v0[1].signum()];
    let mut reversal = [(f64::NEG_INFINITY, 0.0); 2];
    let mut time = 0.0;
    let first_record = (lead_in / dtheta).round() as usize * sub;
    let total_steps = first_record + n_rec * sub;
    let mut out = Vec::with_capacity(n_rec);
    let mut theta = theta0;
    for step in 0..=total_steps {
        if step >= first_record && (step - first_record).is_multiple_of(sub) {
            let k = (step - first_record) / sub;
            if k < n_rec {
                // outward stick–slip after the last reversal of each drive (mm)
                let spike = |i: usize| {
                    if spike_um[i] == 0.0 {
                        return 0.0;
                    }
                    let (t_rev, outward) = reversal[i];
                    spike_um[i] / 1000.0 * outward * (-(time - t_rev) / spike_tau).exp()
                };
                let (ux, uy) = (q[0] / r_mm, q[1] / r_mm);
                let ex = f.scale_x_ppm * 1e-6 * q[0]
                    + f.squareness_um_per_m * 1e-6 * q[1]
                    + f.cyclic_x_um / 1000.0
                        * (2.0 * PI * q[0] / f.cyclic_x_pitch_mm + f.cyclic_x_phase_rad).sin()
                    + f.straightness_y_um / 1000.0 * uy * uy
                    - drive_dir[1] * f.lateral_play_y_um / 2000.0
                    + spike(0);
                let ey = f.scale_y_ppm * 1e-6 * q[1]
                    + f.cyclic_y_um / 1000.0
                        * (2.0 * PI * q[1] / f.cyclic_y_pitch_mm + f.cyclic_y_phase_rad).sin()
                    + f.straightness_x_um / 1000.0 * ux * ux
                    - drive_dir[0] * f.lateral_play_x_um / 2000.0
                    + spike(1);
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
            let m_new = c_a[i] + s * h - s * tau[i] + (m[i] - c_a[i] + s * tau[i]) * e;
            let dm = m_new - m[i];
            if dm != 0.0 && dm.signum() != drive_dir[i] {
                drive_dir[i] = dm.signum();
                reversal[i] = (time + h, m_new.signum());
            }
            m[i] = m_new;
        }
        q = [play(q[0], m[0], gap_x(m[0])), play(q[1], m[1], gap_y(m[1]))];
        theta = theta_b;
        time += h;
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
    let mut comments = vec![
        format!(
            "ISO 230-4 circular test simulated by mtec (scenario {}, seed {seed})",
            setup.scenario
        ),
        format!("radius_mm = {}", setup.radius_mm),
        format!("plane = {}", setup.plane),
        format!("feed_mm_min = {}", setup.feed_mm_min),
    ];
    if let Some([a, b]) = setup.arc_deg {
        comments.push(format!("arc_start_deg = {a}"));
        comments.push(format!("arc_end_deg = {b}"));
    }
    let mut w = CsvWriter::commented(comments, ["angle_deg", "direction", "dl_um"]);
    for (d, name) in [(1.0, "ccw"), (-1.0, "cw")] {
        for (a, dl) in run_direction(setup, f, d, &mut rng) {
            w.row([format!("{a:.4}"), name.to_string(), format!("{dl:.4}")]);
        }
    }
    let csv = w.finish();
    let [a1, a2] = setup.axes();
    let mut diagnostics = serde_json::Map::new();
    let mut put = |k: String, v: f64| {
        diagnostics.insert(k, json!(v));
    };
    put(format!("centre_offset_{a1}"), -f.pivot_offset_um[0]);
    put(format!("centre_offset_{a2}"), -f.pivot_offset_um[1]);
    put("scale_mismatch".into(), f.scale_x_ppm - f.scale_y_ppm);
    put("squareness".into(), f.squareness_um_per_m);
    put("servo_mismatch".into(), f.servo_lag_x_ms - f.servo_lag_y_ms);
    put(format!("backlash_{a1}_pos"), f.backlash_x_pos_um);
    put(format!("backlash_{a1}_neg"), f.backlash_x_neg_um);
    put(format!("backlash_{a2}_pos"), f.backlash_y_pos_um);
    put(format!("backlash_{a2}_neg"), f.backlash_y_neg_um);
    put(format!("cyclic_{a1}"), f.cyclic_x_um);
    put(format!("cyclic_{a1}_pitch_mm"), f.cyclic_x_pitch_mm);
    put(format!("cyclic_{a2}"), f.cyclic_y_um);
    put(format!("cyclic_{a2}_pitch_mm"), f.cyclic_y_pitch_mm);
    put(format!("lateral_play_{a1}"), f.lateral_play_x_um);
    put(format!("lateral_play_{a2}"), f.lateral_play_y_um);
    put(format!("reversal_spike_{a1}"), f.reversal_spike_x_um);
    put(format!("reversal_spike_{a2}"), f.reversal_spike_y_um);
    put(format!("straightness_{a1}"), f.straightness_x_um);
    put(format!("straightness_{a2}"), f.straightness_y_um);
    let mut truth = json!({
        "format": "mtec.truth/1",
        "scenario": setup.scenario,
        "radius_mm": setup.radius_mm,
        "feed_mm_min": setup.feed_mm_min,
        "plane": setup.plane,
        "noise_um": f.noise_um,
        "diagnostics": diagnostics,
        "units": {
            "centre_offset": "um (trace centre minus pivot)", "scale_mismatch": "ppm (axis 1 minus axis 2)",
            "squareness": "um/m (e_1 = alpha * axis-2 position)", "servo_mismatch": "ms (axis-1 lag minus axis-2 lag)",
            "backlash": "um (lost motion at the + and - end of the axis)", "cyclic": "um amplitude",
            "lateral_play": "um (sideways shift of the carriage between its two directions)",
            "reversal_spike": "um (outward, right after the axis reverses)",
            "straightness": "um (bow of the axis at +-R: e_other = S (position/R)^2)",
        },
        "faults": {
            "scale_x_ppm": f.scale_x_ppm, "scale_y_ppm": f.scale_y_ppm,
            "servo_lag_x_ms": f.servo_lag_x_ms, "servo_lag_y_ms": f.servo_lag_y_ms,
            "cyclic_x_phase_rad": f.cyclic_x_phase_rad,
            "cyclic_y_phase_rad": f.cyclic_y_phase_rad,
            "reversal_spike_decay_ms": f.reversal_spike_decay_ms,
            "pivot_offset_um": f.pivot_offset_um,
        }
    });
    if let Some([a, b]) = setup.arc_deg {
        truth["arc_deg"] = json!({"start": a, "end": b, "span": (b - a).rem_euclid(360.0)});
    }
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

/// Runs the scenario `circular-test-arc`: `circular-arc.csv`, a 220° partial arc in the ZX
/// plane (−110° to 110°) with every fault of [`CircularFaults::every_fault`].
pub fn scenario_arc(seed: u64) -> (Vec<(String, String)>, serde_json::Value) {
    let (csv, mut truth) = simulate(
        &CircularSetup::arc_220_zx(),
        &CircularFaults::every_fault(),
        seed,
    );
    truth["files"] = json!({"circular-arc.csv": "every fault injected, 220° arc in ZX"});
    (vec![("circular-arc.csv".to_string(), csv)], truth)
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
