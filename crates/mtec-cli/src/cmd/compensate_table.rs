//! `mtec compensate table`: controller compensation tables from an error model.

use crate::error::CliError;
use mtec_comp::map::{GridMap, MAP_FORMAT};
use mtec_comp::table::{self, axis_profile, Axis, TableError};
use mtec_io::{Destination, InputError, OutputGuard};
use std::path::{Path, PathBuf};

pub const HELP: &str = "\
Writes the compensation table a CNC controller loads, from an error model (a map from
`mtec map fit`, or any model file mtec reads). The compensation value is the negative of the
predicted error, converted to each format's own sign rule; every table is checked against its
format's documented limits before it is written.

Formats:
  linuxcnc        [JOINT_n] COMP_FILE, one `nominal forward reverse` triplet per line, no header,
                  <= 256 lines; --comp-type 1 (trims, default) or 0 (actual positions)
  sinumerik-cec   Siemens 840D sag / cross-axis table %_N_NC_CEC_INI ($AN_CEC...): the value of
                  --output-axis as a function of --axis; values added to the setpoint
  sinumerik-lec   Siemens 840D leadscrew error table %_N_AX_EEC_INI ($AA_ENC_COMP...); a positive
                  value moves the axis negative, so the written value is the error itself
  fanuc           FANUC pitch error tape: parameters 3620-3624 and incremental values N1nnnnP...
                  per interval, relative to the reference point (--reference-mm)
  heidenhain      HEIDENHAIN nonlinear axis error compensation: a .COM table (-o) with the axis
                  error, and its .CMA assignment table beside it (--cma-name)
  beckhoff        Beckhoff TwinCAT CNC volumetric compensation, ISG CSV: X Y Z EXX EYY EZZ (mm)
                  on the map's grid (or --x-range/--y-range/--z-range)

Size bound: a table whose correction exceeds --max-correction-um (default 500 um, the same rule
as `compensate gcode`) is refused with exit code 2, naming the axis, the table position and the
value: for 1-D tables each value |c|, for beckhoff the length of the vector (ex, ey, ez). A
value that is not a finite number is always refused.

Sampling: 1-D tables run along --axis over --range FROM:TO:STEP (default: the map's grid along
that axis), the other coordinates at --at X,Y,Z (default: the centre of the map's grid box, or
0,0,0 for other models). Models without a grid (BPNN, kinematic) need --range (and the
--x/y/z-range for beckhoff); a BPNN extrapolates without warning outside the box it was fitted
on, so keep the ranges inside it.

State: a machine error model (mtec.machine-error/1) changes with the machine's temperatures; a
table is one moment of it, the state after the last row of --state LOG.csv (time_min and the
model's state inputs, rows in time order), named in the table's provenance. Without --state such
a model is refused. Reload the table when the state changes.";

const EXAMPLES: &str = crate::help::examples!(
    "  # a volumetric error map from a laser-tracker grid
  $ mtec simulate volumetric-grid --out g
  $ mtec map fit --grid g/grid.csv -o g/map.json
  # LinuxCNC COMP_FILE of X on the map's grid, at the centre of the grid box
  $ mtec compensate table --model g/map.json --format linuxcnc --axis X \\
      -o x.comp
  # Siemens 840D leadscrew error table of Z from 0 to 300 mm in 10 mm steps
  $ mtec compensate table --model g/map.json --format sinumerik-lec --axis Z \\
      --range 0:300:10 -o z_lec.ini"
);

/// Target controller format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    Linuxcnc,
    SinumerikCec,
    SinumerikLec,
    Fanuc,
    Heidenhain,
    Beckhoff,
}

