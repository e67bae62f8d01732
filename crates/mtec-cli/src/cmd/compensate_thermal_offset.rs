//! `mtec compensate thermal-offset`: the work-offset update (or Siemens temperature-compensation
//! setting data) for the machine's thermal state now. The logic is in
//! `mtec_comp::thermal_offset`; this parses and prints.

use crate::error::CliError;
use mtec_comp::table::{Axis, DEFAULT_MAX_CORRECTION_UM};
use mtec_comp::thermal_offset::{
    self as to, fanuc, linuxcnc, sinumerik, LoadOptions, OffsetError, OffsetModel, OutsidePolicy,
    RunOptions, SettingOptions, UpdateOptions,
};
use mtec_io::{Destination, OutputGuard, Table};
use std::path::PathBuf;

pub const HELP: &str = "\
Writes the part-program lines that bring a work offset up to date with the machine's thermal
drift now, for controllers without a real-time hook: shops that re-zero at each tool change run
these lines there instead of probing. Formats are described in docs/formats.md, the method in
docs/methods.md.

The state now: --temps is the temperature log up to now (time_min and the model's input columns,
e.g. t3_c, spindle_rpm, ambient_c), one continuous record; the model runs over every row and
its state at the last row is used. Lag filters and exp-ambient's temperature rises start at the
first row as if the machine were at rest there, in equilibrium with the room, as in training. So
give the log since the machine was last at rest and --starts-at-rest; a log that does not start
at rest is accepted only when it spans 5 of the model's slowest time constants (exp-ambient: never).

The update: mtec's error e is where the tool goes wrong (it reaches commanded + e); the offset
moves by c = -e, so a predicted +12 um drift in Z moves the offset, and with it the tool relative
to the part, by -12 um. If the offset was set (touched off, probed) while the machine was already
warm, give --zeroed-at-min T (its time in the log): c = -(e(now) - e(T)). Absolute values are
written, never increments: running the lines twice gives the same offset.

Formats:
  g10           LinuxCNC:  G10 L2 P<offset> Z<base + c>           (--base-mm required)
  fanuc         FANUC:     G90 G10 L2 P<offset> Z<base + c>       (--base-mm required)
  fanuc-macro   FANUC:     #<5201+20*offset+axis-1>=<base + c>    (--base-mm required)
  sinumerik     Siemens:   $P_UIFR[<offset>,Z,FI]=<c>, then G54 (or the frame's G code): the
                update goes into the frame's fine offset, the touched-off coarse one stays
  sinumerik-sd  Siemens temperature compensation SD43900/SD43910/SD43920 of --machine-axis:
                K0 = e at P0 = --position-origin-mm, tan(beta) = the slope; needs MD32750

Safety: an input outside the model's training range refuses the update (exit 2) unless
--outside fade accepts the safe fallback: the update scaled by the envelope weight, down to no
update. An update larger than --max-correction-um (default 500 um) is refused.

Positions (mm, machine coordinates): --position-origin-mm is where the model's position_mm is 0;
a model whose drift depends on the position (exp-ambient, e = k*x + b) needs --at-mm (offset
formats: where the offset is used) or --travel-mm (sinumerik-sd: the axis travel, for the bound).";

const EXAMPLES: &str = crate::help::examples!(
    "  # training days of a machining centre, and a day's log since it started cold
  $ mtec simulate production-day --out p
  $ mtec thermal fit --data p/train.csv --target dz_um --model mlr -o p/dz.json
  $ mtec machine build --thermal z=p/dz.json -o p/machine.json
  # the G10 line that updates G54's Z (-312.45 mm, touched off cold) for now
  $ mtec compensate thermal-offset --model p/machine.json \\
      --temps p/day-state.csv --starts-at-rest --format g10 --offset 1 \\
      --base-mm -312.45"
);

/// Output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    G10,
    Fanuc,
    FanucMacro,
    Sinumerik,
    SinumerikSd,
}

/// Policy outside the training envelope.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Outside {
    Refuse,
    Fade,
}

