//! `compensate table`: the compensation table a CNC controller loads, from an error model, or
//! (`--from-iso230-2`) the direction-dependent table of one axis from an ISO 230-2 run.

use super::selective::{self, Elements, Selective};
use crate::{Error, Observer, Result};
use mtec_comp::map::{GridMap, MAP_FORMAT};
use mtec_comp::table::bidirectional::BidirectionalProfile;
use mtec_comp::table::{self, axis_profile, Axis, TableError};
use mtec_io::{Destination, InputError, OutputGuard};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// A controller's table format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Format {
    /// LinuxCNC `[JOINT_n] COMP_FILE`: `nominal forward reverse` triplets.
    Linuxcnc,
    /// Siemens 840D sag / cross-axis table (`$AN_CEC...`).
    SinumerikCec,
    /// Siemens 840D leadscrew error table (`$AA_ENC_COMP...`).
    SinumerikLec,
    /// FANUC pitch error tape.
    Fanuc,
    /// HEIDENHAIN nonlinear axis error compensation: a .COM table and its .CMA assignment.
    Heidenhain,
    /// Beckhoff TwinCAT volumetric compensation (ISG CSV).
    Beckhoff,
}

impl Format {
    /// The name the command line gives it (`sinumerik-cec`, ...).
    /// Every format, in the order the command lists them.
    pub const ALL: [Format; 6] = [
        Format::Linuxcnc,
        Format::SinumerikCec,
        Format::SinumerikLec,
        Format::Fanuc,
        Format::Heidenhain,
        Format::Beckhoff,
    ];

    /// The format named `name` (`linuxcnc`, `sinumerik-cec`, ...).
    pub fn from_name(name: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == name)
    }

    pub fn name(self) -> &'static str {
        match self {
            Format::Linuxcnc => "linuxcnc",
            Format::SinumerikCec => "sinumerik-cec",
            Format::SinumerikLec => "sinumerik-lec",
            Format::Fanuc => "fanuc",
            Format::Heidenhain => "heidenhain",
            Format::Beckhoff => "beckhoff",
        }
    }
}

impl crate::Choice for Format {
    const ALL: &'static [Self] = &Format::ALL;

    fn name(self) -> &'static str {
        Format::name(self)
    }
}

/// Positions FROM:TO:STEP along an axis, in mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// First position (mm).
    pub from: f64,
    /// Last position (mm).
    pub to: f64,
    /// Distance between positions (mm, > 0).
    pub step: f64,
}

impl Range {
    /// Parses `FROM:TO:STEP` (finite ends, a positive step); a usage error otherwise.
    pub fn parse(s: &str) -> Result<Range> {
        let v: Vec<Option<f64>> = s.split(':').map(|p| p.trim().parse::<f64>().ok()).collect();
        match v.as_slice() {
            [Some(a), Some(b), Some(c)] if Range::new(*a, *b, *c).is_ok() => {
                Range::new(*a, *b, *c)
            }
            _ => Err(Error::usage(format!(
                "range `{s}`: expected FROM:TO:STEP in mm with FROM < TO and STEP > 0, e.g. 0:500:25"
            ))),
        }
    }

    /// The range `from`:`to`:`step` (finite ends, a positive step); a usage error otherwise.
    pub fn new(from: f64, to: f64, step: f64) -> Result<Range> {
        if from.is_finite() && to.is_finite() && step > 0.0 {
            Ok(Range { from, to, step })
        } else {
            Err(Error::usage(format!(
                "range {from}:{to}:{step}: expected FROM:TO:STEP in mm with FROM < TO and STEP > 0, e.g. 0:500:25"
            )))
        }
    }

    /// The positions FROM, FROM + STEP, ..., TO; refused unless TO is a whole number of steps
    /// above FROM.
    pub fn values(&self) -> Result<Vec<f64>> {
        let Range { from, to, step } = *self;
        let n = table::range_intervals(from, to, step).map_err(Error::usage)?;
        Ok((0..=n).map(|i| from + step * i as f64).collect())
    }
}

