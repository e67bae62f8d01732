//! `compensate thermal-offset`: the work-offset update (or Siemens temperature-compensation
//! setting data) for the machine's thermal state now. The method is `mtec_comp::thermal_offset`;
//! this reads the files, calls it and writes the lines.

use crate::{Error, Observer, Result};
use mtec_comp::table::{Axis, DEFAULT_MAX_CORRECTION_UM};
use mtec_comp::thermal_offset::{
    self as to, fanuc, linuxcnc, sinumerik, LoadOptions, OffsetError, OffsetModel, OutsidePolicy,
    RunOptions, SettingOptions, UpdateOptions,
};
use mtec_io::{Destination, OutputGuard, Table};
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// What is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// LinuxCNC `G10 L2 P<offset> Z<base + c>`.
    G10,
    /// FANUC `G90 G10 L2 P<offset> Z<base + c>`.
    Fanuc,
    /// FANUC `#<5201+20*offset+axis-1>=<base + c>`.
    FanucMacro,
    /// Siemens frame fine offset `$P_UIFR[<offset>,Z,FI]=<c>`.
    Sinumerik,
    /// Siemens temperature compensation setting data SD43900/SD43910/SD43920.
    SinumerikSd,
}

impl Format {
    /// The name the command line gives it (`fanuc-macro`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Format::G10 => "g10",
            Format::Fanuc => "fanuc",
            Format::FanucMacro => "fanuc-macro",
            Format::Sinumerik => "sinumerik",
            Format::SinumerikSd => "sinumerik-sd",
        }
    }
}

impl crate::Choice for Format {
    const ALL: &'static [Self] = &[
        Format::G10,
        Format::Fanuc,
        Format::FanucMacro,
        Format::Sinumerik,
        Format::SinumerikSd,
    ];

    fn name(self) -> &'static str {
        Format::name(self)
    }
}

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct Options {
    /// A machine error model (`mtec.machine-error/1`) or a thermal model
    /// (`mtec.thermal-model/1`, with `training`).
    pub model: PathBuf,
    /// The temperature log up to now (CSV: time_min and the model's inputs); its last row is now.
    pub temps: PathBuf,
    pub format: Format,
    /// The axis whose offset is updated.
    pub axis: Axis,
    /// Work offset: g10 P0-P9 (1 = G54), fanuc 1-6 (G54-G59), sinumerik frame 0-99 (1 = G54).
    pub offset: u32,
    /// g10/fanuc: the offset's value with no drift, or when it was set (mm).
    pub base_mm: Option<f64>,
    /// Machine position the offset is used at (mm); needed when the drift depends on position.
    pub at_mm: Option<f64>,
    /// Machine position of the model's position_mm = 0 (mm; sinumerik-sd: SD43920).
    pub position_origin_mm: f64,
    /// Log time at which the offset was last set (min); the update is relative to it.
    pub zeroed_at_min: Option<f64>,
    /// The log's first row is the machine at rest, in equilibrium with the room.
    pub starts_at_rest: bool,
    /// Outside the training envelope: refuse, or fade the update to none.
    pub outside: OutsidePolicy,
    /// Refuse an update larger than this (um).
    pub max_correction_um: f64,
    /// Bare thermal model: its training log (the envelope is the range of every input in it).
    pub training: Option<PathBuf>,
    /// Bare thermal model: 1 if its target is the tool's displacement along +axis, -1 if not.
    pub sign: Option<f64>,
    /// fanuc-macro: the control's axis number (`None`: X1, Y2, Z3).
    pub axis_number: Option<u32>,
    /// sinumerik-sd: the machine axis name (`None`: AX1, AX2, AX3 for X, Y, Z).
    pub machine_axis: Option<String>,
    /// sinumerik-sd: the axis travel FROM, TO (mm) over which the compensation is bounded.
    pub travel_mm: Option<[f64; 2]>,
    /// sinumerik-sd: MD32760 $MA_COMP_ADD_VELO_FACTOR, the largest |tan(beta)|.
    pub comp_add_velo_factor: f64,
    /// Output file; `None` or `-`: stdout.
    pub out: Option<PathBuf>,
}

impl Options {
    /// The `format` update of `model` for the last row of `temps` along Z, offset 1 (G54),
    /// every other option at the command's default (g10 and fanuc formats need `base_mm`).
    pub fn new(model: impl Into<PathBuf>, temps: impl Into<PathBuf>, format: Format) -> Self {
        Options {
            model: model.into(),
            temps: temps.into(),
            format,
            axis: Axis::Z,
            offset: 1,
            base_mm: None,
            at_mm: None,
            position_origin_mm: 0.0,
            zeroed_at_min: None,
            starts_at_rest: false,
            outside: OutsidePolicy::Refuse,
            max_correction_um: DEFAULT_MAX_CORRECTION_UM,
            training: None,
            sign: None,
            axis_number: None,
            machine_axis: None,
            travel_mm: None,
            comp_add_velo_factor: 0.01,
            out: None,
        }
    }
}

