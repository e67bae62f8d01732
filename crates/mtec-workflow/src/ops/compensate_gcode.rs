//! `compensate gcode`: rewrites an NC program so that the machine reaches the programmed points.

use super::selective::{Elements, Selective};
use crate::rs274::{flatten_input, FlattenInputs, Flattened, Rs274};
use crate::{Error, Observer, Result};
use mtec_comp::gcode::flatten::FlattenReport;
use mtec_comp::gcode::offsets::WORK_SYSTEMS;
use mtec_comp::gcode::tooltable::{load_tool_table, MachineUnits};
use mtec_comp::gcode::RewriteReport;
use mtec_comp::gcode::{
    rewrite, BlockDelete, GcodeError, OffsetsFile, ProblemKind, RewriteOptions,
};
use mtec_io::{InputError, OutputGuard};
use serde::Serialize;
use std::fmt;
use std::io::{BufRead, BufReader, BufWriter};
use std::path::{Path, PathBuf};

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct Options {
    /// Any model file mtec reads (`mtec_comp::load_error_model`).
    pub model: PathBuf,
    /// State log of a model with a state (temperatures...): the state after its last row is
    /// compensated for.
    pub state: Option<PathBuf>,
    /// The NC program.
    pub input: PathBuf,
    /// The compensated program (`-` for stdout).
    pub output: PathBuf,
    /// Tolerances, limits, units, start position: everything of the rewriter. Its `offsets`
    /// and `block_delete` are replaced from `offsets`, `tool_table` and `block_delete` below.
    pub rewrite: RewriteOptions,
    /// Work, tool and G92 offsets of the set-up (TOML, docs/formats.md).
    pub offsets: Option<PathBuf>,
    /// LinuxCNC tool table: G43 lengths (with `flatten`: passed to rs274).
    pub tool_table: Option<PathBuf>,
    /// Units of the tool table and parameter file (LinuxCNC's LINEAR_UNITS).
    pub machine_units: MachineUnits,
    /// The block delete switch: `Some(true)` skips `/` blocks, `Some(false)` runs them, `None`
    /// refuses a `/` block that moves or sets a mode.
    pub block_delete: Option<bool>,
    /// Run the program through LinuxCNC's interpreter first.
    pub flatten: Option<Rs274>,
    /// The elements of a kinematic model to compensate ([`super::selective`]).
    pub elements: Elements,
}

impl Options {
    /// `input` compensated with `model` into `output`, every other option at its default.
    pub fn new(
        model: impl Into<PathBuf>,
        input: impl Into<PathBuf>,
        output: impl Into<PathBuf>,
    ) -> Self {
        Options {
            model: model.into(),
            state: None,
            input: input.into(),
            output: output.into(),
            rewrite: RewriteOptions::default(),
            offsets: None,
            tool_table: None,
            machine_units: MachineUnits::Mm,
            block_delete: None,
            flatten: None,
            elements: Elements::All,
        }
    }
}

/// What [`run`] did.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// The program the line numbers refer to (the input, or its flattened text).
    pub source: PathBuf,
    pub output: PathBuf,
    /// What rs274 flattening did, when asked for.
    pub flattened: Option<FlattenReport>,
    pub report: RewriteReport,
    /// Every warning, as sent to the observer.
    pub warnings: Vec<String>,
    /// Notes on how the program was read (e.g. no work offsets given).
    pub notes: Vec<String>,
    /// What a selective compensation (`--elements key|LIST`) compensates and costs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selective: Option<Selective>,
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        writeln!(
            f,
            "{}: {} lines read, {} written ({} added by splitting); {} moves corrected, {} arcs linearised, largest correction {:.2} um; {} warnings",
            self.output.display(),
            r.lines_read,
            r.lines_written,
            r.lines_added,
            r.moves_compensated,
            r.arcs_linearised,
            r.max_correction_um,
            r.warnings_total
        )?;
        if r.rapids_not_compensated > 0 || r.moves_end_point_only > 0 {
            writeln!(
                f,
                "  {} rapids before all axes were known copied uncorrected; {} feed moves from an unknown or uncorrected start corrected at their end point only",
                r.rapids_not_compensated, r.moves_end_point_only
            )?;
        }
        if let Some(s) = &self.selective {
            write!(f, "{s}")?;
        }
        Ok(())
    }
}