/// `mtec compensate table`.
#[derive(clap::Args)]
#[command(after_long_help = EXAMPLES)]
pub struct Args {
    /// Error model JSON: a map (mtec.map/1), a kinematic model (mtec.kinematic-model/1), a BPNN
    /// map (mtec.bpnn/1), a machine error model (mtec.machine-error/1, with --state), or a
    /// poly/zero model; `mtec compensate gcode --help` says which command writes each.
    #[arg(long)]
    model: PathBuf,
    /// State log for a model with a state (mtec.machine-error/1): time_min and the model's
    /// state inputs; the table is for the state after the last row. Required for such a model.
    #[arg(long, value_name = "LOG.csv")]
    state: Option<PathBuf>,
    /// Controller table format.
    #[arg(long, value_enum)]
    format: Format,
    /// Axis along which the table runs (input / base axis): X, Y or Z.
    #[arg(long, default_value = "X")]
    axis: String,
    /// Axis that is compensated (cross-axis tables: sinumerik-cec, heidenhain); default = --axis.
    #[arg(long)]
    output_axis: Option<String>,
    /// Table positions FROM:TO:STEP in mm along --axis.
    #[arg(long)]
    range: Option<String>,
    /// Position of the other axes X,Y,Z in mm.
    #[arg(long)]
    at: Option<String>,
    /// LinuxCNC COMP_FILE_TYPE: 1 (offsets) or 0 (actual positions).
    #[arg(long, default_value_t = 1)]
    comp_type: u8,
    /// Siemens CEC table index t.
    #[arg(long, default_value_t = 0)]
    table_index: usize,
    /// Siemens CEC _DIRECTION: 0 both, 1 positive only, -1 negative only.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true)]
    direction: i8,
    /// Largest number of points the controller is configured for (Siemens MD18342 / MD38000).
    #[arg(long)]
    max_points: Option<usize>,
    /// FANUC: machine position of the reference point (mm); must be a table point.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    reference_mm: f64,
    /// FANUC parameter 3620: compensation point number of the reference position.
    #[arg(long, default_value_t = 0)]
    reference_number: u32,
    /// FANUC parameter 3623: magnification.
    #[arg(long, default_value_t = 1)]
    magnification: u32,
    /// FANUC detection unit in um.
    #[arg(long, default_value_t = 1.0)]
    detection_unit_um: f64,
    /// FANUC largest |value| per compensation point.
    #[arg(long, default_value_t = 127)]
    max_increment: i64,
    /// FANUC axis number in the parameter tape (A1, A2, ...); default X=1, Y=2, Z=3.
    #[arg(long)]
    axis_number: Option<u8>,
    /// HEIDENHAIN assignment table name, written beside the .COM file.
    #[arg(long, default_value = "config.cma")]
    cma_name: String,
    /// Beckhoff grid along X: FROM:TO:STEP (default: the map's grid).
    #[arg(long)]
    x_range: Option<String>,
    /// Beckhoff grid along Y: FROM:TO:STEP.
    #[arg(long)]
    y_range: Option<String>,
    /// Beckhoff grid along Z: FROM:TO:STEP.
    #[arg(long)]
    z_range: Option<String>,
    /// Refuse the table if a correction exceeds this, in um (1-D tables: each value; beckhoff:
    /// the length of the correction vector). The same rule and default as `compensate gcode`.
    #[arg(long, default_value_t = table::DEFAULT_MAX_CORRECTION_UM)]
    max_correction_um: f64,
    /// Output file (default and `-`: stdout; required for heidenhain). A file is replaced
    /// atomically, a device or FIFO written in place, a symlink's target written.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<(), CliError> {
    // the CLI's loader: maps and kinematic models (mtec-comp) and the BPNN, poly and zero models
    let model = mtec_workflow::state::model_in_state(
        mtec_comp::load_error_model(&a.model)?,
        &a.model,
        a.state.as_deref(),
        &mut crate::observer::Stderr::default(),
    )?;
    let map = load_map_if_grid(&a.model)?;
    let axis = parse_axis("--axis", &a.axis)?;
    let output_axis = match &a.output_axis {
        Some(s) => parse_axis("--output-axis", s)?,
        None => axis,
    };
    if !(a.max_correction_um.is_finite() && a.max_correction_um > 0.0) {
        return Err(CliError::usage(format!(
            "--max-correction-um must be a positive number, not {}",
            a.max_correction_um
        )));
    }
    let provenance = model.describe();
    let mut guard = OutputGuard::new(&[&a.model]);
    if let Some(p) = &a.state {
        guard.add_input(p);
    }
    // where the table goes is settled before any work (an input, a directory: exit 2)
    let dest = match &a.out {
        Some(p) if a.format == Format::Heidenhain && p.as_os_str() == "-" => {
            return Err(CliError::usage(
                "heidenhain writes two files: give -o NAME.COM, not - (the .CMA goes beside it)",
            ))
        }
        Some(p) => guard.check(p)?,
        None => Destination::Stdout,
    };

    if a.format == Format::Beckhoff {
        let mut axes: [Vec<f64>; 3] = match &map {
            Some(m) => m.axes_mm().clone(),
            None => Default::default(),
        };
        for (k, r) in [&a.x_range, &a.y_range, &a.z_range].iter().enumerate() {
            if let Some(r) = r {
                let (from, to, step) = parse_range(r)?;
                axes[k] = grid_values(from, to, step)?;
            } else if axes[k].is_empty() {
                return Err(CliError::usage(
                    "beckhoff: the model is not a grid map; give --x-range, --y-range and --z-range",
                ));
            }
        }
        let text = table::beckhoff::write(model.as_ref(), &axes, &provenance, a.max_correction_um)
            .map_err(|e| table_error(&a.model, e))?;
        dest.write(text.as_bytes())?;
        return Ok(());
    }

