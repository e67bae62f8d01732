//! ISO 230-2 positioning statistics of a linear axis (and VDI/DGQ 3441), with the optional
//! environmental compensation of the measured positions (air index, ISO 1 normalisation).
//! The job of `mtec iso230-2`.

use crate::{Error, Observer, Result};
use mtec_io::{OutputGuard, Table};
use mtec_measure::air::{self, Air, AirFormula};
use mtec_measure::iso230_2::{self as iso230_2, AxisValues, StandardValues, TargetStats};
use mtec_measure::{evaluate_iso230_2, vdi3441, PositioningData, Standard, Vdi3441};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// The name of the file the job writes into [`Options::out`].
pub const OUTPUT_FILE: &str = "iso230-2.json";

/// What to evaluate and how.
#[derive(Debug, Clone)]
pub struct Options {
    /// The run file (CSV `target_mm,run,direction,deviation_um`).
    pub run: PathBuf,
    /// Folder to write `iso230-2.json` into; `None` writes nothing.
    pub out: Option<PathBuf>,
    /// Air temperature during the run (°C, -40..60); with the pressure and the humidity.
    pub air_temp_c: Option<f64>,
    /// Air pressure during the run (Pa, 50000..120000).
    pub pressure_pa: Option<f64>,
    /// Relative humidity during the run (%, 0..100).
    pub humidity_pct: Option<f64>,
    /// CO2 mole fraction (ppm, 0..2000; Ciddor only).
    pub co2_ppm: f64,
    /// Vacuum wavelength of the laser (nm).
    pub wavelength_nm: f64,
    /// Refractive-index equation.
    pub air_formula: AirFormula,
    /// Index the laser used for its readings (1..1.001; `None`: the formula at 20 °C,
    /// 101325 Pa, 50 % RH).
    pub laser_n: Option<f64>,
    /// Temperature of the machine axis (scale) during the run (°C, -40..60).
    pub material_temp_c: Option<f64>,
    /// Linear expansion coefficient of the axis (µm/m/K, 0..50).
    pub alpha_um_per_m_k: Option<f64>,
    /// The standard(s) to report: `iso230-2:2014` (the report as it always was), `vdi-3441`
    /// or `all` (docs/methods.md §2.2); anything else is a usage error.
    pub standard: String,
}

impl Options {
    /// No environmental compensation, a HeNe laser, Ciddor, nothing written.
    pub fn new(run: impl Into<PathBuf>) -> Options {
        Options {
            run: run.into(),
            out: None,
            air_temp_c: None,
            pressure_pa: None,
            humidity_pct: None,
            co2_ppm: 450.0,
            wavelength_nm: air::HENE_WAVELENGTH_NM,
            air_formula: AirFormula::Ciddor,
            laser_n: None,
            material_temp_c: None,
            alpha_um_per_m_k: None,
            standard: DEFAULT_STANDARD.into(),
        }
    }
}

/// The `--standard` of the report as it has always been: ISO 230-2:2014 (with VDI 3441).
pub const DEFAULT_STANDARD: &str = "iso230-2:2014";

/// The air-index correction applied (docs/methods.md §2.1).
#[derive(Debug, Clone, Serialize)]
pub struct AirCorrection {
    /// `ciddor` or `edlen`.
    pub formula: String,
    /// Vacuum wavelength (nm).
    pub wavelength_nm: f64,
    /// Air temperature (°C).
    pub temperature_c: f64,
    /// Air pressure (Pa).
    pub pressure_pa: f64,
    /// Relative humidity (%).
    pub humidity_pct: f64,
    /// CO2 mole fraction (ppm).
    pub co2_ppm: f64,
    /// Index the laser assumed.
    pub n_laser: f64,
    /// Index of the actual air.
    pub n_actual: f64,
    /// (n_laser / n_actual - 1) (ppm).
    pub correction_ppm: f64,
}