/// Rewrites the program. Every output check (an input, a directory) comes before any work; an
/// unfinished output leaves the target untouched.
pub fn run(opts: &Options, obs: &mut dyn Observer) -> Result<Outcome> {
    // the one output routine of mtec-io: a file atomically, a device, FIFO or `-` straight
    // through, a link's target; an input, a directory or a block device refused before any work
    let mut guard = OutputGuard::new(&[&opts.input, &opts.model]);
    for p in extra_inputs(opts) {
        guard.add_input(p);
    }
    let dest = guard.check(&opts.output)?;
    let mut warnings = Vec::new();
    let mut warn = |obs: &mut dyn Observer, w: String| {
        obs.warning(&w);
        warnings.push(w);
    };
    let (model, selective) = super::selective::load(&opts.model, &opts.elements)?;
    let model = crate::state::model_in_state(model, &opts.model, opts.state.as_deref(), obs)?;
    let mut options = opts.rewrite.clone();
    if let Some(p) = &opts.offsets {
        let file: OffsetsFile = mtec_io::read_toml(p)?;
        options.offsets = file.validate().map_err(|m| InputError::file(p, m))?;
    }
    if let Some(b) = opts.block_delete {
        options.block_delete = if b { BlockDelete::On } else { BlockDelete::Off };
    }
    if let (Some(t), None) = (&opts.tool_table, &opts.flatten) {
        // G43 lengths from the controller's own tool table (rs274 reads it itself when flattening)
        let table = load_tool_table(t, opts.machine_units).map_err(Error::Usage)?;
        let (offsets, notes) = options
            .offsets
            .clone()
            .with_tool_table(&table)
            .map_err(|m| InputError::file(t, m))?;
        for n in notes {
            warn(obs, format!("{}: {n}", t.display()));
        }
        options.offsets = offsets;
    }
    options.validate().map_err(Error::Usage)?;
    options.check_for(model.as_ref()).map_err(Error::Usage)?;

    // with flattening, the rewriter reads the flattened program; its errors name that
    let mut flattened = None;
    let (reader, source): (Box<dyn BufRead>, PathBuf) = if let Some(rs274) = &opts.flatten {
        let Flattened {
            text,
            report,
            work_offsets_mm,
            start_known,
        } = flatten_input(
            &opts.input,
            &FlattenInputs {
                rs274,
                tool_table: opts.tool_table.as_deref(),
                tool_lengths_mm: &options.offsets.tool_length_mm,
                start_offsets: opts.offsets.is_some().then_some(&options.offsets),
                machine_units: opts.machine_units,
                block_delete: opts.block_delete,
            },
        )?;
        // the model is evaluated at machine positions: without offsets, take the work offsets
        // rs274 read from the var file (without one, G54 = 0 as without flattening); with
        // them, say when the two disagree
        if opts.offsets.is_none() && start_known {
            options.offsets.work_mm = work_offsets_mm;
            options.offsets.known = [true; 9];
        } else if let Some(i) = (0..9).find(|&i| {
            // (rs274 read --offsets itself unless a --var-file was given)
            (0..3).any(|a| (options.offsets.work_mm[i][a] - work_offsets_mm[i][a]).abs() > 1e-6)
        }) {
            warn(
                obs,
                format!(
                    "{} in --offsets is {:?} mm but rs274 read {:?} mm (--var-file): the model is evaluated with --offsets",
                    WORK_SYSTEMS[i], options.offsets.work_mm[i], work_offsets_mm[i]
                ),
            );
        }
        obs.progress(&format!(
            "{}: flattened by rs274: {} canonical lines -> {} lines ({} straight moves, {} arcs{})",
            opts.input.display(),
            report.canonical_lines,
            report.lines_written,
            report.straight_moves,
            report.arcs,
            if report.offsets_folded {
                "; offsets folded into the coordinates"
            } else {
                ""
            }
        ));
        flattened = Some(report);
        let mut name = opts.input.clone().into_os_string();
        name.push(" [flattened by rs274]");
        (Box::new(std::io::Cursor::new(text)), PathBuf::from(name))
    } else {
        let input = std::fs::File::open(&opts.input)
            .map_err(|e| InputError::file(&opts.input, format!("cannot read: {e}")))?;
        (
            Box::new(BufReader::with_capacity(1 << 16, input)),
            opts.input.clone(),
        )
    };

    // dropped on error, an unfinished output leaves the target untouched
    let mut writer = BufWriter::with_capacity(1 << 16, dest.open()?);
    let report = rewrite(reader, &mut writer, model.as_ref(), &options).map_err(|e| match e {
        GcodeError::At(d) => Error::Input(InputError::at(&source, d.line, d.column, d.message)),
        GcodeError::Io(e) => Error::Internal(anyhow::anyhow!("{}: {e}", opts.input.display())),
    })?;
    writer.into_inner().map_err(|e| e.into_error())?.commit()?;
    for w in &report.warnings {
        let copied = if w.kind == ProblemKind::Controller {
            ""
        } else {
            " (line copied unchanged)"
        };
        warn(
            obs,
            format!(
                "{}:{}:{}: {}{copied}",
                source.display(),
                w.line,
                w.column,
                w.message
            ),
        );
    }
    if report.warnings_total > report.warnings.len() {
        warn(
            obs,
            format!(
                "… and {} more",
                report.warnings_total - report.warnings.len()
            ),
        );
    }
    if let Some(o) = &report.first_outside_model {
        let d = o.domain_mm;
        warn(
            obs,
            format!(
                "{}:{}:{}: {} corrected point(s) lie outside the model's box X {}..{} Y {}..{} Z {}..{} mm \
                 (first: X {:.3} Y {:.3} Z {:.3} mm, machine frame); there a map is clamped or extrapolated \
                 and a fit is beyond its data: measure over the program's travel, or check the work offsets",
                source.display(),
                o.line,
                o.column,
                report.points_outside_model,
                d[0][0],
                d[0][1],
                d[1][0],
                d[1][1],
                d[2][0],
                d[2][1],
                o.point_mm[0],
                o.point_mm[1],
                o.point_mm[2]
            ),
        );
    }
    let mut notes = Vec::new();
    let var_file = opts.flatten.as_ref().is_some_and(|f| f.var_file.is_some());
    if opts.offsets.is_none() && !var_file && report.moves_compensated > 0 {
        notes.push(
            "no --offsets: program coordinates were taken as machine coordinates (G54 = 0); \
             if the part is set up with work offsets, give them with --offsets (see --help)"
                .to_string(),
        );
    }
    Ok(Outcome {
        source,
        output: opts.output.clone(),
        flattened,
        report,
        warnings,
        notes,
        selective,
    })
}

/// The machine position at program start from `x,y,z` in mm (`--start-position-mm`).
pub fn parse_start_position(s: &str) -> Result<[f64; 3]> {
    parse3(s, "--start-position-mm", "x,y,z in mm")
}

/// The rotary axes' angles at program start from `a,b,c` in degrees (`--start-rotary-deg`).
pub fn parse_start_rotary(s: &str) -> Result<[f64; 3]> {
    parse3(s, "--start-rotary-deg", "a,b,c in degrees")
}

/// Three finite comma-separated numbers; a usage error names `what` and the expected `unit`.
fn parse3(s: &str, what: &str, unit: &str) -> Result<[f64; 3]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::usage(format!("{what} '{s}': expected {unit}")))?;
    if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
        let names = unit.split(' ').next().unwrap_or("");
        return Err(Error::usage(format!(
            "{what} '{s}': expected three numbers {names}"
        )));
    }
    Ok([v[0], v[1], v[2]])
}

/// The files a run reads besides the program and the model (for callers that track inputs).
pub fn extra_inputs(opts: &Options) -> Vec<&Path> {
    [&opts.state, &opts.offsets, &opts.tool_table]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .chain(opts.flatten.iter().filter_map(|f| f.var_file.as_deref()))
        .collect()
}
