//! `mtec circular`: ISO 230-4 values and ballbar diagnostics of a circular test.

use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::ops::circular::{self as op, Options};
use std::path::PathBuf;

/// Arguments of `mtec circular`.
#[derive(clap::Args, Debug)]
#[command(
    about = "ISO 230-4 circular test (G, H) and ballbar diagnostics, ranked",
    long_about = text!("circular.long"),
    after_long_help = examples!("circular.examples")
)]
pub struct Args {
    /// The trace file (angle_deg,direction,dl_um).
    pub run: PathBuf,
    /// Print the results as one JSON object (format mtec.circular/1).
    #[arg(long)]
    pub json: bool,
    /// Nominal radius (mm); overrides `# radius_mm` in the file.
    #[arg(long)]
    pub radius_mm: Option<f64>,
    /// Feed (mm/min); overrides `# feed_mm_min`. Needed for the servo mismatch in ms.
    #[arg(long)]
    pub feed_mm_min: Option<f64>,
    /// Plane XY, YZ or ZX; overrides `# plane`.
    #[arg(long)]
    pub plane: Option<String>,
    /// Start of a partial arc (deg); overrides `# arc_start_deg`. Needs --arc-end-deg.
    #[arg(long, allow_negative_numbers = true)]
    pub arc_start_deg: Option<f64>,
    /// End of a partial arc (deg), traced ccw from the start; overrides `# arc_end_deg`.
    #[arg(long, allow_negative_numbers = true)]
    pub arc_end_deg: Option<f64>,
    /// Contribution (um) from which a fault is reported as present.
    #[arg(long, default_value_t = 0.3)]
    pub threshold_um: f64,
    /// Write circular.json and polar.svg into this folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        run: args.run,
        // the plane is checked before the arc
        plane: args.plane.as_deref().map(op::parse_plane).transpose()?,
        arc_deg: op::arc_deg(args.arc_start_deg, args.arc_end_deg)?,
        radius_mm: args.radius_mm,
        feed_mm_min: args.feed_mm_min,
        threshold_um: args.threshold_um,
        out: args.out,
    };
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    super::report(&outcome, args.json, op::Outcome::to_json)
}
