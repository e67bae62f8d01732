//! Scenario `dbb-rotary`: ballbar measurements of a rotary C axis, static and thermal.
//!
//! The machine: a C-axis rotary table with static error motions (harmonics 1–6 of a few µm and
//! tens of µrad, the part above the first harmonic is what the ballbar method recovers) and
//! thermal changes driven by a lumped thermal network ([`crate::thermal_network`]): the C motor
//! heats most (> 7 °C at the top speed), the axis bearing and the table 3–4 °C, the bed and the
//! ambient air less than 1 °C.
//!
//! The campaign: four experiments at 10, 20, 30, 40 rpm, each 4 h from a cold machine, a
//! measurement every 20 min (13 times); each measurement installs the bar in the five modes of
//! the source layout (preset h = 100 mm, a = 300 mm, b = 500 mm, so k = 400 mm; second mount at
//! 0°, 120°, 240°)
//! and reads it every 5° over one revolution. Each installation has its own set-up error (ball
//! and cup eccentricity ~10 µm, zero offset ~1 µm); the tool side drifts with the spindle head;
//! the ballbar reads with 0.1 µm noise; nine temperature sensors T1…T9 read with 0.03 °C noise.
//! Bar lengths are exact (rigid-body transforms, nothing linearised).
//!
//! Files: `setup.toml` (the modes), `dbb.csv` (`experiment,time_min,mode,angle_deg,dl_um`),
//! `temps.csv` (`experiment,time_min,T1_c…T9_c`), and the truth: the error motions `EXC EYC EZC`
//! (µm), `EAC EBC ECC` (µrad) per experiment/time/angle, the body temperatures, and every
//! installation's set-up error.
//!
//! Error-motion model (truth), with ΔT the rises of bearing (b), table (t), motor (m) over the
//! start of the experiment:
//! `E(C, T) = (1 + 0.04·ΔT_b)·E_static(C) + ΔT_b·E_bearing(C) + ΔT_t·E_growth + ΔT_m·E_tilt`
//! where `E_bearing` holds harmonics 2–3 (the thermal change the method sees), `E_growth` the
//! uniform axial growth and radial shift, `E_tilt` a constant tilt (both removed with the set-up
//! error, see `mtec_identify::ballbar::harmonics`).
//!
//! The five-axis calibration ([`five_axis_calibration`], same seed, same truth, cold start of
//! experiment 1): six more installations ([`supplement_modes`]) that make every motion harmonic
//! observable except the co-rotating first harmonic (the table's own frame), read like the
//! campaign's, and an ISO 230-2 rotary positioning test of C (36 targets, 5 runs each way)
//! against a reference instrument with a smooth error of at most ±1″ and 0.5 µrad noise, which
//! gives ECC.

use crate::output::{OutputFile, ScenarioOutput, SimError};
use crate::thermal_network::{AmbientProfile, Body, DutyCycle, HeatSource, Link, ThermalNetwork};
use mtec_io::CsvWriter;
use mtec_model::Htm;
use nalgebra::Vector3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;
use std::fmt::Write;

/// The columns of `dbb.csv`.
const DBB_HEADER: [&str; 5] = ["experiment", "time_min", "mode", "angle_deg", "dl_um"];

/// Speeds of the four experiments (rpm).
pub const SPEEDS_RPM: [f64; 4] = [10.0, 20.0, 30.0, 40.0];
/// Measurement times within each experiment (min).
pub const TIMES_MIN: [f64; 13] = [
    0.0, 20.0, 40.0, 60.0, 80.0, 100.0, 120.0, 140.0, 160.0, 180.0, 200.0, 220.0, 240.0,
];
/// Angular step of the ballbar readings (deg).
pub const ANGLE_STEP_DEG: f64 = 5.0;
/// Ballbar reading noise (µm, 1σ).
pub const BALLBAR_NOISE_UM: f64 = 0.1;
/// Temperature sensor noise (°C, 1σ).
pub const SENSOR_NOISE_C: f64 = 0.03;
const AMBIENT_C: f64 = 20.0;