/// `mtec compensate thermal-offset`.
#[derive(clap::Args)]
#[command(after_long_help = EXAMPLES)]
pub struct Args {
    /// A machine error model (mtec.machine-error/1: thermal parts with axis, sign, envelope) or
    /// a thermal model (mtec.thermal-model/1, with --training).
    #[arg(long)]
    model: PathBuf,
    /// The temperature log up to now (CSV: time_min and the model's inputs); the last row is now.
    #[arg(long)]
    temps: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value = "g10")]
    format: Format,
    /// The axis whose offset is updated: X, Y or Z.
    #[arg(long, default_value = "Z")]
    axis: String,
    /// Work offset: g10 P0-P9 (1 = G54), fanuc 1-6 (G54-G59), sinumerik frame 0-99 (1 = G54).
    #[arg(long, default_value_t = 1)]
    offset: u32,
    /// g10/fanuc: the offset's value (mm) with no drift, or when it was set (--zeroed-at-min).
    #[arg(long, allow_hyphen_values = true)]
    base_mm: Option<f64>,
    /// Machine position (mm) the offset is used at; needed when the drift depends on position.
    #[arg(long, allow_hyphen_values = true)]
    at_mm: Option<f64>,
    /// Machine position (mm) of the model's position_mm = 0 (sinumerik-sd: SD43920).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    position_origin_mm: f64,
    /// Log time (min) at which the offset was last set; the update is relative to that moment.
    #[arg(long, allow_hyphen_values = true)]
    zeroed_at_min: Option<f64>,
    /// The log's first row is the machine at rest, in equilibrium with the room.
    #[arg(long)]
    starts_at_rest: bool,
    /// Outside the training envelope: refuse, or fade the update to none (the safe fallback).
    #[arg(long, value_enum, default_value = "refuse")]
    outside: Outside,
    /// Refuse an update larger than this (um).
    #[arg(long, default_value_t = DEFAULT_MAX_CORRECTION_UM)]
    max_correction_um: f64,
    /// Bare thermal model: its training log (the envelope is the range of every input in it).
    #[arg(long)]
    training: Option<PathBuf>,
    /// Bare thermal model: 1 if its target is the tool's displacement along +axis, -1 if opposite.
    #[arg(long, allow_hyphen_values = true)]
    sign: Option<f64>,
    /// fanuc-macro: the control's axis number (default X1, Y2, Z3).
    #[arg(long)]
    axis_number: Option<u32>,
    /// sinumerik-sd: the machine axis name (default AX1, AX2, AX3 for X, Y, Z).
    #[arg(long)]
    machine_axis: Option<String>,
    /// sinumerik-sd: the axis travel FROM:TO (mm), over which the compensation is bounded.
    #[arg(long, allow_hyphen_values = true)]
    travel_mm: Option<String>,
    /// sinumerik-sd: MD32760 $MA_COMP_ADD_VELO_FACTOR, the largest |tan(beta)|.
    #[arg(long, default_value_t = 0.01)]
    comp_add_velo_factor: f64,
    /// Output file (default and `-`: stdout), replaced atomically.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

fn lib_error(e: OffsetError) -> CliError {
    match e {
        OffsetError::Input(i) => CliError::Input(i),
        OffsetError::Usage(m) => CliError::Usage(m),
    }
}

/// Options given that the format does not use are refused, not silently ignored.
fn check_options(a: &Args) -> Result<(), CliError> {
    use Format::*;
    let f = a.format;
    let rules: [(&str, bool, bool); 6] = [
        (
            "--base-mm",
            a.base_mm.is_some(),
            matches!(f, G10 | Fanuc | FanucMacro),
        ),
        ("--at-mm", a.at_mm.is_some(), f != SinumerikSd),
        ("--axis-number", a.axis_number.is_some(), f == FanucMacro),
        ("--machine-axis", a.machine_axis.is_some(), f == SinumerikSd),
        ("--travel-mm", a.travel_mm.is_some(), f == SinumerikSd),
        (
            "--zeroed-at-min",
            a.zeroed_at_min.is_some(),
            f != SinumerikSd,
        ),
    ];
    for (flag, given, applies) in rules {
        if given && !applies {
            use clap::ValueEnum;
            let name = f
                .to_possible_value()
                .map(|v| v.get_name().to_string())
                .unwrap_or_default();
            return Err(CliError::usage(format!(
                "{flag} does not apply to --format {name} (see --help)"
            )));
        }
    }
    if matches!(f, G10 | Fanuc | FanucMacro) && a.base_mm.is_none() {
        return Err(CliError::usage(
            "--base-mm is required: the offset's value with no drift (or when it was set, with --zeroed-at-min); the line sets the offset to base + update",
        ));
    }
    Ok(())
}

