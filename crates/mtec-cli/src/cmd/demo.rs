//! `mtec demo`: simulate a machine, run the whole pipeline on it, write the report.

//! The run is `mtec_workflow::project::demo`.

use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::project::demo;
use std::path::PathBuf;

/// Arguments of `mtec demo`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Simulate a machine, run the whole pipeline on it, write the report",
    long_about = text!("demo.long"),
    after_long_help = examples!("demo.examples")
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