/// Preset layout (the source's, dimensions chosen with `mtec_identify::ballbar::search_preset`):
/// h, a, b (mm) and the second mount's table angles (deg). The angular motions are resolved to
/// about 0.21 µm / b of reading noise per µrad: with 0.1 µm noise a 150 mm bar gives ≈ 1.4 µrad
/// per angle, the 500 mm bar here ≈ 0.42 µrad (1σ at the worst angle).
pub const PRESET: (f64, f64, f64, [f64; 3]) = (100.0, 300.0, 500.0, [0.0, 120.0, 240.0]);

/// The five modes (workpiece ball on the table at C = 0, tool ball), ids 1..5.
pub fn modes() -> Vec<(i64, [f64; 3], [f64; 3])> {
    let (h, a, b, phis) = PRESET;
    let k = (b * b - a * a).sqrt();
    let mut m = vec![
        (1, [0.0, 0.0, h], [b, 0.0, h]),
        (2, [0.0, 0.0, h], [0.0, b, h]),
    ];
    for (i, p) in phis.iter().enumerate() {
        let p = p.to_radians();
        m.push((
            3 + i as i64,
            [a * p.cos(), a * p.sin(), h],
            [0.0, 0.0, h + k],
        ));
    }
    m
}

/// Bodies: 0 motor, 1 bearing, 2 axis housing, 3 table, 4 bed.
pub fn network() -> ThermalNetwork {
    ThermalNetwork {
        bodies: vec![
            Body::new("motor", 6.0e3, 1.0),
            Body::new("bearing", 1.0e4, 0.6),
            Body::new("axis_housing", 3.0e4, 2.0),
            Body::new("table", 1.0e4, 0.9),
            Body::new("bed", 8.0e5, 25.0),
        ],
        links: vec![
            Link::new(0, 2, 0.8),
            Link::new(1, 2, 1.5),
            Link::new(1, 3, 10.0),
            Link::new(2, 4, 2.0),
        ],
        sources: vec![
            HeatSource {
                body: 0,
                idle_w: 1.0,
                rated_w: 14.0,
                rated_speed: 40.0,
                exponent: 1.0,
            },
            HeatSource {
                body: 1,
                idle_w: 0.0,
                rated_w: 10.5,
                rated_speed: 40.0,
                exponent: 1.5,
            },
        ],
    }
}

/// Sensor k (T1..T9) as a weighted mix of body temperatures and the ambient air (last weight).
pub(crate) const SENSORS: [[f64; 6]; 9] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0], // T1 motor winding
    [0.6, 0.0, 0.4, 0.0, 0.0, 0.0], // T2 motor flange
    [0.0, 1.0, 0.0, 0.0, 0.0, 0.0], // T3 axis bearing
    [0.0, 0.2, 0.8, 0.0, 0.0, 0.0], // T4 axis housing
    [0.0, 0.2, 0.0, 0.8, 0.0, 0.0], // T5 table centre
    [0.0, 0.0, 0.0, 0.8, 0.0, 0.2], // T6 table edge
    [0.0, 0.0, 0.1, 0.0, 0.9, 0.0], // T7 bed near the axis
    [0.0, 0.0, 0.0, 0.0, 1.0, 0.0], // T8 bed far
    [0.0, 0.0, 0.0, 0.0, 0.0, 1.0], // T9 ambient air
];

/// Fourier error function: Σ amp·cos(n·C + phase) over (n, amp, phase).
#[derive(Debug, Clone)]
struct Harmonics(Vec<(f64, f64, f64)>);

impl Harmonics {
    fn random(rng: &mut StdRng, amps: &[(f64, f64)]) -> Harmonics {
        Harmonics(
            amps.iter()
                .map(|&(n, a)| {
                    (
                        n,
                        a * rng.random_range(0.6..1.0),
                        rng.random_range(0.0..2.0 * PI),
                    )
                })
                .collect(),
        )
    }
    fn at(&self, c_rad: f64) -> f64 {
        self.0
            .iter()
            .map(|(n, a, p)| a * (n * c_rad + p).cos())
            .sum()
    }
}

/// Ground-truth error motions of the C axis as functions of angle and temperature rises.
struct AxisTruth {
    /// EXC, EYC, EZC (µm), EAC, EBC, ECC (µrad) at 20 °C.
    stat: [Harmonics; 6],
    /// Per °C of bearing rise: harmonics 2–3 (µm/°C, µrad/°C).
    bearing: [Harmonics; 6],
    /// Per °C of table rise: uniform growth (µm/°C) in X, Y, Z.
    growth_um_per_c: [f64; 3],
    /// Per °C of motor rise: constant tilt (µrad/°C) about X, Y.
    tilt_urad_per_c: [f64; 2],
}

