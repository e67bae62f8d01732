//! `mtec iso230-2`: ISO 230-2 positioning statistics of a linear axis (and VDI/DGQ 3441).

use crate::error::CliError;
use mtec_io::OutputGuard;
use mtec_measure::air::{self, Air, AirFormula};
use mtec_measure::{evaluate_iso230_2, vdi3441, PositioningData};
use serde_json::json;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

const LONG: &str = "\
Evaluates bidirectional positioning runs of one linear axis (laser interferometer) as ISO 230-2:2014
asks: per target and direction the mean deviation, the standard uncertainty s and the mean +/- 2s
band, the reversal value B_i; and the axis values E_up, E_down, E, M, R_up, R_down, R, B, mean B,
A_up, A_down, A. A second report gives the VDI/DGQ 3441 values Ps, U, Pa and P.

Input (CSV, docs/formats.md, \"ISO 230-2 run CSV\"): target_mm,run,direction,deviation_um
  direction is + (target approached moving in the positive direction) or -;
  every run must visit every target in each direction; at least 2 runs per direction
  (ISO 230-2 asks for 5: fewer gives a warning).

Environmental compensation (docs/methods.md, section 2.1), applied to the
measured positions P_i + x_ij before the statistics (the interferometer is
taken to read 0 at target 0 mm):
  --air-temp-c, --pressure-pa, --humidity-pct (all three): the readings were
  taken with the index the laser assumed (--laser-n; default: the formula at
  20 °C, 101325 Pa, 50 % RH) and are scaled by n_laser / n_actual, n_actual
  from Ciddor (default) or the updated Edlén equation (--air-formula);
  --material-temp-c, --alpha-um-per-m-k (both): ISO 1 normalisation to 20 °C,
  positions divided by 1 + alpha (T - 20).
The report states n used, n actual and each correction in ppm.";

const EXAMPLES: &str = crate::help::examples!(
    "  # five bidirectional laser runs of one axis over 11 targets
  $ mtec simulate iso230-2 --out p
  # A, E, R, B, M per ISO 230-2 and Ps, U, Pa, P per VDI 3441, as a text report
  $ mtec iso230-2 p/iso230-2.csv
  # the same as one JSON object (mtec.iso230-2/1), also in p/iso230-2.json
  $ mtec iso230-2 p/iso230-2.csv --json --out p
  # corrected for 23.5 °C, 98.7 kPa, 40 % RH air and a 24 °C steel axis
  $ mtec iso230-2 p/iso230-2.csv --air-temp-c 23.5 --pressure-pa 98700 \\
      --humidity-pct 40 --material-temp-c 24 --alpha-um-per-m-k 11.5"
);

/// Refractive-index equation of `--air-formula`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Formula {
    /// Ciddor (1996)
    Ciddor,
    /// updated Edlén (Birch & Downs 1993/1994)
    Edlen,
}

impl From<Formula> for AirFormula {
    fn from(f: Formula) -> Self {
        match f {
            Formula::Ciddor => AirFormula::Ciddor,
            Formula::Edlen => AirFormula::Edlen,
        }
    }
}

/// Arguments of `mtec iso230-2`.
#[derive(clap::Args, Debug)]
#[command(
    about = "ISO 230-2 positioning statistics (A, E, R, B, M) and VDI 3441 of a linear axis",
    long_about = LONG,
    after_long_help = EXAMPLES
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
        value_enum,
        default_value = "ciddor",
        value_name = "ciddor|edlen"
    )]
    pub air_formula: Formula,
    /// Index the laser used for its readings (default: the formula at 20 °C, 101325 Pa, 50 % RH).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub laser_n: Option<f64>,
    /// Temperature of the machine axis (scale) during the run (°C, -40..60); with --alpha-um-per-m-k.
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub material_temp_c: Option<f64>,
    /// Linear expansion coefficient of the axis (µm/m/K, 0..50; steel 11.5).
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub alpha_um_per_m_k: Option<f64>,
}

