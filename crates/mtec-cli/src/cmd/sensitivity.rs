//! `mtec sensitivity`: global sensitivity of the volumetric error to the error elements
//! (EFAST, Sobol or Morris), or of a standard test function.

use crate::help::{examples, text};
use crate::{choice::choice, error::CliError};
use mtec_workflow::ops::sensitivity::{self as op, MethodKind, Options};
use std::path::PathBuf;

/// Arguments of `mtec sensitivity`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Global sensitivity (EFAST, Sobol, Morris) of the volumetric error to the error elements",
    long_about = text!("sensitivity.long"),
    after_long_help = examples!("sensitivity.examples")
)]
pub struct Args {
    /// Machine description (TOML).
    #[arg(long, requires = "stats", conflicts_with = "function")]
    pub machine: Option<PathBuf>,
    /// Error statistics (CSV: element,mean,std,unit).
    #[arg(long, requires = "machine")]
    pub stats: Option<PathBuf>,
    /// A standard test function instead of a machine: ishigami, sobol-g, linear.
    #[arg(long)]
    pub function: Option<String>,
    /// Method.
    #[arg(long, value_parser = choice::<MethodKind>(), default_value = "efast")]
    pub method: MethodKind,
    /// Design size: EFAST points per curve (default 1200), Sobol base points (1024), Morris
    /// trajectories (100).
    #[arg(long)]
    pub samples: Option<usize>,
    /// EFAST interference factor M.
    #[arg(long, default_value_t = 4)]
    pub interference: usize,
    /// EFAST repetitions R with new random phases (intervals from their spread if R ≥ 2).
    #[arg(long, default_value_t = 10)]
    pub resamples: usize,
    /// Morris grid levels (even).
    #[arg(long, default_value_t = 4)]
    pub levels: usize,
    /// Bootstrap replicates of the Sobol and Morris intervals (0: none).
    #[arg(long, alias = "bootstrap", default_value_t = 100)]
    pub num_resamples: usize,
    /// Confidence level of the intervals (*_conf).
    #[arg(long, default_value_t = 0.95)]
    pub conf_level: f64,
    /// Random seed of the design.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// One pose: comma-separated axis positions in the machine's axis order (mm, deg).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        conflicts_with = "points"
    )]
    pub at: Option<Vec<f64>>,
    /// Several poses (CSV with x_mm, y_mm, z_mm, ... columns); indices are aggregated.
    #[arg(long)]
    pub points: Option<PathBuf>,
    /// lhs or lhs:N: N poses (64) by Latin hypercube over the travels instead of --at/--points.
    #[arg(long, value_parser = op::parse_sampling)]
    pub sampling: Option<usize>,
    /// Target accuracy of Ex, Ey, Ez for the tolerance allocation, µm.
    #[arg(long, default_value_t = 25.0)]
    pub target_um: f64,
    /// Coverage factor k: the target bounds k·σ of each axis.
    #[arg(long, default_value_t = 2.0)]
    pub coverage: f64,
    /// Print JSON ("format": "mtec.sensitivity/1").
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        machine: args.machine,
        stats: args.stats,
        function: args.function,
        method: args.method,
        samples: args.samples,
        interference: args.interference,
        resamples: args.resamples,
        levels: args.levels,
        num_resamples: args.num_resamples,
        conf_level: args.conf_level,
        seed: args.seed,
        at: args.at,
        points: args.points,
        lhs_poses: args.sampling,
        target_um: args.target_um,
        coverage: args.coverage,
    };
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    super::report(&outcome, args.json, op::Outcome::to_json)
}