/// The ISO 1 normalisation to 20 °C applied.
#[derive(Debug, Clone, Serialize)]
pub struct MaterialCorrection {
    /// Axis temperature (°C).
    pub temperature_c: f64,
    /// Expansion coefficient (µm/m/K).
    pub alpha_um_per_m_k: f64,
    /// (factor - 1) (ppm).
    pub correction_ppm: f64,
}

/// The corrections applied to the measured positions and their product.
#[derive(Debug, Clone, Serialize)]
pub struct Corrections {
    pub air: Option<AirCorrection>,
    pub material: Option<MaterialCorrection>,
    /// Product of the correction factors the measured positions were multiplied by.
    pub scale_factor: f64,
}

/// The result: `mtec.iso230-2/1` (docs/formats.md).
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// `mtec.iso230-2/1`.
    pub format: String,
    /// The run file as given.
    pub file: String,
    /// Runs in the positive direction.
    pub runs_up: usize,
    /// Runs in the negative direction.
    pub runs_down: usize,
    /// The axis values A, E, R, B, M (µm).
    #[serde(flatten)]
    pub axis: AxisValues,
    /// Per-target statistics (µm).
    pub targets: Vec<TargetStats>,
    /// VDI/DGQ 3441 values (µm).
    pub vdi3441: Vdi3441,
    pub corrections: Corrections,
    /// With `--standard` other than iso230-2:2014: each chosen standard's axis values, side by
    /// side (absent otherwise, so the default output is what it always was).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub standards: Option<Vec<StandardValues>>,
    /// What the reader noticed about the runs (e.g. fewer than 5 per direction).
    pub warnings: Vec<String>,
}

/// Checks the environmental options and computes the corrections (usage errors only).
fn corrections(o: &Options) -> Result<Corrections> {
    let mut c = Corrections {
        air: None,
        material: None,
        scale_factor: 1.0,
    };
    let formula = o.air_formula;
    match (o.air_temp_c, o.pressure_pa, o.humidity_pct) {
        (Some(t), Some(p), Some(h)) => {
            let actual = Air {
                temperature_c: t,
                pressure_pa: p,
                humidity_pct: h,
                co2_ppm: o.co2_ppm,
            };
            actual.validate().map_err(Error::usage)?;
            air::validate_wavelength(formula, o.wavelength_nm).map_err(Error::usage)?;
            let n_laser = match o.laser_n {
                Some(n) if n.is_finite() && (1.0..=1.001).contains(&n) => n,
                Some(n) => {
                    return Err(Error::usage(format!(
                        "--laser-n is {n}: expected a refractive index of air, 1 to 1.001"
                    )))
                }
                None => air::refractive_index(formula, &air::STANDARD_AIR, o.wavelength_nm),
            };
            let n_actual = air::refractive_index(formula, &actual, o.wavelength_nm);
            let k = air::index_correction_factor(n_laser, n_actual);
            c.scale_factor *= k;
            c.air = Some(AirCorrection {
                formula: formula.name().to_string(),
                wavelength_nm: o.wavelength_nm,
                temperature_c: t,
                pressure_pa: p,
                humidity_pct: h,
                co2_ppm: o.co2_ppm,
                n_laser,
                n_actual,
                correction_ppm: (k - 1.0) * 1e6,
            });
        }
        (None, None, None) => {
            if o.laser_n.is_some() {
                return Err(Error::usage(
                    "--laser-n needs the air the run was taken in: --air-temp-c, --pressure-pa and --humidity-pct",
                ));
            }
        }
        _ => {
            return Err(Error::usage(
                "the air correction needs all of --air-temp-c, --pressure-pa and --humidity-pct",
            ))
        }
    }
    match (o.material_temp_c, o.alpha_um_per_m_k) {
        (Some(t), Some(alpha)) => {
            air::validate_material(t, alpha).map_err(Error::usage)?;
            let k = air::normalisation_factor(t, alpha);
            c.scale_factor *= k;
            c.material = Some(MaterialCorrection {
                temperature_c: t,
                alpha_um_per_m_k: alpha,
                correction_ppm: (k - 1.0) * 1e6,
            });
        }
        (None, None) => {}
        _ => {
            return Err(Error::usage(
                "the ISO 1 normalisation needs both --material-temp-c and --alpha-um-per-m-k",
            ))
        }
    }
    Ok(c)
}

