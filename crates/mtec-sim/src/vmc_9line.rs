//! Scenario `vmc-9line`: laser-interferometer measurements of the XYFZ vertical machining
//! centre (600 × 800 × 300 mm, tool length 100 mm) along the 9-line design, with the exact
//! kinematics of the ground-truth errors and instrument noise.
//!
//! Files: `machine.toml`, `lines.csv` (SPEC §4 line measurement: one row per point and channel;
//! a line's channels are named `<line>`, `<line>.<dir>` for straightness; plus a `run` column:
//! every line is measured [`RUNS`] times, each run a fresh set-up with its own zero, alignment
//! and noise), `truth.json` (the error set, the laser settings, the straightness alignment
//! slopes of every run).

use crate::instruments::{exact_error_um, gauss, LaserInterferometer};
use crate::output::{OutputFile, ScenarioOutput};
use crate::realistic_truth::realistic_truth;
use crate::truth::geometric_truth;
use mtec_io::CsvWriter;
use mtec_model::{line_preset, Axis, LineSpec, Machine, VolumetricModel};
use rand::rngs::StdRng;
use rand::SeedableRng;

/// Tool length of the scenario's measurements, mm.
pub const TOOL_LENGTH_MM: f64 = 100.0;
/// Repeat runs of every line (a laser calibration typically repeats each line 2–5 times).
pub const RUNS: usize = 3;

/// Simulates `runs` repeat runs of a line design: the CSV text with a `run` column, and the
/// alignment slopes (µrad) of each straightness channel and run (`X1.y run 2`).
pub fn measure_runs(
    machine: &Machine,
    truth: &mtec_model::ErrorSet,
    lines: &[LineSpec],
    laser: &LaserInterferometer,
    seed: u64,
    runs: usize,
) -> (String, Vec<(String, f64)>) {
    let header = LINES_HEADER[..1]
        .iter()
        .chain(&["run"])
        .chain(&LINES_HEADER[1..]);
    let mut csv = CsvWriter::new(header);
    let mut alignments = Vec::new();
    for run in 1..=runs {
        let (rows, slopes) = line_rows(
            machine,
            truth,
            lines,
            laser,
            seed.wrapping_add(7919 * (run as u64 - 1)),
        );
        for [name, rest @ ..] in rows {
            csv.row([name, run.to_string()].into_iter().chain(rest));
        }
        alignments.extend(slopes.into_iter().map(|(n, a)| {
            (
                if run == 1 {
                    n
                } else {
                    format!("{n} run {run}")
                },
                a,
            )
        }));
    }
    (csv.finish(), alignments)
}

/// The columns of one run's line readings.
const LINES_HEADER: [&str; 9] = [
    "line",
    "step",
    "x_mm",
    "y_mm",
    "z_mm",
    "ux",
    "uy",
    "uz",
    "reading_um",
];

/// Simulates a line design on a machine with its truth: the CSV text and the alignment slopes
/// (µrad) given to each straightness channel.
pub fn measure_lines(
    machine: &Machine,
    truth: &mtec_model::ErrorSet,
    lines: &[LineSpec],
    laser: &LaserInterferometer,
    seed: u64,
) -> (String, Vec<(String, f64)>) {
    let (rows, alignments) = line_rows(machine, truth, lines, laser, seed);
    let mut csv = CsvWriter::new(LINES_HEADER);
    for row in rows {
        csv.row(row);
    }
    (csv.finish(), alignments)
}

/// The rows of [`measure_lines`] (fields formatted as written) and the alignment slopes.
type LineRows = (Vec<[String; 9]>, Vec<(String, f64)>);

