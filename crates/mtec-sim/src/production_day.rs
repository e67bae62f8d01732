//! Scenario `production-day`: a vertical machining centre through several production days, the
//! data to fit thermal models on, and one unseen day to compensate (issue 16, item 6).
//!
//! The machine: a C-frame VMC (table X on a saddle Y on the bed, the head on a Z slide on the
//! column), a 12 000 rpm motor spindle with a cooling jacket, ball-screw drives and glass scales
//! on all three axes (the scales read the slides; a scale follows the body it is mounted on).
//!
//! Physics (nothing here knows the model families mtec fits):
//! - **Thermal network** ([`crate::thermal_network`], backward Euler, 30 s step): 13 lumped
//!   bodies — front and rear spindle bearings, spindle shaft, motor, head, Z slide, the column
//!   as left, right and back walls, the Z drive (screw bearing block, nut and motor flange on
//!   the right column wall), bed, saddle, table — with conductances between them and to the air.
//! - **Heat sources**: bearing friction P = P_r (n/n_r)^(5/3) (Palmgren: the viscous friction
//!   moment grows like (ν n)^(2/3), P = M ω); motor iron losses P_r (n/n_r)^1.3 (hysteresis ∝ f,
//!   eddy currents ∝ f²) plus copper losses 120 W·load² while cutting (load per job); the axis
//!   drives' friction P_r·(v/v_r) in the Z drive, the saddle (Y nut) and the table (X nut), v
//!   the job's mean |feed| of that axis.
//! - **Unsensed bodies between sources and sensors**: bearings, shaft, Z drive, Z slide,
//!   saddle and table carry no sensor; the sensors sit on housings and walls and read a mix of
//!   the bodies next to them, so they lag the bodies that move the tool.
//! - **Ambient**: the air follows a day/night sine (maximum at 15:00) around a daily mean that
//!   changes from day to day (weather), interpolated between days.
//! - **Tool-tip drift** along X, Y, Z at a probe point (x, y, z machine coordinates, mm) from the
//!   body temperatures through the structure ([`drift_um`], ΔT from 20 °C, the reference
//!   temperature of ISO 1): the column's height and its bending by the front/back and
//!   left/right wall gradients (κ = α ΔT_wall / depth, a cantilever with the head rigidly on
//!   it), the forward growth of head and slide, the downward growth of slide, head and spindle
//!   nose, the heights of saddle and table, the column's position on the bed, and the table and
//!   saddle growing differently from the scales that read them (position-dependent).
//! - **Instruments**: temperature sensors with 0.02 °C noise, 0.01 °C resolution and a fixed
//!   calibration offset (±0.1 °C); the touch probe with 0.5 µm noise.
//!
//! Days: 00:00–06:00 the machine is off, production runs from 06:00 to 22:00 as jobs (a
//! spindle speed, feeds and a load each) with idle gaps, a lunch stop and sometimes a long stop
//! (cooling), then off again. Training days draw their speeds from a shuffle of 2000…12 000 rpm
//! in steps of 2000, then more, and run a heavy job after lunch (top speed, full load, fastest
//! feeds, the longest job): the training campaign reaches the hottest state production reaches,
//! because outside the training envelope the compensation fades. The unseen day runs
//! 3000…11 000 rpm in steps of 2000 (speeds no training day ran), in another order, starts an
//! hour later, has a two-hour stop in the afternoon and ends at 21:00. Two days before the
//! first training day warm the machine into its daily rhythm.
//!
//! Files: `train.csv` (one experiment per training day, the drift at the table-centre probe),
//! `day-state.csv` and `day-probes.csv` (the unseen day: the controller's state log and the
//! drift probed at five points), the same for `day-hot-*` (the unseen day in a shop 5 °C warmer
//! than anything in the training days), `project.toml` (the `mtec run` project that fits,
//! builds the machine model and compensates both days) and `truth.json` (network, geometry,
//! plans, noise-free drift).

use crate::output::{OutputFile, ScenarioOutput, SimError};
use crate::thermal_network::{Body, Link, ThermalHistory, ThermalNetwork};
use mtec_io::CsvWriter;
use nalgebra::DVector;
use rand::rngs::StdRng;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde::Serialize;

/// Thermal expansion of steel and cast iron, µm per mm per K.
pub const ALPHA_UM_PER_MM_K: f64 = 11.5e-3;
/// Reference temperature of the drift (ISO 1), °C.
pub const REFERENCE_C: f64 = 20.0;
/// Log interval of the controller (min).
pub const SAMPLE_MIN: f64 = 2.0;
/// Number of training days.
pub const TRAINING_DAYS: usize = 4;
/// Days simulated before the first training day (not logged).
pub const PRE_ROLL_DAYS: usize = 2;
/// How far the hot variant's ambient lies above the warmest training air (°C).
pub const HOT_MARGIN_C: f64 = 5.0;
const DAY_MIN: f64 = 1440.0;
const STEP_S: f64 = 30.0;