/// Parses an axis option (`X`, `Y`, `Z`, either case); `opt` names it in the usage error.
pub fn parse_axis(opt: &str, s: &str) -> Result<Axis> {
    Axis::parse(s).ok_or_else(|| Error::usage(format!("{opt} `{s}`: expected X, Y or Z")))
}

/// Parses `--at X,Y,Z` (mm).
pub fn parse_at(s: &str) -> Result<[f64; 3]> {
    let v: Vec<Option<f64>> = s.split(',').map(|p| p.trim().parse::<f64>().ok()).collect();
    match v.as_slice() {
        [Some(x), Some(y), Some(z)] => checked_at([*x, *y, *z]),
        _ => Err(Error::usage(format!(
            "--at `{s}`: expected X,Y,Z in mm, e.g. 250,150,-100"
        ))),
    }
}

/// `--at` (mm) when each coordinate is a plausible position; a usage error otherwise.
pub fn checked_at(at: [f64; 3]) -> Result<[f64; 3]> {
    for c in at {
        mtec_io::plausible::position_option("--at", c).map_err(Error::usage)?;
    }
    Ok(at)
}

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct Options {
    /// Any model file mtec reads (`mtec_comp::load_error_model`); not read when
    /// [`Self::from_iso230_2`] is given.
    pub model: PathBuf,
    /// An ISO 230-2 run (`target_mm,run,direction,deviation_um`) instead of a model: the table
    /// of `axis` at the run's targets, forward c↑ = −x̄↑ and reverse c↓ = −x̄↓ in each format's
    /// direction-dependent form.
    pub from_iso230_2: Option<PathBuf>,
    /// State log of a model with a state: the table is for the state after its last row.
    pub state: Option<PathBuf>,
    pub format: Format,
    /// The axis along which a 1-D table runs (input / base axis).
    pub axis: Axis,
    /// The compensated axis of cross-axis tables (sinumerik-cec, heidenhain); `None`: `axis`.
    pub output_axis: Option<Axis>,
    /// Table positions along `axis` (mm); `None`: the map's grid along it.
    pub range: Option<Range>,
    /// Position of the other axes (mm); `None`: the centre of the map's grid box, or 0,0,0.
    pub at: Option<[f64; 3]>,
    /// LinuxCNC COMP_FILE_TYPE: 1 (offsets) or 0 (actual positions).
    pub comp_type: u8,
    /// Siemens CEC table index t.
    pub table_index: usize,
    /// Siemens CEC _DIRECTION: 0 both, 1 positive only, -1 negative only.
    pub direction: i8,
    /// Largest number of points the controller is configured for (Siemens MD18342 / MD38000).
    pub max_points: Option<usize>,
    /// FANUC: machine position of the reference point (mm).
    pub reference_mm: f64,
    /// FANUC parameter 3620: compensation point number of the reference position.
    pub reference_number: u32,
    /// FANUC parameter 3623: magnification.
    pub magnification: u32,
    /// FANUC detection unit (um).
    pub detection_unit_um: f64,
    /// FANUC largest |value| per compensation point (detection units).
    pub max_increment: i64,
    /// FANUC axis number in the parameter tape; `None`: X=1, Y=2, Z=3.
    pub axis_number: Option<u8>,
    /// HEIDENHAIN assignment table name, written beside the .COM file.
    pub cma_name: String,
    /// Beckhoff grid along X, Y, Z (mm); `None`: the map's grid along that axis.
    pub grid: [Option<Range>; 3],
    /// Refuse the table if a correction exceeds this (um; beckhoff: the vector's length).
    pub max_correction_um: f64,
    /// The table file; `None` or `-`: stdout (heidenhain needs a file).
    pub out: Option<PathBuf>,
    /// The elements of a kinematic model the table compensates ([`selective`]): the table is
    /// sampled from a model of those elements only.
    pub elements: Elements,
}

impl Options {
    /// A `format` table of `model` along X written to `out`, every other option at the
    /// command's default.
    pub fn new(model: impl Into<PathBuf>, format: Format, out: Option<PathBuf>) -> Self {
        Options {
            model: model.into(),
            from_iso230_2: None,
            state: None,
            format,
            axis: Axis::X,
            output_axis: None,
            range: None,
            at: None,
            comp_type: 1,
            table_index: 0,
            direction: 0,
            max_points: None,
            reference_mm: 0.0,
            reference_number: 0,
            magnification: 1,
            detection_unit_um: 1.0,
            max_increment: 127,
            axis_number: None,
            cma_name: "config.cma".into(),
            grid: [None; 3],
            max_correction_um: table::DEFAULT_MAX_CORRECTION_UM,
            out,
            elements: Elements::All,
        }
    }