fn line_rows(
    machine: &Machine,
    truth: &mtec_model::ErrorSet,
    lines: &[LineSpec],
    laser: &LaserInterferometer,
    seed: u64,
) -> LineRows {
    let vm = VolumetricModel::new(machine, truth);
    let mut rng = StdRng::seed_from_u64(seed ^ 0x6c61_7365);
    let mut rows = Vec::new();
    let mut alignments = Vec::new();
    for line in lines {
        let pts = line.points();
        let dir = line.direction();
        let errs: Vec<[f64; 3]> = pts.iter().map(|p| exact_error_um(&vm, p)).collect();
        for (c, u) in line.channels.iter().enumerate() {
            let along = (u[0] * dir[0] + u[1] * dir[1] + u[2] * dir[2]).abs() > 0.999;
            let name = if c == 0 && along {
                line.name.clone()
            } else {
                format!(
                    "{}.{}",
                    line.name,
                    ["x", "y", "z"][u.iter().position(|v| v.abs() > 0.5).unwrap_or(0)]
                )
            };
            let slope = if along {
                0.0
            } else {
                gauss(&mut rng, laser.alignment_urad)
            };
            if !along {
                alignments.push((name.clone(), slope));
            }
            for (k, p) in pts.iter().enumerate() {
                let de = [0, 1, 2].map(|i| errs[k][i] - errs[0][i]);
                let dist_mm = ((0..3).map(|i| (p[i] - pts[0][i]).powi(2)).sum::<f64>()).sqrt();
                let noise = if along {
                    laser.noise_um
                } else {
                    laser.straightness_noise_um
                };
                let reading = u[0] * de[0]
                    + u[1] * de[1]
                    + u[2] * de[2]
                    + slope * 1e-3 * dist_mm
                    + gauss(&mut rng, noise);
                rows.push([
                    name.clone(),
                    k.to_string(),
                    format!("{:.4}", p[0]),
                    format!("{:.4}", p[1]),
                    format!("{:.4}", p[2]),
                    format!("{:.6}", u[0]),
                    format!("{:.6}", u[1]),
                    format!("{:.6}", u[2]),
                    format!("{reading:.4}"),
                ]);
            }
        }
    }
    (rows, alignments)
}

/// The scenario.
pub fn run(seed: u64) -> ScenarioOutput {
    let machine = Machine::vmc_xyfz(TOOL_LENGTH_MM);
    let truth = geometric_truth(&machine, seed);
    scenario(
        "vmc-9line",
        &machine,
        truth,
        LaserInterferometer::default(),
        seed,
    )
}

/// Screw leads (mm) of X, Y, Z of the realistic scenario's machine.
pub const LEADS_MM: [f64; 3] = [12.0, 16.0, 10.0];

/// The scenario's machine with the screw leads of [`LEADS_MM`] (`period_mm` in its file).
pub fn machine_with_leads() -> Machine {
    let mut machine = Machine::vmc_xyfz(TOOL_LENGTH_MM);
    for (a, lead) in [Axis::X, Axis::Y, Axis::Z].into_iter().zip(LEADS_MM) {
        if let Some(s) = machine.specs.get_mut(&a) {
            s.period_mm = Some(lead);
        }
    }
    machine
}

/// Scenario `vmc-9line-realistic` (issue 19): the same machine and design with a truth made of
/// what real machines show ([`crate::realistic_truth`]: cubic, long sinusoid, the ball screws'
/// pitch errors of [`LEADS_MM`], a local bump, waviness), a 0.1 µm laser, 3 runs per line.
/// `vmc-9line` keeps its nearly cubic truth, which other tests and examples pin.
pub fn run_realistic(seed: u64) -> ScenarioOutput {
    let machine = machine_with_leads();
    let truth = realistic_truth(&machine, seed);
    let laser = LaserInterferometer {
        noise_um: 0.1,
        straightness_noise_um: 0.1,
        alignment_urad: 20.0,
    };
    scenario("vmc-9line-realistic", &machine, truth, laser, seed)
}

fn scenario(
    name: &str,
    machine: &Machine,
    truth: mtec_model::ErrorSet,
    laser: LaserInterferometer,
    seed: u64,
) -> ScenarioOutput {
    let lines = line_preset("nine-line", machine, 20, 10.0).expect("XYZ machine has the preset");
    let (csv, alignments) = measure_runs(machine, &truth, &lines, &laser, seed, RUNS);
    let machine_toml = toml::to_string(&machine.to_spec()).expect("machine spec serialises");
    let truth_json = serde_json::json!({
        "format": "mtec.truth/1",
        "scenario": name,
        "seed": seed,
        "errors": truth,
        "laser": { "noise_um": laser.noise_um, "straightness_noise_um": laser.straightness_noise_um, "alignment_urad": laser.alignment_urad },
        "straightness_alignment_urad": alignments.into_iter().collect::<std::collections::BTreeMap<_, _>>(),
        "design": "nine-line",
        "runs": RUNS,
        "lines": lines,
    });
    ScenarioOutput {
        files: vec![
            OutputFile {
                name: "machine.toml".into(),
                contents: format!(
                    "# XYFZ vertical machining centre of the {name} scenario\n{machine_toml}"
                ),
            },
            OutputFile {
                name: "lines.csv".into(),
                contents: format!(
                    "# {name}: laser interferometer, 9-line design, {RUNS} runs, seed {seed}\n{csv}"
                ),
            },
        ],
        truth: truth_json,
    }
}
