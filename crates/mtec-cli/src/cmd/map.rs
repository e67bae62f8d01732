//! `mtec map fit|eval`: volumetric error maps from a measured grid, and their values at points.

use crate::choice::choice;
use crate::error::CliError;
use crate::help::{examples, text};
use mtec_comp::map::Outside;
use mtec_workflow::ops::map;
use mtec_workflow::unused::refused;
use std::path::PathBuf;

/// `mtec map`: volumetric error maps.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: MapCommand,
}

#[derive(clap::Subcommand)]
enum MapCommand {
    /// Build a map (mtec.map/1 JSON) from a measured grid CSV.
    #[command(long_about = text!("map.fit_help"))]
    Fit(FitArgs),
    /// Errors of a map (or any model) at points; CSV out.
    #[command(long_about = text!("map.eval_help"))]
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
#[command(after_long_help = examples!("map.fit_examples"))]
struct FitArgs {
    /// Grid CSV: x_mm,y_mm,z_mm,ex_um,ey_um,ez_um.
    #[arg(long)]
    grid: PathBuf,
    /// Map model.
    #[arg(long, value_enum, default_value = "trilinear")]
    model: MapModel,
    /// Behaviour outside the grid box: clamp, extrapolate or refuse.
    #[arg(long, default_value = "clamp", value_parser = choice::<Outside>())]
    outside: Outside,
    /// Controller whose grid limits to check: none, fanuc-3d (≤ 25 equally spaced points per axis), linuxcnc (≤ 256).
    #[arg(long, default_value = "none", value_parser = ["none", "fanuc-3d", "linuxcnc"])]
    controller: String,
    /// Largest number of grid points per axis (overrides the controller's).
    #[arg(long)]
    max_points_per_axis: Option<usize>,
    /// Hidden neurons of the BPNN (--model bpnn): 10 gives the source's 3-10-3 network
    /// [default: 10].
    #[arg(long)]
    hidden: Option<usize>,
    /// Output map JSON.
    #[arg(short = 'o', long = "out")]
    out: PathBuf,
}

#[derive(clap::Args)]
#[command(after_long_help = examples!("map.eval_examples"))]
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
    let opts = map::FitOptions {
        grid: a.grid,
        kind: match (a.model, a.hidden) {
            (MapModel::Trilinear, Some(_)) => {
                Err(refused("--hidden", "--model bpnn", "--model trilinear"))?
            }
            (MapModel::Trilinear, None) => map::MapKind::Trilinear,
            (MapModel::Bpnn, h) => map::MapKind::Bpnn {
                hidden: h.unwrap_or(10),
            },
        },
        outside: a.outside,
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
