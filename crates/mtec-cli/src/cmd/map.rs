//! `mtec map fit|eval`: volumetric error maps from a measured grid, and their values at points.

use crate::error::CliError;
use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_io::{InputError, OutputGuard, Table};
use std::fmt::Write as _;
use std::path::PathBuf;

const FIT_HELP: &str = "\
Builds a volumetric error map from a measured grid and writes it as JSON (\"format\": \"mtec.map/1\").

The grid file is CSV with the columns x_mm,y_mm,z_mm,ex_um,ey_um,ez_um: one row per grid node
(commanded position in mm, volumetric error of the tool tip in um). The rows must form a full
regular grid: every combination of the distinct x, y and z values exactly once, in any order
(they are sorted). Spacing may differ between grid lines unless a controller needs it equal.
Duplicated, missing or stray nodes are reported with their line and column.

--model trilinear: the map interpolates trilinearly between nodes, as a controller's 3-D
compensation does. --outside says what happens beyond the grid box: clamp (default: the value at
the nearest point of the box), extrapolate (the edge cell continued linearly) or refuse.
--controller fanuc-3d checks at most 25 equally spaced points per axis; linuxcnc at most 256.";

const EVAL_HELP: &str = "\
Evaluates an error model (a map from `mtec map fit`, or any model file mtec reads) at points.

The points file is CSV with at least the columns x_mm,y_mm,z_mm (other columns are ignored).
The output has the columns x_mm,y_mm,z_mm,ex_um,ey_um,ez_um, one row per input row, in the same
order; it goes to stdout unless -o is given. A point the model cannot evaluate (outside a map
whose policy is refuse) is an error naming its line.";

const FIT_EXAMPLES: &str = crate::help::examples!(
    "  # a laser-tracker grid: 11 x 11 x 11 points over 600 x 800 x 300 mm
  $ mtec simulate volumetric-grid --out g
  # the trilinear map of a controller's 3-D compensation; outside: edge value
  $ mtec map fit --grid g/grid.csv --model trilinear --outside clamp \\
      -o g/map.json
  # a build with the neural models (cargo feature `neural`) also fits a BPNN
  # map of the grid: --model bpnn --hidden 10 (73 weights, not 3993 values)"
);

const EVAL_EXAMPLES: &str = crate::help::examples!(
    "  # a measured grid and its map
  $ mtec simulate volumetric-grid --out g
  $ mtec map fit --grid g/grid.csv -o g/map.json
  # the map's errors along the body diagonals the tracker measured too, to
  # compare with their ex_um, ey_um, ez_um (map eval reads x_mm, y_mm, z_mm)
  $ mtec map eval --map g/map.json --points g/diagonals.csv -o diag-map.csv"
);

/// `mtec map`: volumetric error maps.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: MapCommand,
}

#[derive(clap::Subcommand)]
enum MapCommand {
    /// Build a map (mtec.map/1 JSON) from a measured grid CSV.
    #[command(long_about = FIT_HELP)]
    Fit(FitArgs),
    /// Errors of a map (or any model) at points; CSV out.
    #[command(long_about = EVAL_HELP)]
    Eval(EvalArgs),
}

/// The model a map is fitted with.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum MapModel {
    /// Trilinear interpolation between grid nodes.
    Trilinear,
    /// A one-hidden-layer back-propagation network (x, y, z → ex, ey, ez), see --hidden; in a
    /// build with the cargo feature `neural`.
    Bpnn,
}

#[derive(clap::Args)]
#[command(after_long_help = FIT_EXAMPLES)]
struct FitArgs {
    /// Grid CSV: x_mm,y_mm,z_mm,ex_um,ey_um,ez_um.
    #[arg(long)]
    grid: PathBuf,
    /// Map model.
    #[arg(long, value_enum, default_value = "trilinear")]
    model: MapModel,
    /// Behaviour outside the grid box: clamp, extrapolate or refuse.
    #[arg(long, default_value = "clamp", value_parser = ["clamp", "extrapolate", "refuse"])]
    outside: String,
    /// Controller whose grid limits to check: none, fanuc-3d (≤ 25 equally spaced points per axis), linuxcnc (≤ 256).
    #[arg(long, default_value = "none", value_parser = ["none", "fanuc-3d", "linuxcnc"])]
    controller: String,
    /// Largest number of grid points per axis (overrides the controller's).
    #[arg(long)]
    max_points_per_axis: Option<usize>,
    /// Hidden neurons of the BPNN (--model bpnn): 10 gives the source's 3-10-3 network.
    #[arg(long, default_value_t = 10)]
    hidden: usize,
    /// Output map JSON.
    #[arg(short = 'o', long = "out")]
    out: PathBuf,
}