/// Parses `--travel-mm FROM:TO` (mm).
pub fn parse_travel(s: &str) -> Result<[f64; 2]> {
    let v: Vec<Option<f64>> = s.split(':').map(|p| p.trim().parse::<f64>().ok()).collect();
    match v.as_slice() {
        [Some(a), Some(b)] => Ok([*a, *b]),
        _ => Err(Error::usage(format!(
            "--travel-mm `{s}`: expected FROM:TO in mm, e.g. -500:0"
        ))),
    }
}

/// A work-offset update (the offset formats).
#[derive(Debug, Clone, Serialize)]
pub struct Update {
    /// Machine position the drift was evaluated at (mm).
    pub at_mm: f64,
    /// e(now) - e(zeroed), before the envelope weight (um).
    pub drift_um: f64,
    /// The envelope weight w (1 inside the training range).
    pub weight: f64,
    /// c = -w * drift (um): the change of the offset.
    pub correction_um: f64,
    /// The drift depends on the position.
    pub position_dependent: bool,
}

/// Siemens temperature-compensation setting data (sinumerik-sd).
#[derive(Debug, Clone, Serialize)]
pub struct Setting {
    /// The machine axis name the data are written for.
    pub machine_axis: String,
    /// SD43900 K0 (mm).
    pub k0_mm: f64,
    /// SD43910 tan(beta) (mm/mm).
    pub tan_beta: f64,
    /// SD43920 P0 (mm, machine coordinate).
    pub p0_mm: f64,
    /// The envelope weight w.
    pub weight: f64,
    /// The drift depends on the position (MD32750 bit 1 as well as bit 0).
    pub position_dependent: bool,
}

/// What [`run`] did.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    pub format: Format,
    /// `X`, `Y` or `Z`.
    pub axis: char,
    /// The offset update (every format but sinumerik-sd).
    pub update: Option<Update>,
    /// The setting data (sinumerik-sd).
    pub setting: Option<Setting>,
    /// The lines written (the program text).
    pub text: String,
    /// Line of the log's last row (now) in its file.
    pub now_line: usize,
    /// Time of the last row (min).
    pub now_time_min: f64,
    /// Rows before now outside the training envelope.
    pub earlier_outside: usize,
    /// The temperature log.
    pub temps: PathBuf,
    /// Where the lines went (`None`: stdout).
    pub out: Option<PathBuf>,
    /// Notes on the log (rows outside the envelope before now).
    pub notes: Vec<String>,
}

impl fmt::Display for Outcome {
    /// The summary line the command prints on stderr.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "thermal-offset: ")?;
        if let Some(s) = &self.setting {
            write!(
                f,
                "{} temperature compensation: K0 {:+.3} um at P0 {} mm, tan(beta) {:.4e}, weight {}",
                self.axis,
                s.k0_mm * 1e3,
                s.p0_mm,
                s.tan_beta,
                s.weight
            )?;
        }
        if let Some(u) = &self.update {
            write!(
                f,
                "{} offset update {:+.3} um (drift {:+.3} um, weight {})",
                self.axis, u.correction_um, u.drift_um, u.weight
            )?;
        }
        writeln!(
            f,
            " at line {} ({} min) of {}",
            self.now_line,
            self.now_time_min,
            self.temps.display()
        )
    }
}

fn lib_error(e: OffsetError) -> Error {
    match e {
        OffsetError::Input(i) => Error::Input(i),
        OffsetError::Usage(m) => Error::Usage(m),
    }
}

/// Options given that the format does not use are refused, not silently ignored.
fn check_options(o: &Options) -> Result<()> {
    use crate::unused::{refuse_unused, Given};
    use Format::*;
    let f = o.format;
    let d = Options::new(&o.model, &o.temps, f);
    let (sd, offsets) = (
        "--format sinumerik-sd",
        "the work-offset formats (not sinumerik-sd)",
    );
    let options = [
        Given::new("--offset", o.offset != d.offset, f != SinumerikSd, offsets),
        Given::new(
            "--comp-add-velo-factor",
            o.comp_add_velo_factor != d.comp_add_velo_factor,
            f == SinumerikSd,
            sd,
        ),
        Given::new(
            "--base-mm",
            o.base_mm.is_some(),
            matches!(f, G10 | Fanuc | FanucMacro),
            "--format g10, fanuc and fanuc-macro",
        ),
        Given::new("--at-mm", o.at_mm.is_some(), f != SinumerikSd, offsets),
        Given::new(
            "--axis-number",
            o.axis_number.is_some(),
            f == FanucMacro,
            "--format fanuc-macro",
        ),
        Given::new(
            "--machine-axis",
            o.machine_axis.is_some(),
            f == SinumerikSd,
            sd,
        ),
        Given::new("--travel-mm", o.travel_mm.is_some(), f == SinumerikSd, sd),
        Given::new(
            "--zeroed-at-min",
            o.zeroed_at_min.is_some(),
            f != SinumerikSd,
            offsets,
        ),
    ];
    refuse_unused(&format!("--format {}", f.name()), &options)?;
    if matches!(f, G10 | Fanuc | FanucMacro) && o.base_mm.is_none() {
        return Err(Error::usage(
            "--base-mm is required: the offset's value with no drift (or when it was set, with --zeroed-at-min); the line sets the offset to base + update",
        ));
    }
    Ok(())
}

