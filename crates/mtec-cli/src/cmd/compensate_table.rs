//! `mtec compensate table`: controller compensation tables from an error model.

use crate::{choice::choice, error::CliError, help::examples};
use mtec_comp::table;
use mtec_workflow::ops::compensate_table::{self as op, parse_at, parse_axis, Options, Range};
use mtec_workflow::ops::selective::Elements;
use std::path::PathBuf;

/// `mtec compensate table`.
#[derive(clap::Args)]
#[command(after_long_help = examples!("compensate_table.examples"))]
pub struct Args {
    /// Error model JSON: map, kinematic, BPNN, machine error (with --state), poly or zero model
    /// (`mtec compensate gcode --help` says which command writes each).
    #[arg(long, required_unless_present = "from_iso230_2")]
    model: Option<PathBuf>,
    /// ISO 230-2 run CSV (target_mm,run,direction,deviation_um) instead of --model: a
    /// direction-dependent table of --axis at the run's targets.
    #[arg(long, value_name = "RUN.csv", conflicts_with_all = ["model", "state", "elements", "output_axis", "range", "at", "x_range", "y_range", "z_range"])]
    from_iso230_2: Option<PathBuf>,
    /// State log for a model with a state (mtec.machine-error/1): time_min and the model's
    /// state inputs; the table is for the state after the last row. Required for such a model.
    #[arg(long, value_name = "LOG.csv")]
    state: Option<PathBuf>,
    /// Controller table format.
    #[arg(long, value_parser = choice::<op::Format>())]
    format: op::Format,
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
    /// Elements of a kinematic model to compensate: all, key (ranked by EFAST) or a list (EXX,EYY).
    #[arg(long, default_value = "all")]
    elements: Elements,
}

pub fn run(a: Args) -> Result<(), CliError> {
    // The job's options; a malformed axis, range or position is a usage error.
    let range = |r: &Option<String>| r.as_deref().map(Range::parse).transpose();
    let opts = Options {
        axis: parse_axis("--axis", &a.axis)?,
        output_axis: a
            .output_axis
            .as_deref()
            .map(|s| parse_axis("--output-axis", s))
            .transpose()?,
        range: range(&a.range)?,
        at: a.at.as_deref().map(parse_at).transpose()?,
        grid: [range(&a.x_range)?, range(&a.y_range)?, range(&a.z_range)?],
        model: a.model.unwrap_or_default(),
        from_iso230_2: a.from_iso230_2,
        state: a.state,
        format: a.format,
        comp_type: a.comp_type,
        table_index: a.table_index,
        direction: a.direction,
        max_points: a.max_points,
        reference_mm: a.reference_mm,
        reference_number: a.reference_number,
        magnification: a.magnification,
        detection_unit_um: a.detection_unit_um,
        max_increment: a.max_increment,
        axis_number: a.axis_number,
        cma_name: a.cma_name,
        max_correction_um: a.max_correction_um,
        out: a.out,
        elements: a.elements,
    };
    let done = op::run(&opts, &mut crate::observer::Stderr::default())?;
    eprint!("{done}");
    Ok(())
}
