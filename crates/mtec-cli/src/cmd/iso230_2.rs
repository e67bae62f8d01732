//! `mtec iso230-2`: ISO 230-2 positioning statistics of a linear axis (and VDI/DGQ 3441).

use crate::choice::choice;
use crate::error::CliError;
use crate::help::{examples, text};
use mtec_measure::air::{self, AirFormula};
use mtec_workflow::ops::iso230_2::{self as op, Options};
use std::path::PathBuf;

/// Arguments of `mtec iso230-2`.
#[derive(clap::Args, Debug)]
#[command(
    about = "ISO 230-2 positioning statistics (A, E, R, B, M) and VDI 3441 of a linear axis",
    long_about = text!("iso230_2.long"),
    after_long_help = examples!("iso230_2.examples")
)]
pub struct Args {
    /// The run file (target_mm,run,direction,deviation_um).
    pub run: PathBuf,
    /// Print the results as one JSON object (format mtec.iso230-2/1) instead of the text report.
    #[arg(long)]
    pub json: bool,
    /// Also write iso230-2.json into this folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Air temperature during the run (°C, -40..60); with --pressure-pa and --humidity-pct.
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub air_temp_c: Option<f64>,
    /// Air pressure during the run (Pa, 50000..120000).
    #[arg(long, value_name = "PA", allow_negative_numbers = true)]
    pub pressure_pa: Option<f64>,
    /// Relative humidity during the run (%, 0..100).
    #[arg(long, value_name = "PCT", allow_negative_numbers = true)]
    pub humidity_pct: Option<f64>,
    /// CO2 mole fraction (ppm, 0..2000; Ciddor only).
    #[arg(
        long,
        value_name = "PPM",
        default_value_t = 450.0,
        allow_negative_numbers = true
    )]
    pub co2_ppm: f64,
    /// Vacuum wavelength of the laser (nm).
    #[arg(long, value_name = "NM", default_value_t = air::HENE_WAVELENGTH_NM, allow_negative_numbers = true)]
    pub wavelength_nm: f64,
    /// Refractive-index equation.
    #[arg(
        long,
        value_parser = choice::<AirFormula>(),
        default_value = "ciddor",
        value_name = "ciddor|edlen|bonsch-potulski"
    )]
    pub air_formula: AirFormula,
    /// Index the laser used for its readings (default: the formula at 20 °C, 101325 Pa, 50 % RH).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub laser_n: Option<f64>,
    /// Temperature of the machine axis (scale) during the run (°C, -40..60); with --alpha-um-per-m-k.
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub material_temp_c: Option<f64>,
    /// Linear expansion coefficient of the axis (µm/m/K, 0..50; steel 11.5).
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub alpha_um_per_m_k: Option<f64>,
    /// Standard(s) to report: iso230-2:2014 (default, the report as always), vdi-3441, or
    /// all (side by side). ISO 230-2:1997/2006, GB/T 17421.2, JIS B 6190-2 and ASME B5.54
    /// are refused: their definitions are not established (docs/methods.md 2.2).
    #[arg(long, value_name = "NAME", default_value = op::DEFAULT_STANDARD)]
    pub standard: String,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        run: args.run,
        out: args.out,
        air_temp_c: args.air_temp_c,
        pressure_pa: args.pressure_pa,
        humidity_pct: args.humidity_pct,
        co2_ppm: args.co2_ppm,
        wavelength_nm: args.wavelength_nm,
        air_formula: args.air_formula,
        laser_n: args.laser_n,
        material_temp_c: args.material_temp_c,
        alpha_um_per_m_k: args.alpha_um_per_m_k,
        standard: args.standard,
    };
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    super::report(&outcome, args.json, op::Outcome::to_json)
}