    /// Refuses an option that this format (from this source) does not read, given a value
    /// other than its default: a controller must never get a table the user believes has a
    /// magnification, a direction or a reference it does not have.
    pub fn refuse_unused(&self) -> Result<()> {
        use crate::unused::{refuse_unused, Given};
        use Format::*;
        let d = Options::new(&self.model, self.format, None);
        let (f, iso) = (self.format, self.from_iso230_2.is_some());
        let o = Given::new;
        let (fanuc, cec) = ("--format fanuc", "--format sinumerik-cec");
        let model_1d = "the tables of a model along one axis (not beckhoff's grid)";
        let options = [
            o(
                "--comp-type",
                self.comp_type != d.comp_type,
                f == Linuxcnc,
                "--format linuxcnc",
            ),
            o(
                "--table-index",
                self.table_index != d.table_index,
                f == SinumerikCec,
                cec,
            ),
            o(
                "--direction",
                self.direction != d.direction,
                f == SinumerikCec && !iso,
                "--format sinumerik-cec from a model (--from-iso230-2 writes both directions)",
            ),
            o(
                "--max-points",
                self.max_points.is_some(),
                matches!(f, SinumerikCec | SinumerikLec) || (f == Beckhoff && iso),
                "--format sinumerik-cec, sinumerik-lec and beckhoff --from-iso230-2",
            ),
            o(
                "--axis-number",
                self.axis_number.is_some(),
                f == Fanuc || (f == Beckhoff && iso),
                "--format fanuc and beckhoff --from-iso230-2",
            ),
            o(
                "--cma-name",
                self.cma_name != d.cma_name,
                f == Heidenhain,
                "--format heidenhain",
            ),
            o(
                "--x-range, --y-range, --z-range",
                self.grid.iter().any(Option::is_some),
                f == Beckhoff && !iso,
                "--format beckhoff from a model",
            ),
            o(
                "--output-axis",
                self.output_axis.is_some(),
                matches!(f, SinumerikCec | Heidenhain) && !iso,
                "--format sinumerik-cec and heidenhain from a model",
            ),
            o(
                "--range",
                self.range.is_some(),
                f != Beckhoff && !iso,
                model_1d,
            ),
            o("--at", self.at.is_some(), f != Beckhoff && !iso, model_1d),
            o("--state", self.state.is_some(), !iso, "tables of a model"),
        ];
        // FANUC's pitch-error parameters, read by its tape only
        let fanuc_options = [
            ("--reference-mm", self.reference_mm != d.reference_mm),
            (
                "--reference-number",
                self.reference_number != d.reference_number,
            ),
            ("--magnification", self.magnification != d.magnification),
            (
                "--detection-unit-um",
                self.detection_unit_um != d.detection_unit_um,
            ),
            ("--max-increment", self.max_increment != d.max_increment),
        ];
        let options: Vec<Given> = fanuc_options
            .into_iter()
            .map(|(name, given)| o(name, given, f == Fanuc, fanuc))
            .chain(options)
            .collect();
        let source = if iso { " --from-iso230-2" } else { "" };
        refuse_unused(&format!("--format {}{source}", f.name()), &options)
    }
}

/// What [`run`] did.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    pub format: Format,
    /// The model as the table's provenance names it (with its state, if any).
    pub provenance: String,
    /// Table points (1-D) or grid nodes (beckhoff).
    pub points: usize,
    /// The table file (`None`: stdout).
    pub out: Option<PathBuf>,
    /// HEIDENHAIN's assignment table, written beside the .COM file.
    pub cma: Option<PathBuf>,
    /// Every warning, as sent to the observer.
    pub warnings: Vec<String>,
    /// What the table assumes or leaves to the control (`--from-iso230-2`), printed with it.
    pub notes: Vec<String>,
    /// `--from-iso230-2`: the largest reversal |B_i| = |x̄_i↑ − x̄_i↓| of the run (µm), carried
    /// by the table's two directions.
    pub reversal_max_um: Option<f64>,
    /// What a selective compensation (`--elements key|LIST`) compensates and costs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selective: Option<Selective>,
}

