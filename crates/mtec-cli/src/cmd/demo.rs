//! `mtec demo`: simulate a machine, run the whole pipeline on it, write the report.

//! The run is `mtec_workflow::project::demo`.

use crate::error::CliError;
use mtec_workflow::project::demo;
use std::path::PathBuf;

const LONG: &str = "\
Simulate a machine (geometry, thermal, rotary axis), run the whole pipeline, write the report.

The virtual machine writes every kind of measurement (laser lines, positioning runs, circular
and ballbar tests, thermal logs, a tracker grid) into <out>/data with a project file
<out>/data/project.toml; `mtec run` then analyses it exactly as it would a real machine's files,
and the demo adds the one thing only a simulation can: the compensation rate measured against
the known truth.";

const EXAMPLES: &str = crate::help::examples!(
    "  # simulate, analyse, compensate: open demo/report.html in a browser
  $ mtec demo --out demo
  # the same analysis from the project file the demo wrote (edit it to try)
  $ mtec run demo/data/project.toml --out results"
);

/// Arguments of `mtec demo`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Simulate a machine, run the whole pipeline on it, write the report",
    long_about = LONG,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// Output folder.
    #[arg(long, short, default_value = "mtec-demo")]
    pub out: PathBuf,
    /// Random seed of the simulation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print nothing but errors and the report's path.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = demo::Options {
        out: args.out,
        seed: args.seed,
    };
    let done = demo::run(&opts, &mut crate::observer::Stderr { quiet: args.quiet })?;
    println!("report: {}", done.report.display());
    Ok(())
}
