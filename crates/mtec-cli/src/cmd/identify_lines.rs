//! `mtec identify lines`: the error elements of a three-axis machine from line measurements.

use crate::error::CliError;
use mtec_identify::lines::DEFAULT_DEGREE;
use mtec_workflow::ops::identify_lines::{self as op, Options};
use std::io::Write;
use std::path::PathBuf;

/// The long help of `mtec identify lines`.
pub const LONG_ABOUT: &str =
    "Identify the 21 error elements of a three-axis machine from laser lines (9-line method).

Each error motion is a polynomial of its axis position (zero at the travel's lower end;
straightness measured from its least-squares reference line, ISO 230-1), squareness a
constant; every straightness channel gets its own alignment slope (reported, never turned
into squareness). The observation model is the machine's first-order kinematics; the fit is
weighted least squares. The report says
which elements the design cannot identify (named, with what they are confounded with, and
given no numbers), the rank, singular values and condition number, the residual RMS and the
1-sigma uncertainty of every identified element. Predictions of the identified set are valid
at the tool offset of the measurement.

Data (CSV, docs/formats.md, \"Line measurement CSV\"): line,step,x_mm,y_mm,z_mm,ux,uy,uz,
reading_um, one row per point and channel; the reading is the laser reading minus the commanded
displacement from the line's first point, projected on the unit direction (ux,uy,uz). Name a
line's channels `X1` (along the line) and `X1.y`, `X1.z` (straightness). The design is read from
the points. An optional `run` column (1, 2, ...) holds repeat runs: each run of a channel has its own
zero and alignment slope, and least squares averages the runs.

Outputs (each checked before any work; none may be an input or another output): -o the error
set (mtec.errors/1); --kinematic-model the machine with that set (mtec.kinematic-model/1), which
`compensate gcode|table --model` and mtec-rt read as it is; --stats each identified element's
mean and std over its travel (element,mean,std,unit; a constant element's std is its
magnitude), which `sensitivity --stats` reads.

--design checks the data against a built-in design; without --data it analyses that design
alone (what it can identify) on the machine.";

/// The examples that end the help of `mtec identify lines`.
pub const EXAMPLES: &str = crate::help::examples!(
    "  # the 9-line laser measurements of a 3-axis machining centre (simulated)
  $ mtec simulate vmc-9line --out d --seed 1
  # what the 9-line design can identify on this machine, before measuring
  $ mtec identify lines --machine d/machine.toml --design nine-line
  # the 21 error elements with their uncertainties, written as an error set,
  # as a kinematic model to compensate with, and as statistics for sensitivity
  $ mtec identify lines --machine d/machine.toml --data d/lines.csv \\
      -o d/errors.json --kinematic-model d/km.json --stats d/stats.csv
  # the volumetric error the identified set predicts at one point
  $ printf 'x_mm,y_mm,z_mm\\n500,700,250\\n' > pts.csv
  $ mtec volumetric --machine d/machine.toml --errors d/errors.json \\
      --points pts.csv
  # a program corrected with the identified model, no file made by hand
  $ printf 'G21 G90\\nG0 X100 Y200 Z50\\nG1 X500 Y700 Z250 F1000\\nM2\\n' > part.ngc
  $ mtec compensate gcode --model d/km.json part.ngc -o part-km.ngc
  # which identified elements drive the error at X500 Y700 Z250
  $ mtec sensitivity --machine d/machine.toml --stats d/stats.csv \\
      --at 500,700,250"
);

/// Options of `mtec identify lines` (its help text is [`LONG_ABOUT`]).
#[derive(clap::Args, Debug)]
#[command(after_long_help = EXAMPLES)]
pub struct Args {
    /// Machine description (TOML): chain, travels, tool offset of the measurement.
    #[arg(long)]
    pub machine: PathBuf,
    /// Line measurements (CSV, see docs/formats.md).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// A built-in design: the data must contain its lines; without --data, analyse it alone.
    #[arg(long, value_parser = ["nine-line", "fifteen-line"])]
    pub design: Option<String>,
    /// Polynomial degree of the error functions (2..12).
    #[arg(long, default_value_t = DEFAULT_DEGREE)]
    pub degree: usize,
    /// Print the report as JSON ("format": "mtec.identify-lines/1") instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the identified error set (JSON, "format": "mtec.errors/1") here.
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Also write the kinematic model (JSON, "format": "mtec.kinematic-model/1": the machine
    /// and the identified error set) here: `compensate gcode|table --model` and mtec-rt read it.
    #[arg(long, value_name = "FILE")]
    pub kinematic_model: Option<PathBuf>,
    /// Also write the error statistics of the identified set (CSV element,mean,std,unit: each
    /// function over its travel; a constant element's spread is its magnitude) here:
    /// `sensitivity --stats` reads it.
    #[arg(long, value_name = "FILE")]
    pub stats: Option<PathBuf>,
}

impl Args {
    fn options(&self) -> Options {
        Options {
            machine: self.machine.clone(),
            data: self.data.clone(),
            design: self.design.clone(),
            degree: self.degree,
            output: self.output.clone(),
            kinematic_model: self.kinematic_model.clone(),
            stats: self.stats.clone(),
        }
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = args.options();
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    // with an output on stdout (`-o -`) the report goes to stderr; a closed pipe (`| head`)
    // is not an error worth a panic
    let mut out: Box<dyn Write> = if op::writes_to_stdout(&opts) {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    };
    let _ = if args.json {
        writeln!(out, "{}", outcome.to_json()?)
    } else {
        write!(out, "{outcome}")
    };
    let _ = out.flush();
    Ok(())
}