fn parse_travel(s: &str) -> Result<[f64; 2], CliError> {
    let v: Vec<Option<f64>> = s.split(':').map(|p| p.trim().parse::<f64>().ok()).collect();
    match v.as_slice() {
        [Some(a), Some(b)] => Ok([*a, *b]),
        _ => Err(CliError::usage(format!(
            "--travel-mm `{s}`: expected FROM:TO in mm, e.g. -500:0"
        ))),
    }
}

pub fn run(a: Args) -> Result<(), CliError> {
    check_options(&a)?;
    let axis = Axis::parse(&a.axis)
        .ok_or_else(|| CliError::usage(format!("--axis `{}`: expected X, Y or Z", a.axis)))?;
    let mut inputs = vec![a.model.clone(), a.temps.clone()];
    inputs.extend(a.training.clone());
    let dest = match &a.out {
        Some(p) => OutputGuard::new(&inputs).check(p)?,
        None => Destination::Stdout,
    };
    let mut model = OffsetModel::load(
        &a.model,
        LoadOptions {
            axis,
            sign: a.sign,
            training: a.training.as_deref(),
        },
    )
    .map_err(lib_error)?;
    let log = Table::read(&a.temps)?;
    let run = to::run_log(
        &mut model,
        &log,
        RunOptions {
            starts_at_rest: a.starts_at_rest,
            zeroed_at_min: a.zeroed_at_min,
        },
    )
    .map_err(lib_error)?;
    let update_opts = UpdateOptions {
        origin_mm: a.position_origin_mm,
        outside: match a.outside {
            Outside::Refuse => OutsidePolicy::Refuse,
            Outside::Fade => OutsidePolicy::Fade,
        },
        max_correction_um: a.max_correction_um,
    };
    let header = to::provenance(&run, &log, model.source());
    let (text, summary) = if a.format == Format::SinumerikSd {
        let travel = a.travel_mm.as_deref().map(parse_travel).transpose()?;
        let s = to::temp_comp_setting(
            &run,
            &log,
            axis,
            SettingOptions {
                update: update_opts,
                travel_mm: travel,
                max_slope: a.comp_add_velo_factor,
            },
        )
        .map_err(lib_error)?;
        let name = a
            .machine_axis
            .clone()
            .unwrap_or_else(|| format!("AX{}", axis.index() + 1));
        let text = sinumerik::write_temp_comp(&s, &name, &header).map_err(lib_error)?;
        let summary = format!(
            "{} temperature compensation: K0 {:+.3} um at P0 {} mm, tan(beta) {:.4e}, weight {}",
            axis.letter(),
            s.k0_mm * 1e3,
            s.p0_mm,
            s.tan_beta,
            s.weight
        );
        (text, summary)
    } else {
        let u = to::offset_update(&run, &log, axis, a.at_mm, update_opts).map_err(lib_error)?;
        let base = a.base_mm.unwrap_or(0.0);
        let text = match a.format {
            Format::G10 => linuxcnc::write(&u, a.offset, base, &header),
            Format::Fanuc => fanuc::write_g10(&u, a.offset, base, &header),
            Format::FanucMacro => fanuc::write_macro(
                &u,
                a.offset,
                a.axis_number.unwrap_or(axis.index() as u32 + 1),
                base,
                &header,
            ),
            Format::Sinumerik => sinumerik::write_frame(&u, a.offset, &header),
            Format::SinumerikSd => unreachable!("handled above"),
        }
        .map_err(lib_error)?;
        let summary = format!(
            "{} offset update {:+.3} um (drift {:+.3} um, weight {})",
            axis.letter(),
            u.correction_um,
            u.drift_um,
            u.weight
        );
        (text, summary)
    };
    dest.write(text.as_bytes())?;
    eprintln!(
        "thermal-offset: {summary} at line {} ({} min) of {}",
        run.now.line,
        run.now.time_min,
        a.temps.display()
    );
    if run.earlier_outside > 0 {
        eprintln!(
            "note: {} earlier row(s) of {} were outside the training envelope; the model's filters carry their history",
            run.earlier_outside,
            a.temps.display()
        );
    }
    Ok(())
}
