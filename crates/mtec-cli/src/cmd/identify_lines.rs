//! `mtec identify lines`: the error elements of a three-axis machine from line measurements.

use crate::error::CliError;
use crate::inputs::read_machine;
use mtec_identify::lines::{self, LineData, LinesError, DEFAULT_DEGREE};
use mtec_io::{InputError, OutputGuard};
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

--design checks the data against a built-in design; without --data it analyses that design
alone (what it can identify) on the machine.";

/// The examples that end the help of `mtec identify lines`.
pub const EXAMPLES: &str = crate::help::examples!(
    "  # the 9-line laser measurements of a 3-axis machining centre (simulated)
  $ mtec simulate vmc-9line --out d --seed 1
  # what the 9-line design can identify on this machine, before measuring
  $ mtec identify lines --machine d/machine.toml --design nine-line
  # the 21 error elements with their uncertainties, written as an error set
  $ mtec identify lines --machine d/machine.toml --data d/lines.csv \\
      -o d/errors.json
  # the volumetric error the identified set predicts at one point
  $ printf 'x_mm,y_mm,z_mm\\n500,700,250\\n' > pts.csv
  $ mtec volumetric --machine d/machine.toml --errors d/errors.json \\
      --points pts.csv"
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
}

pub fn run(args: Args) -> Result<(), CliError> {
    // where the error set goes is settled before any work (an input, a directory: exit 2)
    let dest = match &args.output {
        Some(_) if args.data.is_none() => {
            return Err(CliError::usage(
                "-o needs measurements (--data): a design alone identifies no values",
            ))
        }
        Some(out) => {
            let mut inputs = vec![args.machine.clone()];
            inputs.extend(args.data.clone());
            Some(OutputGuard::new(&inputs).check(out)?)
        }
        None => None,
    };
    let machine = read_machine(&args.machine)?;
    let preset = match &args.design {
        Some(name) => Some(
            mtec_model::line_preset(name, &machine, 20, 10.0).ok_or_else(|| {
                InputError::file(
                    &args.machine,
                    format!("the `{name}` design needs a machine with axes X, Y and Z"),
                )
            })?,
        ),
        None => None,
    };
    let data =
        match (&args.data, &preset) {
            (Some(path), _) => {
                let d = LineData::read(path)?;
                if let Some(p) = &preset {
                    lines::check_design(&d, p).map_err(|m| {
                        InputError::file(
                            path,
                            format!("{m} (--design {})", args.design.as_deref().unwrap_or("")),
                        )
                    })?;
                }
                d
            }
            (None, Some(p)) => LineData::from_specs(p).map_err(CliError::Usage)?,
            (None, None) => return Err(CliError::usage(
                "give the measurements with --data LINES.csv, or a design to analyse with --design",
            )),
        };
    let id = lines::identify(&machine, &data, args.degree).map_err(|e| match e {
        LinesError::Input(i) => CliError::Input(i),
        LinesError::Model(m) => CliError::Input(InputError::file(&args.machine, m.to_string())),
        other => CliError::Input(InputError::file(
            args.data.as_deref().unwrap_or(&args.machine),
            other.to_string(),
        )),
    })?;
    // a closed pipe (`| head`) is not an error worth a panic: ignore write failures to stdout;
    // with `-o -` the error set has stdout and the report goes to stderr
    let mut stdout = match &dest {
        Some(d) => super::messages(d),
        None => Box::new(std::io::stdout()),
    };
    if args.json {
        let text =
            serde_json::to_string_pretty(&id.report).map_err(|e| CliError::Internal(e.into()))?;
        let _ = writeln!(stdout, "{text}");
    } else {
        let _ = write!(stdout, "{}", id.report.to_text());
    }
    if let (Some(out), Some(dest)) = (&args.output, &dest) {
        let bytes =
            serde_json::to_vec_pretty(&id.errors).map_err(|e| CliError::Internal(e.into()))?;
        let _ = stdout.flush();
        dest.write(&bytes)?;
        if !args.json {
            let _ = writeln!(stdout, "Wrote {}", out.display());
        }
    }
    Ok(())
}