impl AxisTruth {
    fn random(rng: &mut StdRng) -> AxisTruth {
        let lin = [
            (1.0, 2.0),
            (2.0, 1.5),
            (3.0, 0.9),
            (4.0, 0.5),
            (5.0, 0.3),
            (6.0, 0.2),
        ];
        let axial = [(1.0, 0.8), (2.0, 0.8), (3.0, 0.5), (4.0, 0.3), (5.0, 0.2)];
        let ang = [(1.0, 20.0), (2.0, 15.0), (3.0, 9.0), (4.0, 5.0), (5.0, 3.0)];
        let ecc = [(1.0, 10.0), (2.0, 6.0), (3.0, 3.0)];
        let stat = [
            Harmonics::random(rng, &lin),
            Harmonics::random(rng, &lin),
            Harmonics::random(rng, &axial),
            Harmonics::random(rng, &ang),
            Harmonics::random(rng, &ang),
            Harmonics::random(rng, &ecc),
        ];
        let th_lin = [(2.0, 0.45), (3.0, 0.2)];
        let th_ang = [(2.0, 3.0), (3.0, 1.5)];
        let bearing = [
            Harmonics::random(rng, &th_lin),
            Harmonics::random(rng, &th_lin),
            Harmonics::random(rng, &[(2.0, 0.25)]),
            Harmonics::random(rng, &th_ang),
            Harmonics::random(rng, &th_ang),
            Harmonics::random(rng, &[(2.0, 1.0)]),
        ];
        AxisTruth {
            stat,
            bearing,
            growth_um_per_c: [0.6, -0.4, 2.0],
            tilt_urad_per_c: [1.5, -1.0],
        }
    }

    /// `[EXC, EYC, EZC, EAC, EBC, ECC]` at angle C for rises (bearing, table, motor).
    fn motions(&self, c_deg: f64, d_bearing: f64, d_table: f64, d_motor: f64) -> [f64; 6] {
        let c = c_deg.to_radians();
        let scale = 1.0 + 0.04 * d_bearing;
        std::array::from_fn(|k| {
            let mut v = scale * self.stat[k].at(c) + d_bearing * self.bearing[k].at(c);
            if k < 3 {
                v += d_table * self.growth_um_per_c[k];
            } else if k < 5 {
                v += d_motor * self.tilt_urad_per_c[k - 3];
            }
            v
        })
    }
}

/// The table's exact error transform `Trans(δ)·Rz(εz)·Ry(εy)·Rx(εx)` (mm, rad) from µm and µrad.
fn error_transform(e: &[f64; 6]) -> Htm {
    Htm::error_exact(
        Vector3::new(e[0], e[1], e[2]) * 1e-3,
        Vector3::new(e[3], e[4], e[5]) * 1e-6,
    )
}

/// Exact reading (µm) of one installation: actual ball distance minus the nominal bar length.
/// The workpiece ball (nominal `pw` plus set-up offset `ew`, both on the table) is carried by
/// `E(C)·Rz(C)`; the tool ball is at its nominal place plus offset `et` plus the head drift.
fn exact_reading_um(
    pw: Vector3<f64>,
    pt: Vector3<f64>,
    ew_mm: Vector3<f64>,
    et_mm: Vector3<f64>,
    c_deg: f64,
    e: &[f64; 6],
) -> f64 {
    let table = error_transform(e) * Htm::rotation(Vector3::z(), c_deg.to_radians());
    let ball = table.point(&(pw + ew_mm));
    let cup = pt + et_mm;
    ((ball - cup).norm() - (pw - pt).norm()) * 1e3
}

/// Runs the scenario (named `dbb-rotary`, its historical name).
pub fn run(seed: u64) -> Result<ScenarioOutput, SimError> {
    run_named("dbb-rotary", seed)
}

