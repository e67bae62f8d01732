//! `mtec identify lines`: the error elements of a three-axis machine from line measurements.

use crate::error::CliError;
use crate::help::examples;
use mtec_identify::lines::{Degree, DEFAULT_DEGREE};
use mtec_workflow::ops::identify_lines::{self as op, Options};
use std::io::Write;
use std::path::PathBuf;

/// Options of `mtec identify lines` (its help text is `help/identify_lines.long_about.txt`).
#[derive(clap::Args, Debug)]
#[command(after_long_help = examples!("identify_lines.examples"))]
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
    /// Degree of the error functions: `auto` (per kind of element, by cross-validation over the
    /// points), `smooth` (or a smoothing spline where it validates better), 2..12 for all.
    #[arg(long, default_value_t = DEFAULT_DEGREE)]
    pub degree: Degree,
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

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        machine: args.machine,
        data: args.data,
        design: args.design,
        degree: args.degree,
        output: args.output,
        kinematic_model: args.kinematic_model,
        stats: args.stats,
    };
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