impl fmt::Display for Outcome {
    /// The line the command prints on stderr: which table from which model (nothing for a
    /// table on stdout, or a beckhoff table).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for n in &self.notes {
            writeln!(f, "note: {n}")?;
        }
        match (&self.out, &self.cma) {
            (Some(out), Some(cma)) => writeln!(
                f,
                "heidenhain: {} and {} from {}",
                out.display(),
                cma.display(),
                self.provenance
            ),
            (Some(_), None) if self.format != Format::Beckhoff => {
                writeln!(f, "{} table from {}", self.format.name(), self.provenance)
            }
            _ => Ok(()),
        }?;
        match &self.selective {
            Some(s) => write!(f, "{s}"),
            None => Ok(()),
        }
    }
}

/// An observer that keeps the warnings it passes on.
struct Keep<'a> {
    obs: &'a mut dyn Observer,
    warnings: Vec<String>,
}

impl Observer for Keep<'_> {
    fn progress(&mut self, what: &str) {
        self.obs.progress(what);
    }
    fn warning(&mut self, what: &str) {
        self.warnings.push(what.to_string());
        self.obs.warning(what);
    }
    fn stop_requested(&self) -> bool {
        self.obs.stop_requested()
    }
}

/// Samples the model and writes the table. The output is checked (not an input, not a
/// directory) before any table is computed; every value is checked against the format's limits
/// and `max_correction_um` before anything is written.
pub fn run(opts: &Options, obs: &mut dyn Observer) -> Result<Outcome> {
    opts.refuse_unused()?;
    if let Some(run) = &opts.from_iso230_2 {
        if opts.elements != Elements::All {
            return Err(Error::usage(
                "--elements selects elements of a kinematic model; an ISO 230-2 run has none",
            ));
        }
        // what only a model's table reads (the command line refuses these before; a library
        // caller must not get a table the user believes has them)
        let model_only = [
            ("--state", opts.state.is_some()),
            ("--output-axis", opts.output_axis.is_some()),
            ("--range", opts.range.is_some()),
            ("--at", opts.at.is_some()),
            (
                "--x-range/--y-range/--z-range",
                opts.grid.iter().any(Option::is_some),
            ),
        ];
        if let Some((name, _)) = model_only.iter().find(|(_, given)| *given) {
            return Err(Error::usage(format!(
                "{name} is for a table from a model; --from-iso230-2 takes the run's targets"
            )));
        }
        return run_iso230_2(opts, run, obs);
    }
    let mut guard = OutputGuard::new(&[&opts.model]);
    if let Some(p) = &opts.state {
        guard.add_input(p);
    }
    // where the table goes is settled before any work (an input, a directory: exit 2)
    let dest = check_outputs(opts, &guard)?;
    let mut keep = Keep {
        obs,
        warnings: Vec::new(),
    };
    // all elements: the file loaded as it is; key or a list: a model of those only
    let (loaded, selective) = selective::load(&opts.model, &opts.elements)?;
    let model =
        crate::state::model_in_state(loaded, &opts.model, opts.state.as_deref(), &mut keep)?;
    let warnings = keep.warnings;
    let map = load_map_if_grid(&opts.model)?;
    let axis = opts.axis;
    let output_axis = opts.output_axis.unwrap_or(axis);
    table::check_max_correction(opts.max_correction_um).map_err(Error::usage)?;
    let mut provenance = model.describe();
    if let Some(s) = &selective {
        provenance += &format!(
            ", only the elements {} ({})",
            s.elements.join(" "),
            s.selection
        );
    }
    let done = |points: usize, cma: Option<PathBuf>| Outcome {
        format: opts.format,
        provenance: provenance.clone(),
        points,
        out: opts.out.clone(),
        cma,
        warnings: warnings.clone(),
        notes: Vec::new(),
        reversal_max_um: None,
        selective: selective.clone(),
    };

    if opts.format == Format::Beckhoff {
        let mut axes: [Vec<f64>; 3] = match &map {
            Some(m) => m.axes_mm().clone(),
            None => Default::default(),
        };
        for (k, r) in opts.grid.iter().enumerate() {
            if let Some(r) = r {
                axes[k] = r.values()?;
            } else if axes[k].is_empty() {
                return Err(Error::usage(
                    "beckhoff: the model is not a grid map; give --x-range, --y-range and --z-range",
                ));
            }
        }
        let points: usize = axes.iter().map(Vec::len).product();
        if points > table::MAX_TABLE_POINTS {
            return Err(Error::usage(format!(
                "beckhoff: {} × {} × {} = {points} grid points, more than {}: choose coarser --x-range, --y-range, --z-range steps",
                axes[0].len(),
                axes[1].len(),
                axes[2].len(),
                table::MAX_TABLE_POINTS
            )));
        }
        let text =
            table::beckhoff::write(model.as_ref(), &axes, &provenance, opts.max_correction_um)
                .map_err(|e| table_error(&opts.model, e))?;
        dest.write(text.as_bytes())?;
        return Ok(done(axes.iter().map(Vec::len).product(), None));
    }

    // 1-D tables
    let Range { from, to, step } = match opts.range {
        Some(r) => r,
        None => {
            let m = map.as_ref().ok_or_else(|| {
                Error::usage("the model is not a grid map: give --range FROM:TO:STEP")
            })?;
            let ax = &m.axes_mm()[axis.index()];
            if ax.len() < 2 || !m.is_uniform(axis.index()) {
                return Err(Error::usage(format!(
                    "the map's {} values are not equally spaced: give --range FROM:TO:STEP",
                    axis.letter()
                )));
            }
            Range {
                from: ax[0],
                to: ax[ax.len() - 1],
                step: ax[1] - ax[0],
            }
        }
    };
    let at = match (opts.at, &map) {
        (Some(at), _) => at,
        // the centre of the map's grid box
        (None, Some(m)) => {
            let c = |k: usize| {
                let ax = &m.axes_mm()[k];
                0.5 * (ax[0] + ax[ax.len() - 1])
            };
            [c(0), c(1), c(2)]
        }
        (None, None) => [0.0; 3],
    };
    let profile = axis_profile(model.as_ref(), axis, output_axis, from, to, step, at)
        .map_err(|e| table_error(&opts.model, e))?
        .with_max_correction_um(opts.max_correction_um);
    let points = profile.comp_um.len();
    let text = match opts.format {
        Format::Linuxcnc => table::linuxcnc::write(&profile, opts.comp_type),
        Format::SinumerikCec => table::sinumerik::write_cec(
            &profile,
            &table::sinumerik::CecOptions {
                table_index: opts.table_index,
                direction: opts.direction,
                max_points: opts.max_points,
                ..Default::default()
            },
        ),
        Format::SinumerikLec => table::sinumerik::write_lec(
            &profile,
            &table::sinumerik::LecOptions {
                max_points: opts.max_points,
                ..Default::default()
            },
        ),
        Format::Fanuc => table::fanuc::write(
            &profile,
            &fanuc_options(opts, opts.axis_number.unwrap_or(axis.index() as u8 + 1)),
        ),
        Format::Heidenhain => {
            let (out, com_name) = heidenhain_com(opts)?;
            let t = table::heidenhain::write(&profile, &com_name, &opts.cma_name)
                .map_err(|e| table_error(&opts.model, e))?;
            let cma_path = out.with_file_name(&opts.cma_name);
            let cma_dest = guard.check(&cma_path)?;
            dest.write(t.com.as_bytes())?;
            cma_dest.write(t.cma.as_bytes())?;
            return Ok(done(points, Some(cma_path)));
        }
        Format::Beckhoff => unreachable!("handled above"),
    }
    .map_err(|e| table_error(&opts.model, e))?;
    dest.write(text.as_bytes())?;
    Ok(done(points, None))
}