/// Runs the constant-speed campaign under the name the truth records (`dbb-rotary` or its
/// explicit name `dbb-rotary-constant`: same files).
pub fn run_named(scenario: &str, seed: u64) -> Result<ScenarioOutput, SimError> {
    let net = network();
    let names: Vec<String> = net.bodies.iter().map(|b| b.name.clone()).collect();
    let sensors: Vec<Vec<f64>> = SENSORS.iter().map(|w| w.to_vec()).collect();
    let campaign = Campaign {
        scenario,
        body_names: &names,
        sensors: &sensors,
        n_experiments: SPEEDS_RPM.len(),
        extra: serde_json::Map::new(),
    };
    simulate_campaign(&campaign, seed, |ei, rng| {
        let speed = SPEEDS_RPM[ei];
        let ambient = AmbientProfile {
            mean_c: AMBIENT_C + rng.random_range(-0.3..0.3),
            drift_c_per_h: rng.random_range(-0.03..0.03),
            daily_amplitude_c: 0.0,
            phase_h: 0.0,
        };
        let start = vec![ambient.at(0.0); net.bodies.len()];
        let duty = DutyCycle::new(vec![(240.0, speed)]);
        let hist = net.simulate(&start, &duty, &ambient, 240.0, 20.0, 30.0);
        let drivers = hist
            .temps_c
            .iter()
            .map(|tb| Drivers {
                bearing: tb[1] - start[1],
                table: tb[3] - start[3],
                motor: tb[0] - start[0],
                head: tb[4] - start[4],
            })
            .collect();
        let mut meta = serde_json::Map::new();
        meta.insert("speed_rpm".into(), serde_json::json!(speed));
        meta.insert("duration_min".into(), serde_json::json!(240.0));
        ExperimentThermal {
            times_min: TIMES_MIN.to_vec(),
            bodies_c: hist.temps_c,
            ambient_c: hist.ambient_c,
            drivers,
            meta,
        }
    })
}

/// The temperature changes that drive the error motions at one measurement (°C): the axis
/// bearing (harmonics and scale), the table (uniform growth), the motor (tilt) and the bed
/// under the spindle head (the tool cup's drift), each against the state the static error
/// motions belong to.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Drivers {
    pub bearing: f64,
    pub table: f64,
    pub motor: f64,
    pub head: f64,
}

/// The thermal side of one experiment at its measurement times: body temperatures, ambient air,
/// the drivers of the error motions, and what the truth records about the experiment.
pub(crate) struct ExperimentThermal {
    pub times_min: Vec<f64>,
    /// `bodies_c[k][i]`: body i at `times_min[k]`.
    pub bodies_c: Vec<Vec<f64>>,
    pub ambient_c: Vec<f64>,
    pub drivers: Vec<Drivers>,
    /// Entries of the truth's `experiments[i]` after `experiment` (before `bodies`).
    pub meta: serde_json::Map<String, serde_json::Value>,
}

/// A ballbar campaign on the C axis: the bodies, the sensors (weights over the bodies and,
/// last, the ambient air) and how many experiments.
pub(crate) struct Campaign<'a> {
    pub scenario: &'a str,
    pub body_names: &'a [String],
    pub sensors: &'a [Vec<f64>],
    pub n_experiments: usize,
    /// Entries added at the top level of the truth.
    pub extra: serde_json::Map<String, serde_json::Value>,
}

