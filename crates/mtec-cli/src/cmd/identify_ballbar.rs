//! `mtec identify ballbar`: rotary-axis error motions from ballbar readings in five modes.

use crate::error::CliError;
use mtec_workflow::ops::identify_ballbar::{self as op, Options};
use std::path::PathBuf;

pub const LONG_ABOUT: &str = "\
Identifies the error motions EXC, EYC, EZC (um) and EAC, EBC (urad) of a rotary C axis from
double-ball-bar readings taken in five installation modes, at every measured angle, for every
experiment and time (static errors at t = 0, thermal errors later). ECC (rotation about the axis)
is not observable with bars in planes through the axis.

Method: each mode signal has its mean and first harmonic removed (this removes the set-up
eccentricity, the location errors of the axis and drifts of the tool side, and also any true
constant or once-per-revolution error motion); then, per angle, the 5x5 system of the first-order
bar-length model  L0*dL = (r_w - r_t).dr  is solved by SVD. A mode set that cannot separate the
five motions at some angle is refused with the combination it cannot see.

Setup TOML: five [[mode]] tables
  [[mode]]
  id = 1
  workpiece_ball_mm = [0, 0, 100]   # ball on the table, coordinates at C = 0
  tool_ball_mm = [500, 0, 100]      # ball in the spindle, fixed while C turns

Data CSV: experiment,time_min,mode,angle_deg,dl_um   (one full, evenly spaced revolution per
experiment, time and mode; dl_um = reading minus nominal length). Temperatures CSV (optional):
experiment,time_min,<sensor>_c,... joined to the output by experiment and time.

Outputs (in --out DIR, default <data>-ballbar/ beside the data):
  motions.csv        experiment,time_min,angle_deg,EXC_um,EYC_um,EZC_um,EAC_urad,EBC_urad[,<sensor>_c...]
  conditioning.json  rank, singular values and condition number per angle, worst angle, and
                     the motion combinations (harmonics >= 2) that the set-up-error removal
                     makes invisible over a revolution (reported as zero in motions.csv)
  polar_<EXC..EBC>.svg, time_<EXC..EBC>.svg   polar plots against C and change with time
With --json the same content is printed as one JSON object (files only if --out is given).";

const EXAMPLES: &str = crate::help::examples!(
    "  # ballbar on a C axis in 5 installations, 4 speeds x 4 h, with temperatures
  $ mtec simulate dbb-rotary --out d --seed 1
  # EXC, EYC, EZC, EAC, EBC per angle and time; conditioning, plots in d/id
  $ mtec identify ballbar --setup d/setup.toml --data d/dbb.csv \\
      --temps d/temps.csv --out d/id"
);

/// Arguments of `mtec identify ballbar`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Rotary-axis error motions from ballbar readings in five modes",
    long_about = LONG_ABOUT,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// Setup TOML with the five [[mode]] tables.
    #[arg(long)]
    pub setup: PathBuf,
    /// Ballbar readings: experiment,time_min,mode,angle_deg,dl_um.
    #[arg(long)]
    pub data: PathBuf,
    /// Temperatures: experiment,time_min,<sensor>_c,... (joined by experiment and time).
    #[arg(long)]
    pub temps: Option<PathBuf>,
    /// Output folder (default: <data stem>-ballbar beside the data file).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

impl Args {
    /// Without --out, the text report writes into `<data stem>-ballbar`; --json alone writes
    /// nothing.
    fn options(&self) -> Options {
        Options {
            setup: self.setup.clone(),
            data: self.data.clone(),
            temps: self.temps.clone(),
            out: match (&self.out, self.json) {
                (Some(d), _) => Some(d.clone()),
                (None, false) => Some(op::default_out(&self.data)),
                (None, true) => None,
            },
        }
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let outcome = op::run(&args.options(), &mut crate::observer::Stderr::default())?;
    if args.json {
        super::emit(&format!("{}\n", outcome.to_json()?))
    } else {
        super::emit(&outcome.to_string())
    }
}
