//! `mtec compensate gcode`: rewrites an NC program so the machine reaches the programmed points.

use crate::cmd::flatten::{extra_inputs, flatten_input, FlattenArgs, Flattened};
use crate::cmd::model_loader::load_error_model;
use crate::error::CliError;
use mtec_comp::gcode::offsets::WORK_SYSTEMS;
use mtec_comp::gcode::{rewrite, GcodeError, OffsetsFile, OnUnsupported, RewriteOptions, Units};
use mtec_io::InputError;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

pub const LONG_ABOUT: &str = "\
Rewrites an NC program (RS274/NGC as LinuxCNC reads it, or common Fanuc style) so that every
commanded point is corrected for the machine's volumetric error: the command p that makes the
machine reach the target t solves p + e(p) = t. Feed moves are split where the correction
changes along them (by less than --tolerance-um per piece, no piece longer than
--max-segment-mm), arcs are turned into chords where the correction varies along them, rapids
are corrected at their end points.

Only the words that change are edited: comments, line numbers, unknown words, spacing and line
endings are kept. With a zero model the output is byte-identical to the input. A comment naming
the model is written just before the first corrected line.

Constructs that cannot be compensated safely (parameters or expressions in motion words,
O-word subroutines and loops, canned cycles, cutter compensation G41/G42, G10/G92, rotary axis
words) stop the run with file:line:column (--on-unsupported refuse), or are copied unchanged
with a warning (pass-through-with-warning).

