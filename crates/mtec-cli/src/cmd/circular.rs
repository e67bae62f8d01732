//! `mtec circular`: ISO 230-4 values and ballbar diagnostics of a circular test.

use crate::error::CliError;
use mtec_measure::circular::Plane;
use mtec_workflow::ops::circular::{self as op, Options};
use std::path::PathBuf;

const LONG: &str = "\
Evaluates a circular test of two linear axes (ballbar, ISO 230-4): the least-squares circle of each
direction and of both, the circular deviation G (cw, ccw), the bidirectional circular deviation
G(b) and the circular hysteresis H; then fits the ballbar diagnostics from the trace and ranks them
by their contribution to the circularity: centre offset, scale mismatch (ppm), squareness (um/m),
servo mismatch (ms, needs the feed), backlash of each axis at its positive and negative end,
lateral play, reversal spikes, straightness and cyclic error (amplitude and pitch). A fault is
reported as present when it adds at least --threshold-um to the circularity and exceeds 3
standard errors.

Input (CSV, docs/formats.md, \"Circular test CSV\"): angle_deg,direction,dl_um
  angle_deg from the plane's first axis towards its second; direction cw or ccw (ccw =
  increasing angle); dl_um = bar length minus nominal. Header comments give the test:
    # radius_mm = 100
    # plane = XY          (XY, YZ or ZX)
    # feed_mm_min = 1000  (optional)
    # arc_start_deg = -110  (a partial arc, e.g. 220 deg in a vertical plane:
    # arc_end_deg = 110      traced ccw from start to end and cw back; >= 90 deg)
  Options override them. Both directions, over the full circle unless an arc is declared; the
  diagnostics need >= 90 samples each. On a partial arc, G and G(b) are taken over the arc, H
  where both directions overlap, and each fault the arc cannot determine (its pattern reproduced
  by the others over these angles, or its axis reversal off the arc) is reported as \"not
  determined by a 220 deg arc\" instead of a number.";

const EXAMPLES: &str = crate::help::examples!(
    "  # a ballbar test of X and Y (R 100 mm, both directions) with injected faults
  $ mtec simulate circular-test --out c
  # G, G(b), H per ISO 230-4 and the faults that cause them, ranked; the JSON
  # results and the polar plot go to c/result (circular.json, polar.svg)
  $ mtec circular c/circular.csv --out c/result
  # the same machine without the faults, to compare
  $ mtec circular c/circular-fault-free.csv
  # a 220 deg partial arc in ZX (its header: # arc_start_deg = -110 and
  # # arc_end_deg = 110); the faults the arc cannot determine are named
  $ mtec simulate circular-test-arc --out a
  $ mtec circular a/circular-arc.csv --out a/result"
);

/// Arguments of `mtec circular`.
#[derive(clap::Args, Debug)]
#[command(
    about = "ISO 230-4 circular test (G, H) and ballbar diagnostics, ranked",
    long_about = LONG,
    after_long_help = EXAMPLES
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

impl Args {
    fn options(&self) -> Result<Options, CliError> {
        let plane =
            match &self.plane {
                None => None,
                Some(p) => Some(Plane::parse(p).ok_or_else(|| {
                    CliError::usage(format!("--plane {p}: expected XY, YZ or ZX"))
                })?),
            };
        let arc_deg = match (self.arc_start_deg, self.arc_end_deg) {
            (None, None) => None,
            (Some(a), Some(b)) => Some([a, b]),
            _ => {
                return Err(CliError::usage(
                    "a partial arc needs both --arc-start-deg and --arc-end-deg",
                ))
            }
        };
        Ok(Options {
            run: self.run.clone(),
            arc_deg,
            radius_mm: self.radius_mm,
            feed_mm_min: self.feed_mm_min,
            plane,
            threshold_um: self.threshold_um,
            out: self.out.clone(),
        })
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let outcome = op::run(&args.options()?, &mut crate::observer::Stderr::default())?;
    if args.json {
        super::emit(&format!("{}\n", outcome.to_json()?))
    } else {
        super::emit(&outcome.to_string())
    }
}