/// A value the model cannot give or a correction too large is the model file's fault; a table
/// the options make impossible is a usage error.
fn table_error(model: &Path, e: TableError) -> Error {
    match e {
        TableError::Undefined { .. } | TableError::TooLarge { .. } => {
            InputError::file(model, e.to_string()).into()
        }
        other => Error::usage(other.to_string()),
    }
}

/// The grid map itself when the model file is a map (for its grid as default sampling).
fn load_map_if_grid(path: &Path) -> std::result::Result<Option<GridMap>, InputError> {
    let text = mtec_io::read_text(path)?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
    if mtec_comp::load::model_format(path, &text, &value)? == MAP_FORMAT {
        Ok(Some(mtec_comp::load::load_map(path)?))
    } else {
        Ok(None)
    }
}

/// `--from-iso230-2`: the direction-dependent table of `opts.axis` from the run's mean
/// unidirectional deviations (ISO 230-2:2014 3.3.1), c↑ = −x̄↑ and c↓ = −x̄↓ at each target.
fn run_iso230_2(opts: &Options, run: &Path, obs: &mut dyn Observer) -> Result<Outcome> {
    table::check_max_correction(opts.max_correction_um).map_err(Error::usage)?;
    let guard = OutputGuard::new(&[run]);
    let dest = check_outputs(opts, &guard)?;
    let table_in = mtec_io::Table::read(run)?;
    let data = mtec_measure::PositioningData::from_table(&table_in)?;
    let mut warnings = Vec::new();
    for w in &data.warnings {
        obs.warning(w);
        warnings.push(w.clone());
    }
    let iso = mtec_measure::evaluate_iso230_2(&data);
    // the first line of the run that names each target, for messages
    let targets_col = table_in.f64_column("target_mm")?;
    let line_of = |p: f64| {
        table_in
            .rows
            .iter()
            .zip(&targets_col)
            .find(|(_, &t)| (t - p).abs() < 1e-6)
            .map(|(row, _)| row.line)
    };
    let up: Vec<f64> = iso.targets.iter().map(|t| t.mean_up_um).collect();
    let down: Vec<f64> = iso.targets.iter().map(|t| t.mean_down_um).collect();
    let fail = |e: TableError| run_table_error(run, &data.targets_mm, &line_of, e);
    let profile = BidirectionalProfile::from_mean_deviations(
        opts.axis,
        data.targets_mm.clone(),
        &up,
        &down,
        opts.max_correction_um,
    )
    .map_err(fail)?;
    let reversal_max = profile
        .reversal_um()
        .iter()
        .fold(0.0f64, |m, b| m.max(b.abs()));
    let provenance = format!(
        "ISO 230-2 run {} ({} targets, {} runs +, {} runs -)",
        run.display(),
        profile.len(),
        iso.runs_up,
        iso.runs_down
    );
    let mut notes = Vec::new();
    let axis_number = opts.axis_number.unwrap_or(opts.axis.index() as u8 + 1);
    let mut cma = None;
    let text = match opts.format {
        Format::Linuxcnc => table::linuxcnc::write_bidirectional(&profile, opts.comp_type),
        Format::SinumerikCec => {
            notes.push(format!(
                "tables {} (_DIRECTION 1, travel in +) and {} (_DIRECTION -1, travel in -); MD18342 MM_CEC_MAX_POINTS must allow {} points and MD32710 CEC_ENABLE be set",
                opts.table_index,
                opts.table_index + 1,
                profile.len()
            ));
            table::sinumerik::write_cec_bidirectional(
                &profile,
                &table::sinumerik::CecOptions {
                    table_index: opts.table_index,
                    max_points: opts.max_points,
                    ..Default::default()
                },
            )
        }
        Format::SinumerikLec => table::sinumerik::write_lec_bidirectional(
            &profile,
            &table::sinumerik::LecOptions {
                max_points: opts.max_points,
                ..Default::default()
            },
        ),
        Format::Fanuc => {
            notes.push(
                "set parameter 3605#0 = 1 (bidirectional pitch error compensation); the tape assumes reference return in the + direction (1006#5 = 0)".into(),
            );
            table::fanuc::write_bidirectional(
                &profile,
                &fanuc_options(opts, axis_number),
            )
        }
        Format::Heidenhain => {
            let (out, com_name) = heidenhain_com(opts)?;
            notes.push(
                "BACKLASH column = the error measured in the negative direction (MANUALplus 620 Technical Manual p. 716); check one point on the machine".into(),
            );
            let t = table::heidenhain::write_bidirectional(&profile, &com_name, &opts.cma_name)
                .map_err(fail)?;
            let cma_path = out.with_file_name(&opts.cma_name);
            let cma_dest = guard.check(&cma_path)?;
            dest.write(t.com.as_bytes())?;
            cma_dest.write(t.cma.as_bytes())?;
            cma = Some(cma_path);
            Ok(String::new())
        }
        Format::Beckhoff => {
            notes.push(
                "TwinCAT CNC leadscrew error compensation list (kw.ssfk, bilateral): activate with P-AXIS-00175 lr_param.ssfk = 1".into(),
            );
            table::beckhoff::ssfk::write(
                &profile,
                axis_number,
                opts.max_points
                    .unwrap_or(table::beckhoff::ssfk::DEFAULT_MAX_POINTS),
            )
        }
    }
    .map_err(fail)?;
    if cma.is_none() {
        dest.write(text.as_bytes())?;
    }
    Ok(Outcome {
        format: opts.format,
        provenance,
        points: profile.len(),
        out: opts.out.clone(),
        cma,
        warnings,
        notes,
        reversal_max_um: Some(reversal_max),
        selective: None,
    })
}