/// The corrections applied to the measured positions and their product.
struct Corrections {
    air: Option<serde_json::Value>,
    material: Option<serde_json::Value>,
    factor: f64,
    lines: Vec<String>,
}

fn corrections(args: &Args) -> Result<Corrections, CliError> {
    let mut c = Corrections {
        air: None,
        material: None,
        factor: 1.0,
        lines: Vec::new(),
    };
    let formula = AirFormula::from(args.air_formula);
    match (args.air_temp_c, args.pressure_pa, args.humidity_pct) {
        (Some(t), Some(p), Some(h)) => {
            let actual = Air {
                temperature_c: t,
                pressure_pa: p,
                humidity_pct: h,
                co2_ppm: args.co2_ppm,
            };
            actual.validate().map_err(CliError::usage)?;
            air::validate_wavelength(formula, args.wavelength_nm).map_err(CliError::usage)?;
            let n_laser = match args.laser_n {
                Some(n) if n.is_finite() && (1.0..=1.001).contains(&n) => n,
                Some(n) => {
                    return Err(CliError::usage(format!(
                        "--laser-n is {n}: expected a refractive index of air, 1 to 1.001"
                    )))
                }
                None => air::refractive_index(formula, &air::STANDARD_AIR, args.wavelength_nm),
            };
            let n_actual = air::refractive_index(formula, &actual, args.wavelength_nm);
            let k = air::index_correction_factor(n_laser, n_actual);
            c.factor *= k;
            let ppm = (k - 1.0) * 1e6;
            c.lines.push(format!(
                "air ({}, {} nm): {t} °C, {p} Pa, {h} % RH, {} ppm CO2: n_laser {n_laser:.9}, n_actual {n_actual:.9}, correction {ppm:+.3} ppm",
                formula.name(),
                args.wavelength_nm,
                args.co2_ppm
            ));
            c.air = Some(json!({
                "formula": formula.name(),
                "wavelength_nm": args.wavelength_nm,
                "temperature_c": t,
                "pressure_pa": p,
                "humidity_pct": h,
                "co2_ppm": args.co2_ppm,
                "n_laser": n_laser,
                "n_actual": n_actual,
                "correction_ppm": ppm,
            }));
        }
        (None, None, None) => {
            if args.laser_n.is_some() {
                return Err(CliError::usage(
                    "--laser-n needs the air the run was taken in: --air-temp-c, --pressure-pa and --humidity-pct",
                ));
            }
        }
        _ => {
            return Err(CliError::usage(
                "the air correction needs all of --air-temp-c, --pressure-pa and --humidity-pct",
            ))
        }
    }
    match (args.material_temp_c, args.alpha_um_per_m_k) {
        (Some(t), Some(alpha)) => {
            air::validate_material(t, alpha).map_err(CliError::usage)?;
            let k = air::normalisation_factor(t, alpha);
            c.factor *= k;
            let ppm = (k - 1.0) * 1e6;
            c.lines.push(format!(
                "material (ISO 1, to 20 °C): {t} °C, alpha {alpha} um/m/K: correction {ppm:+.3} ppm"
            ));
            c.material = Some(json!({
                "temperature_c": t,
                "alpha_um_per_m_k": alpha,
                "correction_ppm": ppm,
            }));
        }
        (None, None) => {}
        _ => {
            return Err(CliError::usage(
                "the ISO 1 normalisation needs both --material-temp-c and --alpha-um-per-m-k",
            ))
        }
    }
    Ok(c)
}

