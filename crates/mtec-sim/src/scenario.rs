//! Scenarios: named recipes that write a set of measurement files plus their ground truth.

pub use crate::output::{OutputFile, ScenarioOutput, SimError};

/// The scenarios this build knows, with a one-line description each (shown by `mtec simulate --help`).
pub const SCENARIOS: &[(&str, &str)] = &[
    ("vmc-9line", "laser-interferometer lines (9-line design) on an XYFZ machining centre, for `mtec identify lines`"),
    ("vmc-9line-realistic", "as vmc-9line with a realistic truth (long sinusoids, ball-screw pitch errors, local bumps), 0.1 um laser, screw leads in machine.toml"),
    ("volumetric-grid", "laser-tracker volumetric error grid (11x11x11) and body diagonals, for `mtec map fit`"),
    ("iso230-2", "laser-interferometer positioning runs of one axis (ISO 230-2: 11 targets, 5 bidirectional runs)"),
    ("circular-test", "ISO 230-4 ballbar circular test of X and Y with injected faults, and a fault-free run"),
    ("circular-test-arc", "ISO 230-4 ballbar test on a 220 degree partial arc in the ZX plane, every diagnosable fault injected"),
    ("spindle-sensors", "8 collinear spindle temperature sensors and the radial drift (ridge-trace sensor selection)"),
    ("feed-axis-ambient", "Z-axis thermal error along the axis at ambient 15/20/25/30 C (exp-ambient model)"),
    ("production-day", "a VMC through 4 production days and an unseen day (spindle steps, idle, cooling, day/night air), its project.toml fits, builds and compensates: `mtec run`"),
    ("dbb-rotary", "ballbar on a C axis: 5 installation modes, 4 speeds x 4 h, every 20 min, temperatures T1-T9, for `mtec identify ballbar` (same as dbb-rotary-constant)"),
    ("dbb-rotary-constant", "dbb-rotary under its explicit name: each experiment one constant speed from cold, sensors on the heated bodies"),
    ("dbb-rotary-realistic", "ballbar on a C axis heated like a real one: unsensed rotor and bearing rings, surface sensors, 4 x 6 h of speed steps, dwells and cooling, drifting air; 5 modes every 20 min"),
];

/// Runs the named scenario with a seed.
pub fn run_scenario(name: &str, seed: u64) -> Result<ScenarioOutput, SimError> {
    let pairs = |files: Vec<(String, String)>| {
        files
            .into_iter()
            .map(|(name, contents)| OutputFile { name, contents })
            .collect()
    };
    match name {
        "vmc-9line" => Ok(crate::vmc_9line::run(seed)),
        "vmc-9line-realistic" => Ok(crate::vmc_9line::run_realistic(seed)),
        "volumetric-grid" => Ok(crate::volumetric_grid::run(seed)),
        "iso230-2" => {
            let (csv, truth) = crate::iso230_2::simulate(&Default::default(), seed);
            Ok(ScenarioOutput {
                files: pairs(vec![("iso230-2.csv".into(), csv)]),
                truth,
            })
        }
        "circular-test" => {
            let (files, truth) = crate::circular_test::scenario(seed);
            Ok(ScenarioOutput {
                files: pairs(files),
                truth,
            })
        }
        "circular-test-arc" => {
            let (files, truth) = crate::circular_test::scenario_arc(seed);
            Ok(ScenarioOutput {
                files: pairs(files),
                truth,
            })
        }
        "spindle-sensors" => crate::spindle_sensors::run(seed),
        "feed-axis-ambient" => crate::feed_axis_ambient::run(seed),
        "dbb-rotary" | "dbb-rotary-constant" => crate::dbb_rotary::run_named(name, seed),
        "dbb-rotary-realistic" => crate::dbb_rotary_realistic::run(seed),
        "production-day" => crate::production_day::run(seed),
        _ => Err(SimError::UnknownScenario(
            name.to_string(),
            SCENARIOS.iter().map(|s| s.0).collect::<Vec<_>>().join(", "),
        )),
    }
}