#[derive(clap::Args)]
#[command(after_long_help = EVAL_EXAMPLES)]
struct EvalArgs {
    /// Model JSON (mtec.map/1, ...).
    #[arg(long)]
    map: PathBuf,
    /// Points CSV with x_mm,y_mm,z_mm.
    #[arg(long)]
    points: PathBuf,
    /// Output CSV (default: stdout).
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), CliError> {
    match args.command {
        MapCommand::Fit(a) => fit(a),
        MapCommand::Eval(a) => eval(a),
    }
}

fn fit(a: FitArgs) -> Result<(), CliError> {
    let outside = Outside::parse(&a.outside)
        .ok_or_else(|| CliError::usage(format!("unknown --outside `{}`", a.outside)))?;
    let mut limits = GridLimits::for_controller(&a.controller)
        .ok_or_else(|| CliError::usage(format!("unknown --controller `{}`", a.controller)))?;
    if let Some(n) = a.max_points_per_axis {
        if n < 1 {
            return Err(CliError::usage("--max-points-per-axis must be at least 1"));
        }
        limits.max_points_per_axis = Some(n);
    }
    // where the map goes is settled before any work (an input, a directory: exit 2)
    let dest = OutputGuard::new(&[&a.grid]).check(&a.out)?;
    let map = match a.model {
        MapModel::Trilinear => GridMap::read_csv(&a.grid, &limits, outside)?,
        #[cfg(feature = "neural")]
        MapModel::Bpnn => {
            return super::map_bpnn::fit_bpnn(&a.grid, a.hidden, &a.out, &dest);
        }
        #[cfg(not(feature = "neural"))]
        MapModel::Bpnn => return Err(super::neural::unavailable("`map fit --model bpnn`")),
    };
    let mut json =
        serde_json::to_string_pretty(&map.to_file()).map_err(|e| CliError::Internal(e.into()))?;
    json.push('\n');
    dest.write(json.as_bytes())?;
    let n = map.axes_mm();
    eprintln!(
        "map: {}×{}×{} nodes, outside = {} -> {}",
        n[0].len(),
        n[1].len(),
        n[2].len(),
        outside.name(),
        a.out.display()
    );
    Ok(())
}

fn eval(a: EvalArgs) -> Result<(), CliError> {
    let dest = match &a.out {
        Some(path) => OutputGuard::new(&[&a.map, &a.points]).check(path)?,
        None => mtec_io::Destination::Stdout,
    };
    let model = mtec_comp::load_error_model(&a.map)?;
    let table = Table::read(&a.points)?;
    let cols = [
        table.column("x_mm")?,
        table.column("y_mm")?,
        table.column("z_mm")?,
    ];
    let mut out = String::with_capacity(64 * table.rows.len() + 64);
    out.push_str("x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n");
    for row in &table.rows {
        let mut p = [0.0; 3];
        for (pa, &c) in p.iter_mut().zip(&cols) {
            *pa = table.cell_f64(row, c)?;
        }
        let e = model.error_um(p);
        if !e.iter().all(|v| v.is_finite()) {
            return Err(InputError::at(
                &a.points,
                row.line,
                cols[0] + 1,
                format!(
                    "the model has no value at ({}, {}, {}) mm (outside the map's grid, whose policy is refuse; see `mtec map fit --outside`)",
                    p[0], p[1], p[2]
                ),
            )
            .into());
        }
        let _ = writeln!(
            out,
            "{},{},{},{},{},{}",
            row.fields[cols[0]], row.fields[cols[1]], row.fields[cols[2]], e[0], e[1], e[2]
        );
    }
    dest.write(out.as_bytes())?;
    Ok(())
}