/// Simulates a campaign: the axis truth (first draw of the seed's stream), then per experiment
/// its thermal side (`thermal(index, rng)`), the sensors with noise and, at every measurement
/// time, the five installations read over one revolution from the exact bar lengths.
pub(crate) fn simulate_campaign(
    campaign: &Campaign,
    seed: u64,
    mut thermal: impl FnMut(usize, &mut StdRng) -> ExperimentThermal,
) -> Result<ScenarioOutput, SimError> {
    let mut rng = StdRng::seed_from_u64(seed);
    let truth_axis = AxisTruth::random(&mut rng);
    let modes = modes();
    let noise = Normal::new(0.0, BALLBAR_NOISE_UM).map_err(|e| SimError::Invalid(e.to_string()))?;
    let tnoise = Normal::new(0.0, SENSOR_NOISE_C).map_err(|e| SimError::Invalid(e.to_string()))?;
    let n_angles = (360.0 / ANGLE_STEP_DEG).round() as usize;
    let angles: Vec<f64> = (0..n_angles).map(|i| i as f64 * ANGLE_STEP_DEG).collect();
    let nb = campaign.body_names.len();
    if campaign.sensors.iter().any(|w| w.len() != nb + 1) {
        return Err(SimError::Invalid(
            "a sensor needs one weight per body and one for the ambient air".into(),
        ));
    }

    let mut dbb = CsvWriter::new(DBB_HEADER);
    let sensor_columns = (1..=campaign.sensors.len()).map(|k| format!("T{k}_c"));
    let mut temps = CsvWriter::new(
        ["experiment", "time_min"]
            .map(String::from)
            .into_iter()
            .chain(sensor_columns),
    );
    let names = [
        "EXC_um", "EYC_um", "EZC_um", "EAC_urad", "EBC_urad", "ECC_urad",
    ];
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 6];
    let (mut t_exp, mut t_time, mut t_angle) = (Vec::new(), Vec::new(), Vec::new());
    let mut installs = Vec::new();
    let mut experiments = Vec::new();
    for ei in 0..campaign.n_experiments {
        let exp = ei as i64 + 1;
        let th = thermal(ei, &mut rng);
        let mut body_rows = Vec::new();
        for (ti, &time) in th.times_min.iter().enumerate() {
            let tb = &th.bodies_c[ti];
            let amb = th.ambient_c[ti];
            let mut body = serde_json::Map::new();
            body.insert("time_min".into(), serde_json::json!(time));
            for (name, t) in campaign.body_names.iter().zip(tb) {
                body.insert(format!("{name}_c"), serde_json::json!(t));
            }
            body.insert("ambient_c".into(), serde_json::json!(amb));
            body_rows.push(serde_json::Value::Object(body));
            let mut row = vec![exp.to_string(), time.to_string()];
            for w in campaign.sensors {
                let v: f64 = (0..nb).map(|i| w[i] * tb[i]).sum::<f64>() + w[nb] * amb;
                row.push(format!("{:.3}", v + tnoise.sample(&mut rng)));
            }
            temps.row(row);
            let d = th.drivers[ti];
            // The spindle head holding the tool cup drifts with the bed/column (µm/°C).
            let head_drift_mm = Vector3::new(0.3, -0.2, -1.2) * d.head * 1e-3;
            let motions: Vec<[f64; 6]> = angles
                .iter()
                .map(|&c| truth_axis.motions(c, d.bearing, d.table, d.motor))
                .collect();
            for (ai, &c) in angles.iter().enumerate() {
                t_exp.push(exp);
                t_time.push(time);
                t_angle.push(c);
                for k in 0..6 {
                    cols[k].push(motions[ai][k]);
                }
            }
            for (id, pw, pt) in &modes {
                let ew_mm = ball_offset_mm(&mut rng);
                let et_mm = ball_offset_mm(&mut rng);
                let zero_um = rng.random_range(-1.0..1.0);
                installs.push(serde_json::json!({"experiment": exp, "time_min": time, "mode": id, "workpiece_ball_offset_um": (ew_mm * 1e3).as_slice(), "tool_ball_offset_um": (et_mm * 1e3).as_slice(), "zero_offset_um": zero_um}));
                for (ai, &c) in angles.iter().enumerate() {
                    let dl = exact_reading_um(
                        Vector3::from(*pw),
                        Vector3::from(*pt),
                        ew_mm,
                        et_mm + head_drift_mm,
                        c,
                        &motions[ai],
                    ) + zero_um
                        + noise.sample(&mut rng);
                    dbb.row([
                        exp.to_string(),
                        time.to_string(),
                        id.to_string(),
                        c.to_string(),
                        format!("{dl:.4}"),
                    ]);
                }
            }
        }
        let mut e = serde_json::Map::new();
        e.insert("experiment".into(), serde_json::json!(exp));
        e.extend(th.meta);
        e.insert("bodies".into(), serde_json::json!(body_rows));
        experiments.push(serde_json::Value::Object(e));
    }

    let (h, a, b, phis) = PRESET;
    let mut setup = format!(
        "# mtec ballbar setup written by `mtec simulate {}` (docs/formats.md, Ballbar).\n\
         # Source layout: modes 1-2 centre ball on the axis at h, tool cup at radius b;\n\
         # modes 3-5 second mount at radius a (table angles 0, 120, 240 deg), tool cup on the\n\
         # axis k = sqrt(b^2 - a^2) above the ball plane.\n",
        campaign.scenario
    );
    writeln!(
        setup,
        "# h_mm = {h}, a_mm = {a}, b_mm = {b}, mount2_angles_deg = {phis:?}"
    )
    .ok();
    for (id, pw, pt) in &modes {
        write!(
            setup,
            "\n[[mode]]\nid = {id}\nworkpiece_ball_mm = [{}, {}, {}]\ntool_ball_mm = [{}, {}, {}]\n",
            pw[0], pw[1], pw[2], pt[0], pt[1], pt[2]
        )
        .ok();
    }
    let mut motions = serde_json::Map::new();
    motions.insert("experiment".into(), serde_json::json!(t_exp));
    motions.insert("time_min".into(), serde_json::json!(t_time));
    motions.insert("angle_deg".into(), serde_json::json!(t_angle));
    for (k, n) in names.iter().enumerate() {
        motions.insert((*n).into(), serde_json::json!(cols[k]));
    }
    let mut truth = serde_json::json!({
        "format": "mtec.truth/1",
        "scenario": campaign.scenario,
        "seed": seed,
        "convention": "table pose E(C)·Rz(C), E = Trans(EXC,EYC,EZC)·Rz(ECC)·Ry(EBC)·Rx(EAC), error motions in the machine frame, angular motions about the origin (axis line, Z = 0)",
        "preset": {"h_mm": h, "a_mm": a, "b_mm": b, "mount2_angles_deg": phis},
        "ballbar_noise_um": BALLBAR_NOISE_UM,
        "sensor_noise_c": SENSOR_NOISE_C,
        "experiments": experiments,
        "motions": motions,
        "installations": installs,
    });
    if let Some(t) = truth.as_object_mut() {
        t.extend(campaign.extra.clone());
    }
    Ok(ScenarioOutput {
        files: vec![
            OutputFile {
                name: "setup.toml".into(),
                contents: setup,
            },
            OutputFile {
                name: "dbb.csv".into(),
                contents: dbb.finish(),
            },
            OutputFile {
                name: "temps.csv".into(),
                contents: temps.finish(),
            },
        ],
        truth,
    })
}