/// A table the run cannot give is the run file's fault (exit 2): named with the line of the
/// target the message is about (a value too large, or the first target the message names).
fn run_table_error(
    run: &Path,
    targets_mm: &[f64],
    line_of: &dyn Fn(f64) -> Option<usize>,
    e: TableError,
) -> Error {
    let message = e.to_string();
    let target = match &e {
        TableError::TooLarge {
            table_position: Some((_, p)),
            ..
        } => Some(*p),
        _ => targets_mm
            .iter()
            .filter_map(|&p| message.find(&format!(" {p} mm")).map(|i| (i, p)))
            .min_by_key(|(i, _)| *i)
            .map(|(_, p)| p),
    };
    match target.and_then(line_of) {
        Some(line) => InputError::line(run, line, message).into(),
        None => InputError::file(run, message).into(),
    }
}

/// The FANUC writer's options from the job's (the same for a model and an ISO 230-2 run).
fn fanuc_options(opts: &Options, axis_number: u8) -> table::fanuc::FanucOptions {
    table::fanuc::FanucOptions {
        axis_number,
        reference_mm: opts.reference_mm,
        reference_number: opts.reference_number,
        magnification: opts.magnification,
        detection_unit_um: opts.detection_unit_um,
        max_increment: opts.max_increment,
        ..Default::default()
    }
}