The model (--model) is JSON: {\"format\": \"mtec.zero-model/1\"}, or a polynomial
{\"format\": \"mtec.poly-model/1\", \"terms\": [{\"powers\": [1,0,0], \"coef_um\": [0.012,0,0]}]}
giving [Ex, Ey, Ez] in um as a function of the machine position in mm.

Offsets (--offsets, TOML) map program to machine coordinates (machine = program + work offset
+ tool length along Z):
  format = \"mtec.gcode-offsets/1\"
  active = \"G54\"
  [work_offsets_mm]
  G54 = [250.0, 120.0, -300.0]
  [tool_lengths_mm]
  1 = 85.25

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
splines (G5.x), A/B/C/U/V/W motion, a rotated work system (G10 L2 R), and anything rs274 itself
refuses (its message is passed on). Note that stand-alone rs274 reads tool-table and parameter
file lengths as inches.

Examples:
  mtec compensate gcode --model model.json part.ngc -o part-comp.ngc --offsets offsets.toml
  mtec compensate gcode --model m.json --flatten-with rs274 --tool-table t.tbl in.ngc -o out.ngc";

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
    long_about = LONG_ABOUT
)]
pub struct Args {
    /// Error model (JSON): mtec.zero-model/1 or mtec.poly-model/1.
    #[arg(long, value_name = "MODEL.json")]
    pub model: PathBuf,
    /// The NC program to correct.
    #[arg(value_name = "IN.ngc")]
    pub input: PathBuf,
    /// Where to write the corrected program (never an input; written atomically).
    #[arg(short, long, value_name = "OUT.ngc")]
    pub output: PathBuf,
    /// Largest change of the correction along one output piece, in um.
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
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let model = load_error_model(&args.model)?;
    let mut options = RewriteOptions {
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
        ..RewriteOptions::default()
    };
    if let Some(s) = &args.start_position_mm {
        let v: Vec<f64> = s
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                CliError::usage(format!("--start-position-mm '{s}': expected x,y,z in mm"))
            })?;
        if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
            return Err(CliError::usage(format!(
                "--start-position-mm '{s}': expected three numbers x,y,z"
            )));
        }
        options.start_position_mm = Some([v[0], v[1], v[2]]);
    }
    if let Some(p) = &args.offsets {
        let file: OffsetsFile = mtec_io::read_toml(p)?;
        options.offsets = file.validate().map_err(|m| InputError::file(p, m))?;
    }
    options.validate().map_err(CliError::Usage)?;

    for inp in [args.input.as_path(), args.model.as_path()]
        .into_iter()
        .chain(args.offsets.as_deref())
        .chain(extra_inputs(&args.flatten))
    {
        if same_file(inp, &args.output) {
            return Err(CliError::usage(format!(
                "refusing to overwrite the input file {}",
                args.output.display()
            )));
        }
    }
    // with --flatten-with, the rewriter reads the flattened program; its errors name that
    let (reader, source): (Box<dyn BufRead>, PathBuf) = if args.flatten.flatten_with.is_some() {
        let Flattened {
            text,
            report,
            work_offsets_mm,
        } = flatten_input(&args.input, &args.flatten)?;
        // the model is evaluated at machine positions: without --offsets, take the work
        // offsets rs274 read from --var-file; with it, say when the two disagree
        if args.offsets.is_none() {
            options.offsets.work_mm = work_offsets_mm;
        } else if let Some(i) = (0..9).find(|&i| {
            (0..3).any(|a| (options.offsets.work_mm[i][a] - work_offsets_mm[i][a]).abs() > 1e-6)
        }) {
            eprintln!(
                "warning: {} in --offsets is {:?} mm but rs274 read {:?} mm (--var-file): the model is evaluated with --offsets",
                WORK_SYSTEMS[i], options.offsets.work_mm[i], work_offsets_mm[i]
            );
        }
        println!(
            "{}: flattened by rs274: {} canonical lines -> {} lines ({} straight moves, {} arcs{})",
            args.input.display(),
            report.canonical_lines,
            report.lines_written,
            report.straight_moves,
            report.arcs,
            if report.offsets_folded {
                "; offsets folded into the coordinates"
            } else {
                ""
            }
        );
        let mut name = args.input.clone().into_os_string();
        name.push(" [flattened by rs274]");
        (Box::new(std::io::Cursor::new(text)), PathBuf::from(name))
    } else {
        let input = std::fs::File::open(&args.input)
            .map_err(|e| InputError::file(&args.input, format!("cannot read: {e}")))?;
        (
            Box::new(BufReader::with_capacity(1 << 16, input)),
            args.input.clone(),
        )
    };

    let tmp = temp_path(&args.output);
    if let Some(parent) = tmp.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let result = (|| -> Result<_, CliError> {
        let file = std::fs::File::create(&tmp)?;
        let mut writer = BufWriter::with_capacity(1 << 16, file);
        let report =
            rewrite(reader, &mut writer, model.as_ref(), &options).map_err(|e| match e {
                GcodeError::At(d) => {
                    CliError::Input(InputError::at(&source, d.line, d.column, d.message))
                }
                GcodeError::Io(e) => {
                    CliError::Internal(anyhow::anyhow!("{}: {e}", args.input.display()))
                }
            })?;
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, &args.output)?;
        Ok(report)
    })();
    let report = match result {
        Ok(r) => r,
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
    };
    let stderr = std::io::stderr();
    let mut err = stderr.lock();
    for w in &report.warnings {
        let _ = writeln!(
            err,
            "warning: {}:{}:{}: {} (line copied unchanged)",
            source.display(),
            w.line,
            w.column,
            w.message
        );
    }
    if report.warnings_total > report.warnings.len() {
        let _ = writeln!(
            err,
            "warning: … and {} more",
            report.warnings_total - report.warnings.len()
        );
    }
    println!(
        "{}: {} lines read, {} written ({} added by splitting); {} moves corrected, {} arcs linearised, largest correction {:.2} um; {} warnings",
        args.output.display(),
        report.lines_read,
        report.lines_written,
        report.lines_added,
        report.moves_compensated,
        report.arcs_linearised,
        report.max_correction_um,
        report.warnings_total
    );
    if report.rapids_not_compensated > 0 || report.moves_end_point_only > 0 {
        println!(
            "  {} rapids before all axes were known copied uncorrected; {} feed moves from an unknown start corrected at their end point only",
            report.rapids_not_compensated, report.moves_end_point_only
        );
    }
    Ok(())
}

fn temp_path(out: &Path) -> PathBuf {
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    parent.join(format!(".{name}.mtec-tmp-{}", std::process::id()))
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