/// The ballbar installations that complete the preset for a five-axis machine (ids 6–11), all
/// at the cold start: radial bars at a second height (ball on the axis at 250 mm, cup at
/// 500 mm on +X and +Y), short inclined bars (ball at radius 120 mm, 100 mm high, at table
/// angles 0°, 120°, 240°, cup on the axis 90 mm above the ball plane: a 150 mm bar with its cup
/// at 190 mm instead of the preset's 500 mm) and an axial bar (ball on the axis at 100 mm, cup
/// on the axis 150 mm above it). Why these: `mtec_identify::ballbar::revolution`.
pub fn supplement_modes() -> Vec<(i64, [f64; 3], [f64; 3])> {
    let mut m = vec![
        (6, [0.0, 0.0, 250.0], [500.0, 0.0, 250.0]),
        (7, [0.0, 0.0, 250.0], [0.0, 500.0, 250.0]),
    ];
    for (i, p) in [0.0f64, 120.0, 240.0].iter().enumerate() {
        let p = p.to_radians();
        m.push((
            8 + i as i64,
            [120.0 * p.cos(), 120.0 * p.sin(), 100.0],
            [0.0, 0.0, 190.0],
        ));
    }
    m.push((11, [0.0, 0.0, 100.0], [0.0, 0.0, 250.0]));
    m
}

/// Targets of the rotary positioning test (deg): every 10° over one revolution.
pub const POSITIONING_STEP_DEG: f64 = 10.0;
/// Runs in each direction (ISO 230-2 standard test cycle).
pub const POSITIONING_RUNS: usize = 5;
/// The reference instrument's error bound (µrad): ±1″, the stated accuracy of a rotary axis
/// calibrator read with an angular interferometer (Renishaw XR20-W). Simulated as a smooth
/// error of the instrument's angle (harmonics 1–4, random phases, peak at most this bound).
pub const POSITIONING_INSTRUMENT_URAD: f64 = 4.85;
/// Random part of each positioning reading (µrad, 1σ): instrument and axis repeatability.
pub const POSITIONING_NOISE_URAD: f64 = 0.5;