/// Structure (mm).
pub mod geometry {
    /// Height of the head's attachment on the column above the bed at Z = 0 (top).
    pub const H0: f64 = 950.0;
    /// From the attachment down to the tool tip: slide, head, spindle nose.
    pub const L_SLIDE: f64 = 100.0;
    pub const L_HEAD: f64 = 270.0;
    pub const L_NOSE: f64 = 80.0;
    /// Forward growth: head (guideway plane to spindle axis) and slide depth.
    pub const L_FWD_HEAD: f64 = 250.0;
    pub const L_FWD_SLIDE: f64 = 100.0;
    /// Column depth and width.
    pub const D_COL: f64 = 500.0;
    pub const W_COL: f64 = 600.0;
    /// Column centre behind the Y scale's fixed point (bed centre).
    pub const Y_COL: f64 = 450.0;
    /// Heights of saddle and table.
    pub const H_SADDLE: f64 = 150.0;
    pub const H_TABLE: f64 = 100.0;
}

/// Body indices.
mod b {
    pub const FRONT_BEARING: usize = 0;
    pub const REAR_BEARING: usize = 1;
    pub const SHAFT: usize = 2;
    pub const MOTOR: usize = 3;
    pub const HEAD: usize = 4;
    pub const SLIDE: usize = 5;
    pub const COL_LEFT: usize = 6;
    pub const COL_RIGHT: usize = 7;
    pub const COL_BACK: usize = 8;
    pub const Z_DRIVE: usize = 9;
    pub const BED: usize = 10;
    pub const SADDLE: usize = 11;
    pub const TABLE: usize = 12;
}

/// The machine's thermal network (capacities C = m·c, c ≈ 460 J/(kg K) steel, 500 cast iron;
/// conductances to the air h·A with h ≈ 8 W/(m² K), more where a fan or the cooling jacket
/// works).
pub fn network() -> ThermalNetwork {
    ThermalNetwork {
        bodies: vec![
            Body::new("front_bearing", 1.8e3, 0.3),
            Body::new("rear_bearing", 0.9e3, 0.2),
            Body::new("spindle_shaft", 5.5e3, 1.0),
            Body::new("motor", 1.6e4, 12.0),
            Body::new("head", 9.0e4, 35.0),
            Body::new("z_slide", 6.0e4, 6.0),
            Body::new("column_left", 3.0e5, 10.0),
            Body::new("column_right", 3.0e5, 10.0),
            Body::new("column_back", 5.0e5, 14.0),
            Body::new("z_drive", 7.0e3, 2.5),
            Body::new("bed", 1.25e6, 30.0),
            Body::new("saddle", 1.75e5, 8.0),
            Body::new("table", 1.5e5, 10.0),
        ],
        links: vec![
            Link::new(b::FRONT_BEARING, b::HEAD, 8.0),
            Link::new(b::FRONT_BEARING, b::SHAFT, 6.0),
            Link::new(b::REAR_BEARING, b::HEAD, 4.0),
            Link::new(b::REAR_BEARING, b::SHAFT, 3.0),
            Link::new(b::MOTOR, b::HEAD, 5.0),
            Link::new(b::MOTOR, b::SHAFT, 2.0),
            Link::new(b::HEAD, b::SLIDE, 15.0),
            Link::new(b::SLIDE, b::COL_LEFT, 3.0),
            Link::new(b::SLIDE, b::COL_RIGHT, 3.0),
            Link::new(b::Z_DRIVE, b::COL_RIGHT, 4.0),
            Link::new(b::Z_DRIVE, b::SLIDE, 1.0),
            Link::new(b::COL_LEFT, b::COL_RIGHT, 15.0),
            Link::new(b::COL_LEFT, b::COL_BACK, 12.0),
            Link::new(b::COL_RIGHT, b::COL_BACK, 12.0),
            Link::new(b::COL_LEFT, b::BED, 6.0),
            Link::new(b::COL_RIGHT, b::BED, 6.0),
            Link::new(b::COL_BACK, b::BED, 10.0),
            Link::new(b::BED, b::SADDLE, 5.0),
            Link::new(b::SADDLE, b::TABLE, 4.0),
        ],
        // the sources are driven by several inputs: see `add_power`
        sources: vec![],
    }
}

/// Rated speed of the spindle (rpm) and the powers there (W).
const SPINDLE_RATED_RPM: f64 = 12000.0;
const FRONT_BEARING_W: f64 = 180.0;
const REAR_BEARING_W: f64 = 70.0;
const MOTOR_IRON_W: f64 = 250.0;
const MOTOR_COPPER_W: f64 = 120.0;
/// Axis drives: power (W) at a mean |feed| (mm/min).
const Z_DRIVE_W: f64 = 30.0;
const Z_DRIVE_FEED: f64 = 3000.0;
const XY_DRIVE_W: f64 = 40.0;
const XY_DRIVE_FEED: f64 = 6000.0;

/// One job: a spindle speed, mean |feed| of X, Y, Z and a motor load, over a time span.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Job {
    pub start_min: f64,
    pub duration_min: f64,
    pub rpm: f64,
    pub feed_mm_min: [f64; 3],
    pub load: f64,
}

/// What runs at a time: spindle speed, feeds, load (all zero when no job runs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Duty {
    pub rpm: f64,
    pub feed_mm_min: [f64; 3],
    pub load: f64,
}

const IDLE: Duty = Duty {
    rpm: 0.0,
    feed_mm_min: [0.0; 3],
    load: 0.0,
};

/// The jobs of the whole simulated timeline (times from the start of the first pre-roll day).
#[derive(Debug, Clone, Serialize)]
pub struct Plan {
    pub jobs: Vec<Job>,
}