    // 1-D tables
    let (from, to, step) = match &a.range {
        Some(r) => parse_range(r)?,
        None => {
            let m = map.as_ref().ok_or_else(|| {
                CliError::usage("the model is not a grid map: give --range FROM:TO:STEP")
            })?;
            let ax = &m.axes_mm()[axis.index()];
            if ax.len() < 2 || !m.is_uniform(axis.index()) {
                return Err(CliError::usage(format!(
                    "the map's {} values are not equally spaced: give --range FROM:TO:STEP",
                    axis.letter()
                )));
            }
            (ax[0], ax[ax.len() - 1], ax[1] - ax[0])
        }
    };
    let at = match &a.at {
        Some(s) => parse_triple(s)?,
        None => match &map {
            Some(m) => {
                let c = |k: usize| {
                    let ax = &m.axes_mm()[k];
                    0.5 * (ax[0] + ax[ax.len() - 1])
                };
                [c(0), c(1), c(2)]
            }
            None => [0.0; 3],
        },
    };
    let profile = axis_profile(model.as_ref(), axis, output_axis, from, to, step, at)
        .map_err(|e| table_error(&a.model, e))?
        .with_max_correction_um(a.max_correction_um);
    let text = match a.format {
        Format::Linuxcnc => table::linuxcnc::write(&profile, a.comp_type),
        Format::SinumerikCec => table::sinumerik::write_cec(
            &profile,
            &table::sinumerik::CecOptions {
                table_index: a.table_index,
                direction: a.direction,
                max_points: a.max_points,
                ..Default::default()
            },
        ),
        Format::SinumerikLec => table::sinumerik::write_lec(
            &profile,
            &table::sinumerik::LecOptions {
                max_points: a.max_points,
                ..Default::default()
            },
        ),
        Format::Fanuc => table::fanuc::write(
            &profile,
            &table::fanuc::FanucOptions {
                axis_number: a.axis_number.unwrap_or(axis.index() as u8 + 1),
                reference_mm: a.reference_mm,
                reference_number: a.reference_number,
                magnification: a.magnification,
                detection_unit_um: a.detection_unit_um,
                max_increment: a.max_increment,
                ..Default::default()
            },
        ),
        Format::Heidenhain => {
            let out = a.out.as_deref().ok_or_else(|| {
                CliError::usage(
                    "heidenhain writes two files: give -o NAME.COM (the .CMA goes beside it)",
                )
            })?;
            let com_name = out
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "TABLE.COM".into());
            let t = table::heidenhain::write(&profile, &com_name, &a.cma_name)
                .map_err(|e| table_error(&a.model, e))?;
            let cma_path = out.with_file_name(&a.cma_name);
            let cma_dest = guard.check(&cma_path)?;
            dest.write(t.com.as_bytes())?;
            cma_dest.write(t.cma.as_bytes())?;
            eprintln!(
                "heidenhain: {} and {} from {provenance}",
                out.display(),
                cma_path.display()
            );
            return Ok(());
        }
        Format::Beckhoff => unreachable!("handled above"),
    }
    .map_err(|e| table_error(&a.model, e))?;
    dest.write(text.as_bytes())?;
    if a.out.is_some() {
        use clap::ValueEnum;
        let name = a
            .format
            .to_possible_value()
            .map(|v| v.get_name().to_string())
            .unwrap_or_default();
        eprintln!("{name} table from {provenance}");
    }
    Ok(())
}

fn table_error(model: &Path, e: TableError) -> CliError {
    match e {
        TableError::Undefined { .. } | TableError::TooLarge { .. } => {
            InputError::file(model, e.to_string()).into()
        }
        other => CliError::usage(other.to_string()),
    }
}

/// The grid map itself when the model file is a map (for its grid as default sampling).
fn load_map_if_grid(path: &Path) -> Result<Option<GridMap>, InputError> {
    let text = mtec_io::read_text(path)?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
    if mtec_comp::load::model_format(path, &text, &value)? == MAP_FORMAT {
        Ok(Some(mtec_comp::load::load_map(path)?))
    } else {
        Ok(None)
    }
}

fn parse_axis(opt: &str, s: &str) -> Result<Axis, CliError> {
    Axis::parse(s).ok_or_else(|| CliError::usage(format!("{opt} `{s}`: expected X, Y or Z")))
}

fn parse_range(s: &str) -> Result<(f64, f64, f64), CliError> {
    let v: Vec<Option<f64>> = s.split(':').map(|p| p.trim().parse::<f64>().ok()).collect();
    match v.as_slice() {
        [Some(a), Some(b), Some(c)] if a.is_finite() && b.is_finite() && *c > 0.0 => {
            Ok((*a, *b, *c))
        }
        _ => Err(CliError::usage(format!(
            "range `{s}`: expected FROM:TO:STEP in mm with FROM < TO and STEP > 0, e.g. 0:500:25"
        ))),
    }
}

fn parse_triple(s: &str) -> Result<[f64; 3], CliError> {
    let v: Vec<Option<f64>> = s.split(',').map(|p| p.trim().parse::<f64>().ok()).collect();
    match v.as_slice() {
        [Some(x), Some(y), Some(z)] => Ok([*x, *y, *z]),
        _ => Err(CliError::usage(format!(
            "--at `{s}`: expected X,Y,Z in mm, e.g. 250,150,-100"
        ))),
    }
}

fn grid_values(from: f64, to: f64, step: f64) -> Result<Vec<f64>, CliError> {
    let n = ((to - from) / step).round();
    if to <= from || ((to - from) / step - n).abs() > 1e-6 {
        return Err(CliError::usage(format!(
            "range {from}:{to}:{step} is not a whole number of steps from FROM up to TO"
        )));
    }
    Ok((0..=n as usize).map(|i| from + step * i as f64).collect())
}
