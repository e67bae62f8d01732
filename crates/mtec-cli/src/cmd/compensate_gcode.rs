//! `mtec compensate gcode`: rewrites an NC program so the machine reaches the programmed points.

use crate::help::{examples, text};
use crate::{choice::choice, error::CliError};
use mtec_comp::gcode::tooltable::MachineUnits;
use mtec_comp::gcode::{OnUnsupported, RewriteOptions, Units};
use mtec_workflow::ops::compensate_gcode::{self, Options};
use mtec_workflow::ops::selective::Elements;
use mtec_workflow::rs274::Rs274;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
#[command(
    about = "Rewrite an NC program (G-code) so the machine reaches the programmed points",
    long_about = text!("compensate_gcode.long_about"),
    after_long_help = examples!("compensate_gcode.examples")
)]
pub struct Args {
    /// Error model (JSON): any model file mtec writes (see below).
    #[arg(long, value_name = "MODEL.json")]
    pub model: PathBuf,
    /// State log for a model with a state (mtec.machine-error/1): time_min and the model's
    /// state inputs; the state after the last row is compensated for. Required for such a model.
    #[arg(long, value_name = "LOG.csv")]
    pub state: Option<PathBuf>,
    /// The NC program to correct.
    #[arg(value_name = "IN.ngc")]
    pub input: PathBuf,
    /// Where to write the corrected program (never an input; a file is replaced atomically, a
    /// device or FIFO written in place, `-` is stdout).
    #[arg(short, long, value_name = "OUT.ngc")]
    pub output: PathBuf,
    /// Largest distance of the compensated path from the programmed one, in um (the bound
    /// every output piece is split to).
    #[arg(long, default_value_t = 0.5)]
    pub tolerance_um: f64,
    /// Longest piece of a compensated feed move, in mm.
    #[arg(long, default_value_t = 10.0)]
    pub max_segment_mm: f64,
    /// Largest chord sagitta when an arc is replaced by straight pieces, in um.
    #[arg(long, default_value_t = 0.5)]
    pub chord_tolerance_um: f64,
    /// Refuse corrections larger than this, in um (at most 10000).
    #[arg(long, default_value_t = 500.0)]
    pub max_correction_um: f64,
    /// What to do with constructs that cannot be compensated safely.
    #[arg(long, value_parser = choice::<OnUnsupported>(), default_value = "refuse")]
    pub on_unsupported: OnUnsupported,
    /// Work offsets and tool lengths (TOML, format mtec.gcode-offsets/1).
    #[arg(long, value_name = "CFG.toml")]
    pub offsets: Option<PathBuf>,
    /// Units before the program's first G20/G21 (the controller's power-on default).
    #[arg(long, value_parser = choice::<Units>(), default_value = "mm")]
    pub default_units: Units,
    /// Digits after the point of rewritten words in mm programs [default: 4, more if
    /// --tolerance-um needs them].
    #[arg(long)]
    pub decimals_mm: Option<usize>,
    /// Digits after the point of rewritten words in inch programs [default: 5, more if
    /// --tolerance-um needs them].
    #[arg(long)]
    pub decimals_inch: Option<usize>,
    /// Machine position at program start, "x,y,z" in mm (e.g. home; on a lathe the fixed Y).
    #[arg(long, value_name = "X,Y,Z")]
    pub start_position_mm: Option<String>,
    /// Sample spacing of the path check for models that are not grid maps, in mm (0.001-10).
    #[arg(long, default_value_t = 0.5)]
    pub check_step_mm: f64,
    /// Machine angles of the rotary axes at program start, "a,b,c" in degrees (only the axes of
    /// the model's chain are used, e.g. "0,0,90" for C at 90 on a WCAYFXZT). Without it an
    /// angle is unknown until the program commands it, and a feed move before that is refused.
    #[arg(long, value_name = "A,B,C")]
    pub start_rotary_deg: Option<String>,
    /// Largest turn of a rotary axis between samples of the path check of a move that turns
    /// one, in degrees (0.5° moves a point 500 mm from the axis by 4.4 mm along its arc; the
    /// check also samples every --check-step-mm of the tool tip's path; 0.001-10).
    #[arg(long, default_value_t = 0.5)]
    pub check_step_deg: f64,
    /// Longest line the controller reads (LinuxCNC: 251 with either line ending); longer
    /// rewritten lines are refused.
    #[arg(long, default_value_t = 251)]
    pub max_line_chars: usize,
    /// Elements of a kinematic model to compensate: all, key (ranked by EFAST) or a list (EXX,EYY).
    #[arg(long, default_value = "all")]
    pub elements: Elements,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

/// The interpreters a program can be flattened with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FlattenWith {
    /// LinuxCNC's stand-alone interpreter (`rs274 -g`, Debian package linuxcnc-uspace).
    Rs274,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum OnOff {
    On,
    Off,
}

/// The flattening options of `compensate gcode`.
#[derive(clap::Args, Debug, Clone)]
pub struct FlattenArgs {
    /// Run the program through LinuxCNC's interpreter first and compensate the moves it makes
    /// (for O-word subroutines/loops, canned cycles, cutter compensation, parameters, G92...).
    /// The output is then a LinuxCNC-only plain program.
    #[arg(long, value_enum, value_name = "rs274")]
    pub flatten_with: Option<FlattenWith>,
    /// The rs274 binary to use (default: `rs274` on PATH).
    #[arg(long, value_name = "PATH", requires = "flatten_with")]
    pub rs274: Option<PathBuf>,
    /// LinuxCNC tool table (.tbl): tool lengths for G43 (Z offsets, in --machine-units);
    /// --flatten-with passes it (else the --offsets lengths, never rs274's built-in) to rs274.
    #[arg(long, value_name = "FILE.tbl")]
    pub tool_table: Option<PathBuf>,
    /// The machine's units (LinuxCNC's INI LINEAR_UNITS), in which tool tables and parameter
    /// files hold their lengths (not the program's G20/G21). Stand-alone rs274 reads both as
    /// inches, so with `mm` they are handed to it converted.
    #[arg(
        long,
        value_parser = choice::<MachineUnits>(),
        default_value = "mm",
        value_name = "mm|inch"
    )]
    pub machine_units: MachineUnits,
    /// Parameter file for rs274 (`-v`): work offsets and other parameters (copied, never written).
    #[arg(long, value_name = "FILE.var", requires = "flatten_with")]
    pub var_file: Option<PathBuf>,
    /// The operator's block delete switch: `on` skips `/` blocks (copied, not interpreted),
    /// `off` runs them; not given, a `/` block that moves or sets a mode is refused. With
    /// --flatten-with, `on` is passed to rs274 as `-b`.
    #[arg(long, value_enum, value_name = "on|off")]
    pub block_delete: Option<OnOff>,
    /// Stop rs274 after this many seconds (a program that loops forever).
    #[arg(
        long,
        default_value_t = 300.0,
        value_name = "S",
        requires = "flatten_with"
    )]
    pub rs274_timeout_s: f64,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let base = RewriteOptions::with_tolerance(args.tolerance_um);
    let rewrite = RewriteOptions {
        max_segment_mm: args.max_segment_mm,
        chord_tolerance_um: args.chord_tolerance_um,
        max_correction_um: args.max_correction_um,
        on_unsupported: args.on_unsupported,
        default_units: args.default_units,
        decimals_mm: args.decimals_mm.unwrap_or(base.decimals_mm),
        decimals_inch: args.decimals_inch.unwrap_or(base.decimals_inch),
        check_step_mm: args.check_step_mm,
        check_step_deg: args.check_step_deg,
        max_line_chars: args.max_line_chars,
        start_position_mm: args
            .start_position_mm
            .as_deref()
            .map(compensate_gcode::parse_start_position)
            .transpose()?,
        start_rotary_deg: args
            .start_rotary_deg
            .as_deref()
            .map(compensate_gcode::parse_start_rotary)
            .transpose()?,
        ..base
    };
    let f = args.flatten;
    let opts = Options {
        model: args.model,
        state: args.state,
        input: args.input,
        output: args.output,
        rewrite,
        elements: args.elements,
        offsets: args.offsets,
        tool_table: f.tool_table,
        machine_units: f.machine_units,
        block_delete: f.block_delete.map(|b| b == OnOff::On),
        flatten: f.flatten_with.map(|FlattenWith::Rs274| Rs274 {
            bin: f.rs274,
            var_file: f.var_file,
            timeout_s: f.rs274_timeout_s,
        }),
    };
    let done = compensate_gcode::run(&opts, &mut crate::observer::Stderr::default())?;
    // the report goes to stdout unless the program itself does (-o -)
    if opts.output.as_os_str() == "-" {
        eprint!("{done}");
    } else {
        print!("{done}");
    }
    for n in &done.notes {
        eprintln!("note: {n}");
    }
    Ok(())
}