/// Evaluates the runs; writes `iso230-2.json` into `opts.out` when given. The file is read as
/// a stream (files of any size).
pub fn run(opts: &Options, obs: &mut dyn Observer) -> Result<Outcome> {
    let prepared = prepare(opts, &opts.run)?;
    let data = PositioningData::read(&opts.run)?;
    finish(&opts.run, data, prepared, obs)
}

/// [`run`] of runs already read (the Python module's arrays, or a file): `opts.run` is not
/// read; the table's path names the runs in errors, warnings and the outcome's `file`.
pub fn run_table(table: &Table, opts: &Options, obs: &mut dyn Observer) -> Result<Outcome> {
    let prepared = prepare(opts, &table.path)?;
    let data = PositioningData::from_table(table)?;
    finish(&table.path, data, prepared, obs)
}

/// What is settled before any reading: the corrections and the standards asked for (usage
/// errors), and that the output is not the input.
struct Prepared {
    corrections: Corrections,
    chosen: Vec<Standard>,
    guard: OutputGuard,
    out_file: Option<PathBuf>,
}

fn prepare(opts: &Options, run: &Path) -> Result<Prepared> {
    let corrections = corrections(opts)?;
    let chosen = Standard::parse(&opts.standard).map_err(Error::usage)?;
    let guard = OutputGuard::new(&[run]);
    let out_file = opts.out.as_ref().map(|d| d.join(OUTPUT_FILE));
    if let Some(f) = &out_file {
        guard.check(f)?;
    }
    Ok(Prepared {
        corrections,
        chosen,
        guard,
        out_file,
    })
}

fn finish(
    run: &Path,
    mut data: PositioningData,
    p: Prepared,
    obs: &mut dyn Observer,
) -> Result<Outcome> {
    if p.corrections.scale_factor != 1.0 {
        data = data.with_scaled_positions(p.corrections.scale_factor);
    }
    let iso = evaluate_iso230_2(&data);
    let vdi = vdi3441(&iso);
    let standards = (p.chosen != [Standard::Iso230_2_2014]).then(|| {
        p.chosen
            .iter()
            .map(|s| iso230_2::values_of(*s, &iso))
            .collect()
    });
    for w in &data.warnings {
        obs.warning(&format!("{}: {w}", run.display()));
    }
    let outcome = Outcome {
        format: "mtec.iso230-2/1".into(),
        file: run.display().to_string(),
        runs_up: iso.runs_up,
        runs_down: iso.runs_down,
        axis: iso.axis,
        targets: iso.targets,
        vdi3441: vdi,
        corrections: p.corrections,
        standards,
        warnings: data.warnings,
    };
    if let Some(f) = &p.out_file {
        p.guard.write(f, outcome.to_json()?.as_bytes())?;
    }
    Ok(outcome)
}