impl Plan {
    /// The duty over the interval that ends at `t_min` (jobs start and end on the log grid).
    pub fn duty_before(&self, t_min: f64) -> Duty {
        let t = t_min - 1e-9;
        // jobs are sorted by start; few per day, a linear scan is fine
        for j in &self.jobs {
            if t >= j.start_min && t < j.start_min + j.duration_min {
                return Duty {
                    rpm: j.rpm,
                    feed_mm_min: j.feed_mm_min,
                    load: j.load,
                };
            }
        }
        IDLE
    }
}

/// Heat (W) into each body for a duty (module docs).
fn add_power(d: &Duty, rhs: &mut DVector<f64>) {
    if d.rpm > 0.0 {
        let r = d.rpm / SPINDLE_RATED_RPM;
        rhs[b::FRONT_BEARING] += FRONT_BEARING_W * r.powf(5.0 / 3.0);
        rhs[b::REAR_BEARING] += REAR_BEARING_W * r.powf(5.0 / 3.0);
        rhs[b::MOTOR] += MOTOR_IRON_W * r.powf(1.3) + MOTOR_COPPER_W * d.load * d.load;
    }
    rhs[b::TABLE] += XY_DRIVE_W * d.feed_mm_min[0] / XY_DRIVE_FEED;
    rhs[b::SADDLE] += XY_DRIVE_W * d.feed_mm_min[1] / XY_DRIVE_FEED;
    rhs[b::Z_DRIVE] += Z_DRIVE_W * d.feed_mm_min[2] / Z_DRIVE_FEED;
}

/// Tool-tip drift [ex, ey, ez] (µm; actual − commanded, the tool relative to the workpiece) at
/// machine position `p_mm` for body temperatures `t_c` (module docs).
pub fn drift_um(t_c: &[f64], p_mm: [f64; 3]) -> [f64; 3] {
    use geometry::*;
    let a = ALPHA_UM_PER_MM_K;
    let d = |i: usize| t_c[i] - REFERENCE_C;
    let [x, y, z] = p_mm;
    let h = H0 + z; // attachment height of the head
    let l_down = L_SLIDE + L_HEAD + L_NOSE;
    let front = 0.5 * (d(b::COL_LEFT) + d(b::COL_RIGHT));
    // wall gradients bend the column: curvature κ = α ΔT / wall distance (µm/mm²)
    let kappa_y = a * (front - d(b::COL_BACK)) / D_COL;
    let kappa_x = a * (d(b::COL_RIGHT) - d(b::COL_LEFT)) / W_COL;
    // cantilever: u(h) = −κh²/2, slope −κh; the tool l_down below the attachment moves
    // u − slope·l_down = κ h (l_down − h/2); the tool l_tip in front tilts down by κ h l_tip
    let bend = |kappa: f64| kappa * h * (l_down - 0.5 * h);
    let l_tip = 0.5 * D_COL + L_FWD_HEAD;
    let ex = bend(kappa_x) + a * x * (d(b::TABLE) - d(b::SADDLE));
    let ey = bend(kappa_y)
        + a * (L_FWD_HEAD * d(b::HEAD) + L_FWD_SLIDE * d(b::SLIDE) + 0.5 * D_COL * front
            - Y_COL * d(b::BED))
        + a * y * (d(b::SADDLE) - d(b::BED));
    let ez = -kappa_y * h * l_tip
        + a * (h * front
            - L_SLIDE * d(b::SLIDE)
            - L_HEAD * d(b::HEAD)
            - L_NOSE * d(b::SHAFT)
            - H_SADDLE * d(b::SADDLE)
            - H_TABLE * d(b::TABLE));
    [ex, ey, ez]
}

/// A temperature sensor: a name and its weights over the bodies.
pub const SENSORS: [(&str, &[(usize, f64)]); 8] = [
    (
        "spindle_front_c",
        &[(b::HEAD, 0.8), (b::FRONT_BEARING, 0.2)],
    ),
    ("motor_c", &[(b::MOTOR, 0.85), (b::HEAD, 0.15)]),
    ("head_c", &[(b::HEAD, 0.7), (b::SLIDE, 0.3)]),
    ("column_left_c", &[(b::COL_LEFT, 1.0)]),
    ("column_right_c", &[(b::COL_RIGHT, 1.0)]),
    ("column_back_c", &[(b::COL_BACK, 1.0)]),
    ("bed_c", &[(b::BED, 1.0)]),
    // the air sensor reads the ambient (index usize::MAX below)
    ("air_c", &[]),
];

const TEMP_NOISE_C: f64 = 0.02;
const TEMP_OFFSET_C: f64 = 0.1;
const PROBE_NOISE_UM: f64 = 0.5;

/// The probe points (machine coordinates, mm): the table centre first, then four corners.
pub const PROBES: [(&str, [f64; 3]); 5] = [
    ("centre", [0.0, 0.0, -350.0]),
    ("x-y-", [-200.0, -150.0, -350.0]),
    ("x+y-", [200.0, -150.0, -350.0]),
    ("x-y+", [-200.0, 150.0, -350.0]),
    ("x+y+", [200.0, 150.0, -350.0]),
];