/// Runs the model over the log, computes the update now and writes its lines. Options the
/// format does not use and an output that is an input are refused before any reading.
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    check_options(opts)?;
    let mut inputs = vec![opts.model.clone(), opts.temps.clone()];
    inputs.extend(opts.training.clone());
    let dest = match &opts.out {
        Some(p) => OutputGuard::new(&inputs).check(p)?,
        None => Destination::Stdout,
    };
    let outcome = update_checked(opts, &Table::read(&opts.temps)?)?;
    dest.write(outcome.text.as_bytes())?;
    Ok(outcome)
}

/// [`run`] on a temperature log already read (a file, or the Python module's arrays; `temps`
/// is not read, the log's path names it), without writing: the update and its text.
pub fn update_now(opts: &Options, log: &Table) -> Result<Outcome> {
    check_options(opts)?;
    update_checked(opts, log)
}

/// [`update_now`] of options already checked.
fn update_checked(opts: &Options, log: &Table) -> Result<Outcome> {
    let axis = opts.axis;
    let mut model = OffsetModel::load(
        &opts.model,
        LoadOptions {
            axis,
            sign: opts.sign,
            training: opts.training.as_deref(),
        },
    )
    .map_err(lib_error)?;
    let run = to::run_log(
        &mut model,
        log,
        RunOptions {
            starts_at_rest: opts.starts_at_rest,
            zeroed_at_min: opts.zeroed_at_min,
        },
    )
    .map_err(lib_error)?;
    let update_opts = UpdateOptions {
        origin_mm: opts.position_origin_mm,
        outside: opts.outside,
        max_correction_um: opts.max_correction_um,
    };
    let header = to::provenance(&run, log, model.source());
    let (text, update, setting) = if opts.format == Format::SinumerikSd {
        let s = to::temp_comp_setting(
            &run,
            log,
            axis,
            SettingOptions {
                update: update_opts,
                travel_mm: opts.travel_mm,
                max_slope: opts.comp_add_velo_factor,
            },
        )
        .map_err(lib_error)?;
        let name = opts
            .machine_axis
            .clone()
            .unwrap_or_else(|| format!("AX{}", axis.index() + 1));
        let text = sinumerik::write_temp_comp(&s, &name, &header).map_err(lib_error)?;
        let setting = Setting {
            machine_axis: name,
            k0_mm: s.k0_mm,
            tan_beta: s.tan_beta,
            p0_mm: s.p0_mm,
            weight: s.weight,
            position_dependent: s.position_dependent,
        };
        (text, None, Some(setting))
    } else {
        let u = to::offset_update(&run, log, axis, opts.at_mm, update_opts).map_err(lib_error)?;
        let base = opts.base_mm.unwrap_or(0.0);
        let text = match opts.format {
            Format::G10 => linuxcnc::write(&u, opts.offset, base, &header),
            Format::Fanuc => fanuc::write_g10(&u, opts.offset, base, &header),
            Format::FanucMacro => fanuc::write_macro(
                &u,
                opts.offset,
                opts.axis_number.unwrap_or(axis.index() as u32 + 1),
                base,
                &header,
            ),
            Format::Sinumerik => sinumerik::write_frame(&u, opts.offset, &header),
            Format::SinumerikSd => unreachable!("handled above"),
        }
        .map_err(lib_error)?;
        let update = Update {
            at_mm: u.at_mm,
            drift_um: u.drift_um,
            weight: u.weight,
            correction_um: u.correction_um,
            position_dependent: u.position_dependent,
        };
        (text, Some(update), None)
    };
    let mut notes = Vec::new();
    if run.earlier_outside > 0 {
        notes.push(format!(
            "{} earlier row(s) of {} were outside the training envelope; the model's filters carry their history",
            run.earlier_outside,
            log.path.display()
        ));
    }
    Ok(Outcome {
        format: opts.format,
        axis: axis.letter(),
        update,
        setting,
        text,
        now_line: run.now.line,
        now_time_min: run.now.time_min,
        earlier_outside: run.earlier_outside,
        temps: log.path.clone(),
        out: opts.out.clone(),
        notes,
    })
}