impl Outcome {
    /// The outcome as the pretty JSON text of `iso230-2.json` (keys sorted).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(&serde_json::to_value(self)?)?)
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, o: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            o,
            "ISO 230-2:2014 positioning of {} ({} runs +, {} runs -)",
            self.file, self.runs_up, self.runs_down
        )?;
        let c = &self.corrections;
        if let Some(a) = &c.air {
            writeln!(
                o,
                "corrected for air ({}, {} nm): {} °C, {} Pa, {} % RH, {} ppm CO2: n_laser {:.9}, n_actual {:.9}, correction {:+.3} ppm",
                a.formula,
                a.wavelength_nm,
                a.temperature_c,
                a.pressure_pa,
                a.humidity_pct,
                a.co2_ppm,
                a.n_laser,
                a.n_actual,
                a.correction_ppm
            )?;
        }
        if let Some(m) = &c.material {
            writeln!(
                o,
                "corrected for material (ISO 1, to 20 °C): {} °C, alpha {} um/m/K: correction {:+.3} ppm",
                m.temperature_c, m.alpha_um_per_m_k, m.correction_ppm
            )?;
        }
        if c.air.is_some() || c.material.is_some() {
            writeln!(
                o,
                "measured positions scaled by {:.12} ({:+.3} ppm)",
                c.scale_factor,
                (c.scale_factor - 1.0) * 1e6
            )?;
        }
        writeln!(o)?;
        writeln!(
            o,
            "{:>10} {:>9} {:>9} {:>7} {:>7} {:>8} {:>8} {:>7}",
            "target_mm", "mean+_um", "mean-_um", "s+_um", "s-_um", "B_i_um", "mean_um", "R_i_um"
        )?;
        for t in &self.targets {
            writeln!(
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
            )?;
        }
        let a = &self.axis;
        writeln!(o)?;
        writeln!(o, "axis values (um)        up      down     bidirectional")?;
        writeln!(
            o,
            "  A  accuracy      {:>8.3}  {:>8.3}  {:>8.3}",
            a.a_up_um, a.a_down_um, a.a_um
        )?;
        writeln!(
            o,
            "  E  systematic    {:>8.3}  {:>8.3}  {:>8.3}",
            a.e_up_um, a.e_down_um, a.e_um
        )?;
        writeln!(
            o,
            "  R  repeatability {:>8.3}  {:>8.3}  {:>8.3}",
            a.r_up_um, a.r_down_um, a.r_um
        )?;
        writeln!(
            o,
            "  M  range of mean bidirectional deviation       {:>8.3}",
            a.m_um
        )?;
        writeln!(
            o,
            "  B  reversal value (max |B_i|)                  {:>8.3}",
            a.b_um
        )?;
        writeln!(
            o,
            "  mean reversal value                            {:>8.3}",
            a.mean_b_um
        )?;
        writeln!(o)?;
        let v = &self.vdi3441;
        writeln!(
            o,
            "VDI/DGQ 3441 (um): Ps = {:.3}  U = {:.3}  Pa = {:.3}  P = {:.3}",
            v.ps_um, v.u_um, v.pa_um, v.p_um
        )?;
        if let Some(st) = &self.standards {
            side_by_side(o, st)?;
        }
        Ok(())
    }
}

/// Reads one quantity of a standard's values (`None`: the standard does not define it).
type Getter = fn(&StandardValues) -> Option<f64>;

/// The chosen standards' axis values in one table, one column per standard.
fn side_by_side(o: &mut fmt::Formatter<'_>, st: &[StandardValues]) -> fmt::Result {
    writeln!(o)?;
    write!(o, "standards side by side (um)  ")?;
    for s in st {
        write!(o, " {:>14}", s.standard)?;
    }
    writeln!(o)?;
    let rows: [(&str, Getter); 5] = [
        ("accuracy (A; P)", |s| Some(s.accuracy_um)),
        ("repeatability (R; Ps)", |s| Some(s.repeatability_um)),
        ("reversal (B; U)", |s| Some(s.reversal_um)),
        ("systematic (E)", |s| s.systematic_um),
        ("range of means (M; Pa)", |s| Some(s.mean_range_um)),
    ];
    for (label, get) in rows {
        write!(o, "  {label:<27}")?;
        for s in st {
            match get(s) {
                Some(x) => write!(o, " {x:>14.3}")?,
                None => write!(o, " {:>14}", "-")?,
            }
        }
        writeln!(o)?;
    }
    let missing: Vec<&str> = iso230_2::NOT_ESTABLISHED.iter().map(|(n, _)| *n).collect();
    writeln!(
        o,
        "not reported (definitions not established, docs/methods.md 2.2): {}",
        missing.join(", ")
    )
}