/// Round to the log grid.
fn grid(t: f64) -> f64 {
    (t / SAMPLE_MIN).round() * SAMPLE_MIN
}

/// A random job at `start` with a given speed.
fn job(rng: &mut StdRng, start: f64, rpm: f64, minutes: (f64, f64)) -> Job {
    Job {
        start_min: start,
        duration_min: grid(rng.random_range(minutes.0..minutes.1)),
        rpm,
        feed_mm_min: [
            rng.random_range(1000.0..6000.0),
            rng.random_range(1000.0..6000.0),
            rng.random_range(300.0..3000.0),
        ],
        load: rng.random_range(0.2..0.9),
    }
}

/// The heavy job of a training day (module docs): top speed, full load, the fastest feeds,
/// as long as the longest job.
fn heavy_job(start: f64) -> Job {
    Job {
        start_min: start,
        duration_min: JOB_MINUTES.1,
        rpm: SPINDLE_RATED_RPM,
        feed_mm_min: [6000.0, 6000.0, 3000.0],
        load: 0.9,
    }
}

/// Shortest and longest job (min).
const JOB_MINUTES: (f64, f64) = (40.0, 140.0);

/// Jobs of one day starting at `day_start` (module docs): `speeds` in order, shift from
/// `begin` to `end` (min after midnight), a lunch stop near 12:00 (followed by the heavy job
/// when `heavy`), and `long_stop` (start after midnight, duration) when given.
fn day_jobs(
    rng: &mut StdRng,
    day_start: f64,
    speeds: &[f64],
    (begin, end): (f64, f64),
    long_stop: Option<(f64, f64)>,
    heavy: bool,
) -> Vec<Job> {
    let mut jobs = Vec::new();
    let mut t = begin;
    let mut lunch = false;
    let mut speeds = speeds.iter();
    let mut heavy_due = heavy;
    while t < end {
        let mut j = if heavy_due && lunch {
            heavy_due = false;
            heavy_job(day_start + t)
        } else {
            match speeds.next() {
                Some(&rpm) => job(rng, day_start + t, rpm, JOB_MINUTES),
                None => break,
            }
        };
        j.duration_min = j.duration_min.min(end - t);
        if let Some((s, _)) = long_stop {
            if t < s {
                j.duration_min = j.duration_min.min(s - t);
            }
        }
        t += j.duration_min;
        jobs.push(j);
        // idle gap: set-up, tool change, inspection
        t += grid(rng.random_range(4.0..30.0));
        if !lunch && t >= 690.0 {
            t += grid(rng.random_range(40.0..60.0));
            lunch = true;
        }
        if let Some((s, d)) = long_stop {
            if t >= s && t < s + d {
                t = s + d;
            }
        }
    }
    jobs
}

/// Speeds of a training day: every training speed once, shuffled, then a few more.
fn training_speeds(rng: &mut StdRng) -> Vec<f64> {
    let set = [2000.0, 4000.0, 6000.0, 8000.0, 10000.0, 12000.0];
    let mut v = set.to_vec();
    v.shuffle(rng);
    for _ in 0..6 {
        v.push(set[rng.random_range(0..set.len())]);
    }
    v
}

/// Speeds of the unseen day: the odd thousands, in an order the training days do not follow.
fn unseen_speeds(rng: &mut StdRng) -> Vec<f64> {
    let set = [3000.0, 5000.0, 7000.0, 9000.0, 11000.0];
    // from high to low and back: a warm start, not the training days' shuffle
    let mut v = vec![11000.0, 7000.0, 3000.0, 9000.0, 5000.0];
    for _ in 0..6 {
        v.push(set[rng.random_range(0..set.len())]);
    }
    v
}

/// Ambient: day means (°C) and day/night amplitudes (°C) interpolated between days (module
/// docs); index 0 is the first pre-roll day.
#[derive(Debug, Clone, Serialize)]
pub struct Ambient {
    pub day_mean_c: Vec<f64>,
    pub day_amplitude_c: Vec<f64>,
    /// Added everywhere (the hot variant).
    pub shift_c: f64,
}

impl Ambient {
    pub fn at(&self, t_min: f64) -> f64 {
        let n = self.day_mean_c.len();
        // day values sit at noon of each day; linear in between, constant beyond
        let u = (t_min - 720.0) / DAY_MIN;
        let i = (u.floor().max(0.0) as usize).min(n - 1);
        let j = (i + 1).min(n - 1);
        let f = (u - i as f64).clamp(0.0, 1.0);
        let lerp = |v: &[f64]| v[i] + f * (v[j] - v[i]);
        let hour = (t_min / 60.0) % 24.0;
        // maximum at 15:00
        lerp(&self.day_mean_c)
            + lerp(&self.day_amplitude_c) * (2.0 * std::f64::consts::PI * (hour - 9.0) / 24.0).sin()
            + self.shift_c
    }
}

/// The whole timeline: plan and ambient of pre-roll, training and unseen days.
#[derive(Debug, Clone, Serialize)]
pub struct Timeline {
    pub plan: Plan,
    pub ambient: Ambient,
    pub days: usize,
}

/// Index of the first training day and of the unseen day in the timeline.
pub const FIRST_TRAINING_DAY: usize = PRE_ROLL_DAYS;
pub const UNSEEN_DAY: usize = PRE_ROLL_DAYS + TRAINING_DAYS;

