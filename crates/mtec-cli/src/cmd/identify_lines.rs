//! `mtec identify lines`: the error elements of a three-axis machine from line measurements.

use crate::error::CliError;
use crate::inputs::read_machine;
use mtec_comp::kinematic::KinematicFile;
use mtec_identify::lines::{self, LineData, LinesError, DEFAULT_DEGREE};
use mtec_io::{Destination, InputError, OutputGuard};
use mtec_sensitivity::error_model::ErrorStatistics;
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

/// The files `identify lines` writes, settled before any work.
struct Outputs {
    errors: Option<(PathBuf, Destination)>,
    kinematic_model: Option<(PathBuf, Destination)>,
    stats: Option<(PathBuf, Destination)>,
}

impl Outputs {
    /// Checks every output before any work: none may be an input, a directory or another of
    /// them, at most one may be stdout (`-`), and all need measurements (exit 2).
    fn check(args: &Args) -> Result<Outputs, CliError> {
        let named = [
            ("-o", &args.output),
            ("--kinematic-model", &args.kinematic_model),
            ("--stats", &args.stats),
        ];
        let given: Vec<(&str, &PathBuf)> = named
            .iter()
            .filter_map(|(o, p)| p.as_ref().map(|p| (*o, p)))
            .collect();
        if let (Some((opt, _)), None) = (given.first(), &args.data) {
            return Err(CliError::usage(format!(
                "{opt} needs measurements (--data): a design alone identifies no values"
            )));
        }
        let on_stdout: Vec<&str> = given
            .iter()
            .filter(|(_, p)| p.as_os_str() == "-")
            .map(|(o, _)| *o)
            .collect();
        if on_stdout.len() > 1 {
            return Err(CliError::usage(format!(
                "{} all name stdout (-): at most one output can go there",
                on_stdout.join(" and ")
            )));
        }
        let mut inputs = vec![args.machine.clone()];
        inputs.extend(args.data.clone());
        let guard = OutputGuard::new(&inputs);
        // each output against the ones before it, so that two never name one file
        let mut earlier: Vec<(&str, OutputGuard)> = Vec::new();
        let mut check = |opt: &'static str,
                         p: &Option<PathBuf>|
         -> Result<Option<(PathBuf, Destination)>, CliError> {
            let Some(p) = p else { return Ok(None) };
            let dest = guard.check(p)?;
            for (other, g) in &earlier {
                if g.check(p).is_err() {
                    return Err(CliError::Input(InputError::file(
                        p,
                        format!(
                            "{opt} names the same file as {other}: give each output its own file"
                        ),
                    )));
                }
            }
            earlier.push((opt, OutputGuard::new(&[p])));
            Ok(Some((p.clone(), dest)))
        };
        Ok(Outputs {
            errors: check("-o", &args.output)?,
            kinematic_model: check("--kinematic-model", &args.kinematic_model)?,
            stats: check("--stats", &args.stats)?,
        })
    }

    /// The destinations that are given, in the order they are written.
    fn all(&self) -> impl Iterator<Item = &(PathBuf, Destination)> {
        [&self.errors, &self.kinematic_model, &self.stats]
            .into_iter()
            .flatten()
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    // where the outputs go is settled before any work (an input, a directory: exit 2)
    let outputs = Outputs::check(&args)?;
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
    // everything is made before anything is written: a machine the compensation cannot
    // evaluate (no X, Y, Z) refuses the kinematic model, and no file is left half-done
    let kinematic = match &outputs.kinematic_model {
        Some(_) => Some(
            KinematicFile::new(&machine, &id.errors)
                .map_err(|m| CliError::Input(InputError::file(&args.machine, m)))?
                .to_json()
                .map_err(|e| CliError::Internal(e.into()))?,
        ),
        None => None,
    };
    let stats = outputs
        .stats
        .as_ref()
        .map(|_| ErrorStatistics::of_identified(&id.errors, &machine).to_identified_csv());
    let errors = match &outputs.errors {
        Some(_) => {
            Some(serde_json::to_vec_pretty(&id.errors).map_err(|e| CliError::Internal(e.into()))?)
        }
        None => None,
    };
    // a closed pipe (`| head`) is not an error worth a panic: ignore write failures to stdout;
    // with an output on stdout (`-o -`) the report goes to stderr
    let mut stdout = match outputs.all().find(|(_, d)| d.is_stdout()) {
        Some((_, d)) => super::messages(d),
        None => Box::new(std::io::stdout()),
    };
    if args.json {
        let text =
            serde_json::to_string_pretty(&id.report).map_err(|e| CliError::Internal(e.into()))?;
        let _ = writeln!(stdout, "{text}");
    } else {
        let _ = write!(stdout, "{}", id.report.to_text());
    }
    let _ = stdout.flush();
    for (out, bytes) in [
        (&outputs.errors, errors),
        (&outputs.kinematic_model, kinematic.map(String::into_bytes)),
        (&outputs.stats, stats.map(String::into_bytes)),
    ] {
        if let (Some((path, dest)), Some(bytes)) = (out, bytes) {
            dest.write(&bytes)?;
            if !args.json {
                let _ = writeln!(stdout, "Wrote {}", path.display());
            }
        }
    }
    Ok(())
}