/// The calibration of the C axis for the five-axis scenario at the cold start of experiment 1
/// of [`run`] (same seed, same truth).
#[derive(Debug, Clone)]
pub struct FiveAxisCalibration {
    /// [`supplement_modes`].
    pub modes: Vec<(i64, [f64; 3], [f64; 3])>,
    /// Their readings, the DBB format of [`run`] (experiment 1, time 0).
    pub dbb_csv: String,
    /// Rotary positioning test targets (deg) and deviations (actual − commanded angle, µrad),
    /// `up[run][target]`, `down[run][target]`, read against the instrument zeroed at 0°.
    pub positioning_targets_deg: Vec<f64>,
    pub positioning_up_urad: Vec<Vec<f64>>,
    pub positioning_down_urad: Vec<Vec<f64>>,
}

/// Simulates the supplementary installations and the rotary positioning test from the exact
/// truth of [`run`] with the same seed (set-up errors, noise and the instrument's error drawn
/// from their own stream).
pub fn five_axis_calibration(seed: u64) -> Result<FiveAxisCalibration, SimError> {
    // the truth is the first draw of run()'s stream
    let truth_axis = AxisTruth::random(&mut StdRng::seed_from_u64(seed));
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5EED_F1FE_A815);
    let noise = Normal::new(0.0, BALLBAR_NOISE_UM).map_err(|e| SimError::Invalid(e.to_string()))?;
    let n_angles = (360.0 / ANGLE_STEP_DEG).round() as usize;
    let modes = supplement_modes();
    let mut dbb = CsvWriter::new(DBB_HEADER);
    for (id, pw, pt) in &modes {
        let ew_mm = ball_offset_mm(&mut rng);
        let et_mm = ball_offset_mm(&mut rng);
        let zero_um = rng.random_range(-1.0..1.0);
        for i in 0..n_angles {
            let c = i as f64 * ANGLE_STEP_DEG;
            let e = truth_axis.motions(c, 0.0, 0.0, 0.0);
            let dl = exact_reading_um(Vector3::from(*pw), Vector3::from(*pt), ew_mm, et_mm, c, &e)
                + zero_um
                + noise.sample(&mut rng);
            dbb.row([
                "1".into(),
                "0".into(),
                id.to_string(),
                c.to_string(),
                format!("{dl:.4}"),
            ]);
        }
    }
    // rotary positioning: the instrument's own error, then the runs
    let amps = [2.0, 1.3, 0.9, 0.6];
    let scale = POSITIONING_INSTRUMENT_URAD / amps.iter().sum::<f64>();
    let instrument = Harmonics(
        amps.iter()
            .enumerate()
            .map(|(n, a)| {
                (
                    n as f64 + 1.0,
                    a * scale * rng.random_range(0.6..1.0),
                    rng.random_range(0.0..2.0 * PI),
                )
            })
            .collect(),
    );
    let pnoise =
        Normal::new(0.0, POSITIONING_NOISE_URAD).map_err(|e| SimError::Invalid(e.to_string()))?;
    let m = (360.0 / POSITIONING_STEP_DEG).round() as usize;
    let targets: Vec<f64> = (0..m).map(|i| i as f64 * POSITIONING_STEP_DEG).collect();
    let reading = |c: f64| truth_axis.motions(c, 0.0, 0.0, 0.0)[5] + instrument.at(c.to_radians());
    let zero = reading(0.0) + pnoise.sample(&mut rng);
    let runs = |rng: &mut StdRng| -> Vec<Vec<f64>> {
        (0..POSITIONING_RUNS)
            .map(|_| {
                targets
                    .iter()
                    .map(|&c| reading(c) - zero + pnoise.sample(rng))
                    .collect()
            })
            .collect()
    };
    let up = runs(&mut rng);
    let down = runs(&mut rng);
    Ok(FiveAxisCalibration {
        modes,
        dbb_csv: dbb.finish(),
        positioning_targets_deg: targets,
        positioning_up_urad: up,
        positioning_down_urad: down,
    })
}