/// The timeline of a seed.
pub fn timeline(seed: u64) -> Timeline {
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed_da7a);
    let days = UNSEEN_DAY + 1;
    let mut jobs = Vec::new();
    for d in 0..UNSEEN_DAY {
        let speeds = training_speeds(&mut rng);
        let long_stop = if rng.random_bool(0.5) {
            Some((
                grid(rng.random_range(920.0..1100.0)),
                grid(rng.random_range(60.0..150.0)),
            ))
        } else {
            None
        };
        jobs.extend(day_jobs(
            &mut rng,
            d as f64 * DAY_MIN,
            &speeds,
            (360.0, 1320.0),
            long_stop,
            true,
        ));
    }
    let speeds = unseen_speeds(&mut rng);
    jobs.extend(day_jobs(
        &mut rng,
        UNSEEN_DAY as f64 * DAY_MIN,
        &speeds,
        (420.0, 1260.0),
        Some((840.0, 120.0)),
        false,
    ));
    let mut day_mean_c: Vec<f64> = (0..UNSEEN_DAY)
        .map(|_| 21.0 + rng.random_range(-1.2..1.2))
        .collect();
    let mut day_amplitude_c: Vec<f64> = (0..UNSEEN_DAY)
        .map(|_| rng.random_range(0.8..2.0))
        .collect();
    // the unseen day is an ordinary day: mean and amplitude inside the training days' ranges
    let median = |v: &[f64]| {
        let mut s = v[FIRST_TRAINING_DAY..].to_vec();
        s.sort_by(f64::total_cmp);
        0.5 * (s[(s.len() - 1) / 2] + s[s.len() / 2])
    };
    let (m, a) = (median(&day_mean_c), median(&day_amplitude_c));
    day_mean_c.push(m);
    day_amplitude_c.push(a);
    Timeline {
        plan: Plan { jobs },
        ambient: Ambient {
            day_mean_c,
            day_amplitude_c,
            shift_c: 0.0,
        },
        days,
    }
}

/// Simulates the timeline from equilibrium with the first ambient, logged every
/// [`SAMPLE_MIN`].
pub fn simulate(t: &Timeline) -> ThermalHistory {
    let net = network();
    let a0 = t.ambient.at(0.0);
    let init = vec![a0; net.bodies.len()];
    net.simulate_with(
        &init,
        |m| t.ambient.at(m),
        |m, rhs| add_power(&t.plan.duty_before(m), rhs),
        t.days as f64 * DAY_MIN,
        SAMPLE_MIN,
        STEP_S,
    )
}

/// Sensor readings at one record: noise, resolution 0.01 °C, calibration offsets.
fn read_sensors(
    temps: &[f64],
    ambient: f64,
    offsets: &[f64],
    noise: &Normal<f64>,
    rng: &mut StdRng,
) -> Vec<f64> {
    SENSORS
        .iter()
        .zip(offsets)
        .map(|((_, w), off)| {
            let truth = if w.is_empty() {
                ambient
            } else {
                w.iter().map(|&(i, c)| c * temps[i]).sum()
            };
            ((truth + off + noise.sample(rng)) * 100.0).round() / 100.0
        })
        .collect()
}

/// Rows (record indices) of day `d`: from its midnight to the last record before the next.
fn day_rows(h: &ThermalHistory, d: usize) -> Vec<usize> {
    let (a, z) = (d as f64 * DAY_MIN, (d + 1) as f64 * DAY_MIN);
    (0..h.time_min.len())
        .filter(|&k| h.time_min[k] >= a - 1e-9 && h.time_min[k] < z - 1e-9)
        .collect()
}

/// The columns of the controller's state: the sensors, the spindle speed and the feeds.
fn header_inputs() -> impl Iterator<Item = &'static str> {
    let duty = [
        "spindle_rpm",
        "x_feed_mm_min",
        "y_feed_mm_min",
        "z_feed_mm_min",
    ];
    SENSORS.iter().map(|s| s.0).chain(duty)
}

/// The fields of [`header_inputs`]: temperatures to 0.01 °C, speed and feeds to units.
fn inputs<'a>(sensors: &'a [f64], d: &Duty) -> impl Iterator<Item = String> + 'a {
    let duty = [d.rpm, d.feed_mm_min[0], d.feed_mm_min[1], d.feed_mm_min[2]];
    let temps = sensors.iter().map(|s| format!("{s:.2}"));
    temps.chain(duty.map(|v| format!("{v:.0}")))
}

/// The unseen day's files: state log, probe readings, noise-free drift `[record][probe][axis]`.
struct DayFiles {
    state: String,
    probes: String,
    truth: Vec<Vec<[f64; 3]>>,
}

