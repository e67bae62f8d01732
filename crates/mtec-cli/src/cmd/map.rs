//! `mtec map fit|eval`: volumetric error maps from a measured grid, and their values at points.

use crate::error::CliError;
use mtec_comp::map::Outside;
use mtec_workflow::ops::map;
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
    let opts = map::FitOptions {
        grid: a.grid,
        kind: match a.model {
            MapModel::Trilinear => map::MapKind::Trilinear,
            MapModel::Bpnn => map::MapKind::Bpnn { hidden: a.hidden },
        },
        outside,
        controller: a.controller,
        max_points_per_axis: a.max_points_per_axis,
        out: a.out,
    };
    let done = fit_observed(&opts)?;
    // a BPNN's fit report goes to stdout unless the model itself does (-o -); the trilinear
    // map's one line always to stderr
    if matches!(opts.kind, map::MapKind::Bpnn { .. }) && opts.out.as_os_str() != "-" {
        print!("{done}");
    } else {
        eprint!("{done}");
    }
    Ok(())
}

/// A BPNN's training shows its epochs on one redrawn line and stops on Ctrl-C (keeping the best
/// epoch); the trilinear map's steps are lines on stderr.
#[cfg(feature = "neural")]
fn fit_observed(opts: &map::FitOptions) -> Result<map::FitOutcome, CliError> {
    if matches!(opts.kind, map::MapKind::Bpnn { .. }) {
        let mut term = super::terminal::Terminal::new(false);
        let done = super::terminal::ctrl_c::during(|| map::fit(opts, &mut term));
        term.done();
        return done;
    }
    map::fit(opts, &mut crate::observer::Stderr::default())
}

#[cfg(not(feature = "neural"))]
fn fit_observed(opts: &map::FitOptions) -> Result<map::FitOutcome, CliError> {
    map::fit(opts, &mut crate::observer::Stderr::default())
}

fn eval(a: EvalArgs) -> Result<(), CliError> {
    let opts = map::EvalOptions {
        model: a.map,
        points: a.points,
        out: a.out,
    };
    map::eval(&opts, &mut crate::observer::Stderr::default())?;
    Ok(())
}