pub fn run(args: Args) -> Result<(), CliError> {
    let corr = corrections(&args)?;
    let mut data = PositioningData::read(&args.run)?;
    if corr.factor != 1.0 {
        data = data.with_scaled_positions(corr.factor);
    }
    let iso = evaluate_iso230_2(&data);
    let vdi = vdi3441(&iso);
    for w in &data.warnings {
        eprintln!("warning: {}: {w}", args.run.display());
    }
    let mut doc = json!({
        "format": "mtec.iso230-2/1",
        "file": args.run.display().to_string(),
        "runs_up": iso.runs_up,
        "runs_down": iso.runs_down,
    });
    let obj = doc.as_object_mut().expect("object");
    if let serde_json::Value::Object(axis) =
        serde_json::to_value(&iso.axis).map_err(anyhow::Error::from)?
    {
        obj.extend(axis);
    }
    obj.insert(
        "targets".into(),
        serde_json::to_value(&iso.targets).map_err(anyhow::Error::from)?,
    );
    obj.insert(
        "vdi3441".into(),
        serde_json::to_value(&vdi).map_err(anyhow::Error::from)?,
    );
    obj.insert(
        "corrections".into(),
        json!({"air": corr.air, "material": corr.material, "scale_factor": corr.factor}),
    );
    obj.insert("warnings".into(), json!(data.warnings));
    let text = serde_json::to_string_pretty(&doc).map_err(anyhow::Error::from)?;
    if let Some(dir) = &args.out {
        OutputGuard::new(&[&args.run]).write(&dir.join("iso230-2.json"), text.as_bytes())?;
    }
    if args.json {
        return emit(&format!("{text}\n"));
    }
    let mut o = String::new();
    let _ = writeln!(
        o,
        "ISO 230-2:2014 positioning of {} ({} runs +, {} runs -)",
        args.run.display(),
        iso.runs_up,
        iso.runs_down
    );
    for line in &corr.lines {
        let _ = writeln!(o, "corrected for {line}");
    }
    if !corr.lines.is_empty() {
        let _ = writeln!(
            o,
            "measured positions scaled by {:.12} ({:+.3} ppm)",
            corr.factor,
            (corr.factor - 1.0) * 1e6
        );
    }
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "{:>10} {:>9} {:>9} {:>7} {:>7} {:>8} {:>8} {:>7}",
        "target_mm", "mean+_um", "mean-_um", "s+_um", "s-_um", "B_i_um", "mean_um", "R_i_um"
    );
    for t in &iso.targets {
        let _ = writeln!(
            o,
            "{:>10.3} {:>9.3} {:>9.3} {:>7.3} {:>7.3} {:>8.3} {:>8.3} {:>7.3}",
            t.target_mm,
            t.mean_up_um,
            t.mean_down_um,
            t.s_up_um,
            t.s_down_um,
            t.reversal_um,
            t.mean_bidirectional_um,
            t.r_um
        );
    }
    let a = &iso.axis;
    let _ = writeln!(o);
    let _ = writeln!(o, "axis values (um)        up      down     bidirectional");
    let _ = writeln!(
        o,
        "  A  accuracy      {:>8.3}  {:>8.3}  {:>8.3}",
        a.a_up_um, a.a_down_um, a.a_um
    );
    let _ = writeln!(
        o,
        "  E  systematic    {:>8.3}  {:>8.3}  {:>8.3}",
        a.e_up_um, a.e_down_um, a.e_um
    );
    let _ = writeln!(
        o,
        "  R  repeatability {:>8.3}  {:>8.3}  {:>8.3}",
        a.r_up_um, a.r_down_um, a.r_um
    );
    let _ = writeln!(
        o,
        "  M  range of mean bidirectional deviation       {:>8.3}",
        a.m_um
    );
    let _ = writeln!(
        o,
        "  B  reversal value (max |B_i|)                  {:>8.3}",
        a.b_um
    );
    let _ = writeln!(
        o,
        "  mean reversal value                            {:>8.3}",
        a.mean_b_um
    );
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "VDI/DGQ 3441 (um): Ps = {:.3}  U = {:.3}  Pa = {:.3}  P = {:.3}",
        vdi.ps_um, vdi.u_um, vdi.pa_um, vdi.p_um
    );
    emit(&o)
}

/// Writes the report to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn emit(text: &str) -> Result<(), CliError> {
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