/// Where the table goes, settled before any work (an input, a directory, a folder that takes
/// no file: exit 2); heidenhain's .CMA beside the .COM is checked here too.
fn check_outputs(opts: &Options, guard: &OutputGuard) -> Result<Destination> {
    match &opts.out {
        Some(p) if opts.format == Format::Heidenhain && p.as_os_str() == "-" => Err(Error::usage(
            "heidenhain writes two files: give -o NAME.COM, not - (the .CMA goes beside it)",
        )),
        Some(p) => {
            let dest = guard.check(p)?;
            if opts.format == Format::Heidenhain {
                if p.file_name() == Some(std::ffi::OsStr::new(&opts.cma_name)) {
                    return Err(Error::usage(format!(
                        "-o {} and --cma-name {} name one file: the assignment table would replace the table",
                        p.display(),
                        opts.cma_name
                    )));
                }
                guard.check(&p.with_file_name(&opts.cma_name))?;
            }
            Ok(dest)
        }
        None => Ok(Destination::Stdout),
    }
}

/// HEIDENHAIN writes two files: the `-o NAME.COM` path and the name the `.COM` is known by.
fn heidenhain_com(opts: &Options) -> crate::Result<(&std::path::Path, String)> {
    let out = opts.out.as_deref().ok_or_else(|| {
        Error::usage("heidenhain writes two files: give -o NAME.COM (the .CMA goes beside it)")
    })?;
    let com_name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "TABLE.COM".into());
    Ok((out, com_name))
}
