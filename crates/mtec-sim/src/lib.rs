//! mtec-sim: the virtual machine with a known ground truth.
//!
//! What it is for: generating every kind of measurement mtec analyses (laser-interferometer
//! lines, ISO 230-2 runs, ballbar runs, thermal logs, tracker grids) from exact (non-linearised)
//! rigid-body kinematics, a lumped thermal network and instrument noise, deterministically from a
//! seed, together with the truth (`truth.json`) that the analysis must recover.
//!
//! What it is not for: analysis. Nothing here is used to identify or fit anything.

pub mod circular_test;
pub mod dbb_rotary;
pub mod dbb_rotary_realistic;
pub mod feed_axis_ambient;
pub mod instruments;
pub mod iso230_2;
pub mod output;
pub mod production_day;
pub mod realistic_truth;
pub mod scenario;
pub mod spindle_sensors;
pub mod thermal_network;
pub mod truth;
pub mod vmc_9line;
pub mod volumetric_grid;

pub use scenario::{run_scenario, OutputFile, ScenarioOutput, SimError, SCENARIOS};
pub use thermal_network::{
    AmbientProfile, Body, DutyCycle, HeatSource, Link, ThermalHistory, ThermalNetwork,
};