/// The unseen day of a simulated history (see [`DayFiles`]).
fn unseen_day_files(
    t: &Timeline,
    h: &ThermalHistory,
    offsets: &[f64],
    rng: &mut StdRng,
    comment: &str,
) -> Result<DayFiles, SimError> {
    let tn = Normal::new(0.0, TEMP_NOISE_C).map_err(|e| SimError::Invalid(e.to_string()))?;
    let pn = Normal::new(0.0, PROBE_NOISE_UM).map_err(|e| SimError::Invalid(e.to_string()))?;
    let mut state = CsvWriter::commented(
        [format!(
            "{comment}: the controller's state log (mtec-sim production-day)"
        )],
        std::iter::once("time_min").chain(header_inputs()),
    );
    let mut probes = CsvWriter::commented(
        [format!("{comment}: tool-tip drift probed at five points, actual - commanded (mtec-sim production-day)")],
        ["time_min", "probe", "x_mm", "y_mm", "z_mm", "ex_um", "ey_um", "ez_um"],
    );
    let mut truth = Vec::new();
    let day0 = UNSEEN_DAY as f64 * DAY_MIN;
    for k in day_rows(h, UNSEEN_DAY) {
        let tm = h.time_min[k] - day0;
        let temps = &h.temps_c[k];
        let s = read_sensors(temps, h.ambient_c[k], offsets, &tn, rng);
        let duty = t.plan.duty_before(h.time_min[k]);
        state.row(std::iter::once(format!("{tm:.0}")).chain(inputs(&s, &duty)));
        let mut at = Vec::new();
        for (name, p) in PROBES {
            let e = drift_um(temps, p);
            let mut row = vec![format!("{tm:.0}"), name.to_string()];
            row.extend(p.iter().map(|v| format!("{v:.1}")));
            // the noise of x, then y, then z
            row.extend(e.map(|v| format!("{:.2}", v + pn.sample(rng))));
            probes.row(row);
            at.push(e);
        }
        truth.push(at);
    }
    Ok(DayFiles {
        state: state.finish(),
        probes: probes.finish(),
        truth,
    })
}

/// The `mtec run` project the scenario writes (see docs/formats.md, Project TOML).
pub const PROJECT_TOML: &str = r#"# production-day: fit thermal models on the training days, build the machine model, compensate
# the unseen day (and the same day in a shop 5 C warmer) through the real-time code path.
name = "production day"

[[thermal]]
data = "train.csv"
target = "dx_um"
model = "mlr"
lag = true

[[thermal]]
data = "train.csv"
target = "dy_um"
model = "mlr"
lag = true

[[thermal]]
data = "train.csv"
target = "dz_um"
model = "mlr"
lag = true

[machine_model]
data = "train.csv"
parts = [
  { target = "dx_um", axis = "x" },
  { target = "dy_um", axis = "y" },
  { target = "dz_um", axis = "z" },
]

[[replay]]
name = "unseen day"
state = "day-state.csv"
probes = "day-probes.csv"

[[replay]]
name = "unseen day, shop 5 C warmer than the training days"
state = "day-hot-state.csv"
probes = "day-hot-probes.csv"
"#;