/// The set-up error of a ballbar ball as the bar is mounted: each coordinate uniform in ±12 µm
/// (drawn x, y, z in that order, so a seed gives the same installation everywhere it is used).
fn ball_offset_mm(rng: &mut StdRng) -> Vector3<f64> {
    const S: f64 = 0.012;
    Vector3::new(
        rng.random_range(-S..S),
        rng.random_range(-S..S),
        rng.random_range(-S..S),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thermal brief: motor > 7 °C, bearing and table 3–4 °C, bed and ambient < 1 °C at the
    /// top speed after 4 h; lower speeds warm less.
    #[test]
    fn temperature_rises_match_the_brief() {
        let net = network();
        let amb = AmbientProfile::constant(20.0);
        let mut last_motor = 0.0;
        for &speed in &SPEEDS_RPM {
            let h = net.simulate(
                &[20.0; 5],
                &DutyCycle::new(vec![(240.0, speed)]),
                &amb,
                240.0,
                20.0,
                30.0,
            );
            let end = h.temps_c.last().unwrap();
            let rise: Vec<f64> = end.iter().map(|t| t - 20.0).collect();
            eprintln!("{speed} rpm: rises {rise:.2?}");
            assert!(rise[0] > last_motor);
            last_motor = rise[0];
            if speed == 40.0 {
                assert!(rise[0] > 7.0, "motor {}", rise[0]);
                for i in [1, 3] {
                    assert!((3.0..=4.0).contains(&rise[i]), "body {i}: {}", rise[i]);
                }
                assert!(rise[4] < 1.0);
            }
        }
    }

    /// The calibration simulates the same truth as `run`: the supplementary axial bar reads
    /// −EZC of `run`'s truth (plus a constant set-up error and noise).
    #[test]
    fn five_axis_calibration_reads_the_truth_of_run() {
        let t = run(4).unwrap().truth;
        let cal = five_axis_calibration(4).unwrap();
        let ezc: Vec<f64> = t["motions"]["EZC_um"].as_array().unwrap()[..72]
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let axial: Vec<f64> = cal
            .dbb_csv
            .lines()
            .filter(|l| l.starts_with("1,0,11,"))
            .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(axial.len(), 72);
        let d: Vec<f64> = axial.iter().zip(&ezc).map(|(a, e)| a + e).collect();
        let mean = d.iter().sum::<f64>() / 72.0;
        let rms = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 72.0).sqrt();
        assert!(rms < 0.15, "{rms}");
        assert_eq!(cal.positioning_up_urad.len(), POSITIONING_RUNS);
        assert_eq!(cal.positioning_targets_deg.len(), 36);
    }

    #[test]
    fn deterministic_and_complete() {
        let a = run(7).unwrap();
        let b = run(7).unwrap();
        assert_eq!(a.files[1].contents, b.files[1].contents);
        let rows = a.files[1].contents.lines().count() - 1;
        assert_eq!(rows, 4 * 13 * 5 * 72);
        assert_eq!(a.files[2].contents.lines().count() - 1, 4 * 13);
        let n = a.truth["motions"]["EXC_um"].as_array().unwrap().len();
        assert_eq!(n, 4 * 13 * 72);
        // with the drifting ambient of the scenario, the fastest experiment still warms as asked
        for seed in [1, 2, 3] {
            let t = run(seed).unwrap().truth;
            let bodies = t["experiments"][3]["bodies"].as_array().unwrap();
            let rise = |k: &str| bodies[12][k].as_f64().unwrap() - bodies[0][k].as_f64().unwrap();
            assert!(rise("motor_c") > 7.0);
            for k in ["bearing_c", "table_c"] {
                assert!(
                    (3.0..=4.0).contains(&rise(k)),
                    "seed {seed} {k}: {}",
                    rise(k)
                );
            }
            assert!(rise("bed_c").abs() < 1.0 && rise("ambient_c").abs() < 1.0);
        }
    }

    /// Hand-worked exact reading: a ball on the axis at h with a +X cup, shifted EXC = 3 µm,
    /// reads −3 µm (bar shorter); eccentricity of the ball by +5 µm in X reads −5 µm at C = 0 and
    /// +5 µm at C = 180°.
    #[test]
    fn exact_reading_worked_by_hand() {
        let pw = Vector3::new(0.0, 0.0, 100.0);
        let pt = Vector3::new(150.0, 0.0, 100.0);
        let z = Vector3::zeros();
        let e = [3.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert!((exact_reading_um(pw, pt, z, z, 0.0, &e) + 3.0).abs() < 1e-6);
        let ew = Vector3::new(0.005, 0.0, 0.0);
        let zero = [0.0; 6];
        assert!((exact_reading_um(pw, pt, ew, z, 0.0, &zero) + 5.0).abs() < 1e-6);
        assert!((exact_reading_um(pw, pt, ew, z, 180.0, &zero) - 5.0).abs() < 1e-6);
    }
}
