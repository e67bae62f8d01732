//! `mtec compensate gcode`: rewrites an NC program so the machine reaches the programmed points.

use crate::error::CliError;
use mtec_comp::gcode::tooltable::MachineUnits;
use mtec_comp::gcode::{OnUnsupported, RewriteOptions, Units};
use mtec_workflow::ops::compensate_gcode::{self, Options};
use mtec_workflow::rs274::Rs274;
use std::path::PathBuf;

pub const LONG_ABOUT: &str = "\
Rewrites an NC program (RS274/NGC as LinuxCNC reads it, or common Fanuc style) so that every
commanded point is corrected for the machine's volumetric error: the command p that makes the
machine reach the target t solves p + e(p) = t. Every feed move (G1, G2/G3 including full
circles without axis words, G53 G1) is split until a bound of the tool's distance from the
programmed path is at most --tolerance-um on every piece (no piece longer than
--max-segment-mm); arcs stay arcs (R arcs are written with their centre I/J/K) when the bound
allows it, otherwise they become chords of sagitta <= --chord-tolerance-um, each split the same
way. The bound is exact for trilinear grid maps (the map is cubic along a line inside a cell:
moves are cut at cell planes and each cubic's maximum is solved), and for other models it is
checked at samples every --check-step-mm. Rapids are corrected at their end points. The
documented guarantee: every point of the compensated path lies within --tolerance-um of the
programmed path (plus --chord-tolerance-um on linearised arcs), the rounding of the written
words included; options that cannot hold it (too few --decimals-mm) are refused.

Only the words that change are edited: comments, line numbers, unknown words, spacing and line
endings are kept. With a zero model the output is byte-identical to the input. A comment naming
the model is written just before the first corrected line.

LinuxCNC parameters and [expressions] with literal values are evaluated as LinuxCNC does, and
G10 L1/L2/L20, G92, G52, G92.1, G92.2 are followed as modal state. Constructs that cannot be
compensated safely (parameters known only at run time, O-word subroutines and loops, canned
cycles, cutter compensation G41/G42, G92.3, G10 other than L1/L2/L20 or with a rotation or a
rotary word, two codes of one modal group) stop the run with file:line:column
(--on-unsupported refuse), or are copied unchanged with a warning (pass-through-with-warning).

Rotary axes (A, B, C): with a kinematic model whose chain has them (mtec.kinematic-model/1,
e.g. a table-tilting WCAYFXZT or a head WYXFZCBT), five-axis programs are compensated as
LinuxCNC runs them without tool centre point control: in a G1 every joint moves linearly from
its start to its end value, so the programmed tool tip is the ideal chain's tool tip along that
joint path (a curve as soon as an axis turns). The rotary words are kept (rounded to 4 decimals
where a move is split, the rounding absorbed by X Y Z) and X, Y, Z are corrected so that the
tool tip with the model's errors lies on that curve; a move is split until every piece is
within --tolerance-um, checked at samples every --check-step-mm of the tool tip's path and
every --check-step-deg of any rotary axis. The tool orientation is not corrected (the rotary
words stay as programmed). Split moves keep their duration under LinuxCNC's feed rules: in G94
the length of a move is its XYZ length when X, Y or Z moves, else its rotary length in degrees;
in G93 (inverse time) every piece gets F = 1/(its share of the time). The angles must be known
before the first feed move: programmed, or given by --start-rotary-deg a,b,c (machine angles;
only the axes of the model's chain are used). Refused with file:line:column: a rotary word for an
axis the model's chain lacks or with a model that has no rotary axes (a three-axis map does not
know where a turned table puts the tool), U/V/W words (no chain mtec models has them), an arc
that turns a rotary axis, G93 without F, G95 moves that would need new feeds, and poses where
the linear axes do not move the tool tip along three perpendicular directions.

Models (--model): a JSON file whose \"format\" says what it is (docs/formats.md, \"Other compensable
model files\"); each gives [Ex, Ey, Ez] in um as a function of the machine position in mm:
  mtec.map/1              a volumetric error map (trilinear grid): `mtec map fit --grid GRID.csv`
  mtec.bpnn/1             a neural map of a grid (x, y, z -> ex, ey, ez):
                          `mtec map fit --grid GRID.csv --model bpnn`
  mtec.kinematic-model/1  a machine with its error set (three axes, or with A, B, C: evaluated at
                          the commanded angles): `mtec identify lines --kinematic-model
                          FILE`; `mtec run` writes kinematic-model.json from a project with
                          [lines] and [compensation] and no [map]
  mtec.machine-error/1    a geometric model plus thermal models with a state:
                          `mtec machine build`; needs --state (below)
  mtec.poly-model/1       a polynomial E = sum of coef_um * x^i y^j z^k, written by hand:
                          {\"format\": \"mtec.poly-model/1\", \"terms\": [{\"powers\": [1,0,0],
                          \"coef_um\": [0.012,0,0]}]}
  mtec.zero-model/1       no error, written by hand: {\"format\": \"mtec.zero-model/1\"}; the output
                          is then byte-identical to the input
A machine error model's thermal part depends on the machine's temperatures now, so it needs
--state LOG.csv (time_min and the model's state inputs, rows in time order); every row advances
the state and the program is compensated for the state after the last row, which the header
comment names. Without --state such a model is refused.

Offsets (--offsets, TOML) map program to machine coordinates (machine = program + work offset
+ G92/G52 offset + tool length along Z); G10 L1/L2/L20, G92, G52, G92.1 and G92.2 with literal
values in the program change them as LinuxCNC does:
  format = \"mtec.gcode-offsets/1\"
  active = \"G54\"
  [work_offsets_mm]
  G54 = [250.0, 120.0, -300.0]
  [tool_lengths_mm]
  1 = 85.25

Without --offsets only G54 is known (as zero: program coordinates are machine coordinates); a
program that selects another work system is refused at that word. Every written line is at
most --max-line-chars long (251: LinuxCNC's interpreter refuses 253 characters, a CR
counting as one); the header comment is shortened to fit.

Flattening (--flatten-with rs274): for programs the rewriter refuses (O-word subroutines and
loops, canned cycles, cutter compensation, polar coordinates, parameters, G92/G52, G10), LinuxCNC's
interpreter (rs274, package linuxcnc-uspace) runs the program first and its moves are written as a
plain program (G0/G1, G2/G3 with I J K, F, S, M3/M4/M5, M7/M8/M9, G4, T M6), which is then
compensated. The output is a LinuxCNC-only program for one setup: cutter radius compensation and
tool lengths are baked in for the tool table given (--tool-table), G92/G52 offsets and work offsets
changed by the program are folded into the coordinates (the output runs with G49 and no G92), and
it keeps the original's G54-G59.3 selection, so it reaches the same machine positions when run
with the same work-offset table (--var-file; without --offsets the model is evaluated with the
work offsets rs274 read from it). Refused, with
rs274's line: spindle-synchronised motion (G33, G76), probing (G38.x), rigid tapping (G33.1),
splines (G5.x), U/V/W motion, A/B/C offsets, arcs that turn a rotary axis, a rotated work system
(G10 L2 R), and anything rs274 itself
refuses (its message is passed on). Note that stand-alone rs274 reads tool-table and parameter
file lengths as inches.";

const EXAMPLES: &str = crate::help::examples!(
    "  # a volumetric error map from a laser-tracker grid
  $ mtec simulate volumetric-grid --out g
  $ mtec map fit --grid g/grid.csv -o g/map.json
  # a part program (a contour with an arc), in machine coordinates
  $ printf '%s\\n' 'G21 G90 G17' 'G0 X20 Y20 Z50' 'G1 Z20 F300' \\
      'G1 X200 F1200' 'G2 X200 Y120 J50' 'G1 X20' 'G1 Y20' 'G0 Z50' \\
      M2 > part.ngc
  # the program corrected for the map (within --tolerance-um, 0.5 um)
  $ mtec compensate gcode --model g/map.json part.ngc -o part-compensated.ngc"
);

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum OnUnsupportedArg {
    Refuse,
    PassThroughWithWarning,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum UnitsArg {
    Mm,
    Inch,
}

#[derive(clap::Args, Debug)]
#[command(
    about = "Rewrite an NC program (G-code) so the machine reaches the programmed points",
    long_about = LONG_ABOUT,
    after_long_help = EXAMPLES
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
    /// Refuse corrections larger than this, in um.
    #[arg(long, default_value_t = 500.0)]
    pub max_correction_um: f64,
    /// What to do with constructs that cannot be compensated safely.
    #[arg(long, value_enum, default_value = "refuse")]
    pub on_unsupported: OnUnsupportedArg,
    /// Work offsets and tool lengths (TOML, format mtec.gcode-offsets/1).
    #[arg(long, value_name = "CFG.toml")]
    pub offsets: Option<PathBuf>,
    /// Units before the program's first G20/G21 (the controller's power-on default).
    #[arg(long, value_enum, default_value = "mm")]
    pub default_units: UnitsArg,
    /// Digits after the point of rewritten words in mm programs.
    #[arg(long, default_value_t = 4)]
    pub decimals_mm: usize,
    /// Digits after the point of rewritten words in inch programs.
    #[arg(long, default_value_t = 5)]
    pub decimals_inch: usize,
    /// Machine position at program start, "x,y,z" in mm (e.g. home; on a lathe the fixed Y).
    #[arg(long, value_name = "X,Y,Z")]
    pub start_position_mm: Option<String>,
    /// Sample spacing of the path check for models that are not grid maps, in mm.
    #[arg(long, default_value_t = 0.5)]
    pub check_step_mm: f64,
    /// Machine angles of the rotary axes at program start, "a,b,c" in degrees (only the axes of
    /// the model's chain are used, e.g. "0,0,90" for C at 90 on a WCAYFXZT). Without it an
    /// angle is unknown until the program commands it, and a feed move before that is refused.
    #[arg(long, value_name = "A,B,C")]
    pub start_rotary_deg: Option<String>,
    /// Largest turn of a rotary axis between samples of the path check of a move that turns
    /// one, in degrees (0.5° moves a point 500 mm from the axis by 4.4 mm along its arc; the
    /// check also samples every --check-step-mm of the tool tip's path).
    #[arg(long, default_value_t = 0.5)]
    pub check_step_deg: f64,
    /// Longest line the controller reads (LinuxCNC: 251 with either line ending); longer
    /// rewritten lines are refused.
    #[arg(long, default_value_t = 251)]
    pub max_line_chars: usize,
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

/// Units of a tool table's lengths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MachineUnitsArg {
    Mm,
    Inch,
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
    /// with --flatten-with, passed to rs274 (`-t`), which bakes lengths and cutter radii in.
    #[arg(long, value_name = "FILE.tbl")]
    pub tool_table: Option<PathBuf>,
    /// The machine's units (LinuxCNC's INI LINEAR_UNITS), in which tool tables and parameter
    /// files hold their lengths (not the program's G20/G21). Stand-alone rs274 reads both as
    /// inches, so with `mm` they are handed to it converted.
    #[arg(long, value_enum, default_value = "mm", value_name = "mm|inch")]
    pub machine_units: MachineUnitsArg,
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
    let parse3 = |s: &str, what: &str, unit: &str| -> Result<[f64; 3], CliError> {
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| CliError::usage(format!("{what} '{s}': expected {unit}")))?;
        if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
            let names = unit.split(' ').next().unwrap_or("");
            return Err(CliError::usage(format!(
                "{what} '{s}': expected three numbers {names}"
            )));
        }
        Ok([v[0], v[1], v[2]])
    };
    let rewrite = RewriteOptions {
        tolerance_um: args.tolerance_um,
        max_segment_mm: args.max_segment_mm,
        chord_tolerance_um: args.chord_tolerance_um,
        max_correction_um: args.max_correction_um,
        on_unsupported: match args.on_unsupported {
            OnUnsupportedArg::Refuse => OnUnsupported::Refuse,
            OnUnsupportedArg::PassThroughWithWarning => OnUnsupported::PassThroughWithWarning,
        },
        default_units: match args.default_units {
            UnitsArg::Mm => Units::Mm,
            UnitsArg::Inch => Units::Inch,
        },
        decimals_mm: args.decimals_mm,
        decimals_inch: args.decimals_inch,
        check_step_mm: args.check_step_mm,
        check_step_deg: args.check_step_deg,
        max_line_chars: args.max_line_chars,
        start_position_mm: args
            .start_position_mm
            .as_deref()
            .map(|s| parse3(s, "--start-position-mm", "x,y,z in mm"))
            .transpose()?,
        start_rotary_deg: args
            .start_rotary_deg
            .as_deref()
            .map(|s| parse3(s, "--start-rotary-deg", "a,b,c in degrees"))
            .transpose()?,
        ..RewriteOptions::default()
    };
    let f = args.flatten;
    let opts = Options {
        model: args.model,
        state: args.state,
        input: args.input,
        output: args.output,
        rewrite,
        offsets: args.offsets,
        tool_table: f.tool_table,
        machine_units: match f.machine_units {
            MachineUnitsArg::Mm => MachineUnits::Mm,
            MachineUnitsArg::Inch => MachineUnits::Inch,
        },
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