/// Runs the scenario.
pub fn run(seed: u64) -> Result<ScenarioOutput, SimError> {
    let t = timeline(seed);
    let h = simulate(&t);
    let mut rng = StdRng::seed_from_u64(seed);
    let offsets: Vec<f64> = SENSORS
        .iter()
        .map(|_| rng.random_range(-TEMP_OFFSET_C..TEMP_OFFSET_C))
        .collect();
    let tn = Normal::new(0.0, TEMP_NOISE_C).map_err(|e| SimError::Invalid(e.to_string()))?;
    let pn = Normal::new(0.0, PROBE_NOISE_UM).map_err(|e| SimError::Invalid(e.to_string()))?;

    // training days: one experiment each, the drift at the table-centre probe
    let mut train = CsvWriter::commented(
        [format!("production-day (seed {seed}): {TRAINING_DAYS} training days of a VMC, drift at the table-centre probe (mtec-sim)")],
        ["experiment", "time_min"]
            .into_iter()
            .chain(header_inputs())
            .chain(["dx_um", "dy_um", "dz_um"]),
    );
    let mut train_air = (f64::INFINITY, f64::NEG_INFINITY);
    let mut train_truth = Vec::new();
    for d in FIRST_TRAINING_DAY..UNSEEN_DAY {
        let day0 = d as f64 * DAY_MIN;
        let mut rows = Vec::new();
        for k in day_rows(&h, d) {
            let temps = &h.temps_c[k];
            let s = read_sensors(temps, h.ambient_c[k], &offsets, &tn, &mut rng);
            train_air = (train_air.0.min(s[7]), train_air.1.max(s[7]));
            let e = drift_um(temps, PROBES[0].1);
            let mut row = vec![
                format!("day{}", d - FIRST_TRAINING_DAY + 1),
                format!("{:.0}", h.time_min[k] - day0),
            ];
            row.extend(inputs(&s, &t.plan.duty_before(h.time_min[k])));
            // the noise of x, then y, then z
            row.extend(e.map(|v| format!("{:.2}", v + pn.sample(&mut rng))));
            train.row(row);
            rows.push(e);
        }
        train_truth.push(rows);
    }
    let day = unseen_day_files(
        &t,
        &h,
        &offsets,
        &mut rng,
        &format!("production-day (seed {seed}), unseen day"),
    )?;

    // the same timeline in a shop whose air stays HOT_MARGIN_C above the warmest training air
    // all through the unseen day
    let unseen: Vec<usize> = day_rows(&h, UNSEEN_DAY);
    let unseen_min = unseen
        .iter()
        .map(|&k| h.ambient_c[k])
        .fold(f64::INFINITY, f64::min);
    let mut hot = t.clone();
    hot.ambient.shift_c = train_air.1 - unseen_min + HOT_MARGIN_C + TEMP_OFFSET_C + 0.1;
    let hh = simulate(&hot);
    let hot_day = unseen_day_files(
        &hot,
        &hh,
        &offsets,
        &mut rng,
        &format!("production-day (seed {seed}), unseen day in a shop 5 C warmer"),
    )?;

    let file = |name: &str, contents: String| OutputFile {
        name: name.into(),
        contents,
    };
    let day_jobs: Vec<&Job> = t
        .plan
        .jobs
        .iter()
        .filter(|j| j.start_min >= FIRST_TRAINING_DAY as f64 * DAY_MIN)
        .collect();
    Ok(ScenarioOutput {
        files: vec![
            file("train.csv", train.finish()),
            file("day-state.csv", day.state),
            file("day-probes.csv", day.probes),
            file("day-hot-state.csv", hot_day.state),
            file("day-hot-probes.csv", hot_day.probes),
            file("project.toml", PROJECT_TOML.to_string()),
        ],
        truth: serde_json::json!({
            "scenario": "production-day",
            "seed": seed,
            "alpha_um_per_mm_k": ALPHA_UM_PER_MM_K,
            "reference_c": REFERENCE_C,
            "sample_min": SAMPLE_MIN,
            "network": network(),
            "sources": {
                "spindle_rated_rpm": SPINDLE_RATED_RPM,
                "front_bearing_w": FRONT_BEARING_W, "rear_bearing_w": REAR_BEARING_W,
                "bearing_exponent": 5.0 / 3.0,
                "motor_iron_w": MOTOR_IRON_W, "motor_iron_exponent": 1.3,
                "motor_copper_w_at_full_load": MOTOR_COPPER_W,
                "z_drive_w": Z_DRIVE_W, "z_drive_feed_mm_min": Z_DRIVE_FEED,
                "xy_drive_w": XY_DRIVE_W, "xy_drive_feed_mm_min": XY_DRIVE_FEED,
            },
            "geometry_mm": {
                "h0": geometry::H0, "l_slide": geometry::L_SLIDE, "l_head": geometry::L_HEAD,
                "l_nose": geometry::L_NOSE, "l_fwd_head": geometry::L_FWD_HEAD,
                "l_fwd_slide": geometry::L_FWD_SLIDE, "d_col": geometry::D_COL,
                "w_col": geometry::W_COL, "y_col": geometry::Y_COL,
                "h_saddle": geometry::H_SADDLE, "h_table": geometry::H_TABLE,
            },
            "sensors": SENSORS.iter().map(|(n, w)| serde_json::json!({"sensor": n, "weights": w})).collect::<Vec<_>>(),
            "sensor_offsets_c": offsets,
            "temperature_noise_c": TEMP_NOISE_C,
            "probe_noise_um": PROBE_NOISE_UM,
            "probes": PROBES.iter().map(|(n, p)| serde_json::json!({"probe": n, "position_mm": p})).collect::<Vec<_>>(),
            "training_days": TRAINING_DAYS,
            "pre_roll_days": PRE_ROLL_DAYS,
            "jobs_from_first_training_day": day_jobs,
            "ambient": t.ambient,
            "hot_shift_c": hot.ambient.shift_c,
            "training_air_range_c": [train_air.0, train_air.1],
            "train_drift_um_noise_free": train_truth,
            "day_drift_um_noise_free": day.truth,
            "day_hot_drift_um_noise_free": hot_day.truth,
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_machine_at_the_reference_temperature_has_no_drift_and_a_uniform_rise_bends_nothing() {
        let n = network().bodies.len();
        for (_, p) in PROBES {
            assert_eq!(drift_um(&vec![REFERENCE_C; n], p), [0.0; 3]);
        }
        // every body 3 K warmer: no wall gradient, table and saddle like their scales; what is
        // left is the uniform growth of the loop: ey = α·3·(L_fwd,head + L_fwd,slide + D/2 − Y_col),
        // ez = α·3·(h − L_slide − L_head − L_nose − H_saddle − H_table), the same at every probe
        use geometry::*;
        let a = ALPHA_UM_PER_MM_K * 3.0;
        for (_, p) in PROBES {
            let e = drift_um(&vec![REFERENCE_C + 3.0; n], p);
            let h = H0 + p[2];
            assert!(e[0].abs() < 1e-12, "{e:?}");
            assert!((e[1] - a * (L_FWD_HEAD + L_FWD_SLIDE + 0.5 * D_COL - Y_COL)).abs() < 1e-12);
            assert!(
                (e[2] - a * (h - L_SLIDE - L_HEAD - L_NOSE - H_SADDLE - H_TABLE)).abs() < 1e-12
            );
        }
    }

    #[test]
    fn column_bending_matches_a_beam_integrated_numerically() {
        // front walls 2 K warmer than the back wall: curvature κ = α·2/D along the whole column.
        // Integrate u'' = −κ from the clamped base (u = u' = 0) with small steps, carry the tool
        // rigidly with the head (l_down below, l_tip in front of the column axis) and compare.
        use geometry::*;
        let n = network().bodies.len();
        let mut t = vec![REFERENCE_C; n];
        t[b::COL_LEFT] += 2.0;
        t[b::COL_RIGHT] += 2.0;
        let p = PROBES[0].1;
        let h = H0 + p[2];
        let kappa = ALPHA_UM_PER_MM_K * 2.0 / D_COL; // µm/mm²
        let steps = 100_000;
        let dh = h / steps as f64;
        let (mut u, mut slope) = (0.0, 0.0);
        for _ in 0..steps {
            // exact for constant curvature: u += slope·dh − κ dh²/2
            u += slope * dh - 0.5 * kappa * dh * dh;
            slope -= kappa * dh;
        }
        let l_down = L_SLIDE + L_HEAD + L_NOSE;
        let l_tip = 0.5 * D_COL + L_FWD_HEAD;
        // tool below and in front of the attachment: Δy = u + slope·(−l_down), Δz = −slope·l_tip
        let want_y = u - slope * l_down;
        let want_z = -slope * l_tip;
        // what the walls' own growth adds (no bending): forward growth of the front face and the
        // column's height up to the head
        let growth_y = ALPHA_UM_PER_MM_K * 0.5 * D_COL * 2.0;
        let growth_z = ALPHA_UM_PER_MM_K * h * 2.0;
        let e = drift_um(&t, p);
        assert!((e[1] - growth_y - want_y).abs() < 1e-9, "{e:?} vs {want_y}");
        assert!((e[2] - growth_z + want_z).abs() < 1e-9, "{e:?} vs {want_z}");
        // the tilt carries the tool forward (+Y) although the column's top leans back
        assert!(u < 0.0 && want_y > 0.0);
    }

    #[test]
    fn the_days_follow_the_plan() {
        for seed in 1..=8 {
            let t = timeline(seed);
            let day_of = |j: &Job| (j.start_min / DAY_MIN).floor() as usize;
            let training: Vec<&Job> = t
                .plan
                .jobs
                .iter()
                .filter(|j| (FIRST_TRAINING_DAY..UNSEEN_DAY).contains(&day_of(j)))
                .collect();
            let unseen: Vec<&Job> = t
                .plan
                .jobs
                .iter()
                .filter(|j| day_of(j) == UNSEEN_DAY)
                .collect();
            // jobs on the log grid, inside the shift, never overlapping
            for w in t.plan.jobs.windows(2) {
                assert!(w[0].start_min + w[0].duration_min <= w[1].start_min);
            }
            for j in &t.plan.jobs {
                let m = j.start_min % DAY_MIN;
                assert!(m >= 360.0 && m + j.duration_min <= 1320.0, "{j:?}");
                assert_eq!(j.start_min % SAMPLE_MIN, 0.0);
                assert_eq!(j.duration_min % SAMPLE_MIN, 0.0);
                assert!(j.duration_min > 0.0);
            }
            // every training speed runs on the training days; the unseen day's speeds never
            // ran there, and it runs them in another order (not rising, not the training shuffle)
            for s in [2000.0, 4000.0, 6000.0, 8000.0, 10000.0, 12000.0] {
                assert!(
                    training.iter().filter(|j| j.rpm == s).count() >= 2,
                    "seed {seed}: {s}"
                );
            }
            assert!(unseen.len() >= 5);
            for j in &unseen {
                assert!(training.iter().all(|k| k.rpm != j.rpm), "seed {seed}");
                assert!(j.rpm >= 3000.0 && j.rpm <= 11000.0);
            }
            assert_eq!(unseen[0].rpm, 11000.0);
            // the unseen day stops for two hours at 14:00 (cooling)
            let day0 = UNSEEN_DAY as f64 * DAY_MIN;
            assert!(unseen.iter().all(
                |j| j.start_min + j.duration_min <= day0 + 840.0 || j.start_min >= day0 + 960.0
            ));
        }
    }

    #[test]
    fn the_hot_day_stays_five_degrees_above_the_training_air_and_seeds_repeat() {
        let out = run(3).unwrap();
        let again = run(3).unwrap();
        let col = |name: &str, c: &str| -> Vec<f64> {
            let f = out.files.iter().find(|f| f.name == name).unwrap();
            let mut lines = f.contents.lines().filter(|l| !l.starts_with('#'));
            let header: Vec<&str> = lines.next().unwrap().split(',').collect();
            let i = header.iter().position(|h| *h == c).unwrap();
            lines
                .map(|l| l.split(',').nth(i).unwrap().parse().unwrap())
                .collect()
        };
        let train_max = col("train.csv", "air_c")
            .into_iter()
            .fold(f64::MIN, f64::max);
        let hot_min = col("day-hot-state.csv", "air_c")
            .into_iter()
            .fold(f64::MAX, f64::min);
        assert!(
            hot_min >= train_max + HOT_MARGIN_C,
            "{hot_min} vs {train_max}"
        );
        // 4 training days and the unseen day at 2-min samples, 5 probes
        assert_eq!(col("train.csv", "dz_um").len(), 4 * 720);
        assert_eq!(col("day-state.csv", "air_c").len(), 720);
        assert_eq!(col("day-probes.csv", "ez_um").len(), 5 * 720);
        for (a, b) in out.files.iter().zip(&again.files) {
            assert_eq!(a.contents, b.contents);
        }
        let other = run(4).unwrap();
        assert_ne!(out.files[0].contents, other.files[0].contents);
    }
}
