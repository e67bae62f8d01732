//! `mtec run PROJECT.toml`: the pipeline a project file asks for, with an HTML report, run
//! in-process by `mtec_workflow::project::run`; this parses and prints where the report went.

use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::project;

/// Arguments of `mtec run`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Run the whole pipeline of a project file and write an HTML report",
    long_about = text!("run.long"),
    after_long_help = examples!("run.examples")
)]
pub struct Args {
    /// Project file (TOML).
    pub project: std::path::PathBuf,
    /// Output folder (default: <project name>-results beside the project file).
    #[arg(long, short)]
    pub out: Option<std::path::PathBuf>,
    /// Print nothing but errors.
    #[arg(long)]
    pub quiet: bool,
    /// Print a JSON summary (the stages and their output files) on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    // the neural models' thread setting, while this process has no other thread
    #[cfg(feature = "neural")]
    super::neural::single_candle_thread();
    let opts = project::RunOptions {
        project: args.project,
        out: args.out,
        title: None,
    };
    let done = project::run(&opts, &mut crate::observer::Stderr { quiet: args.quiet })?;
    if args.json {
        println!("{}", serde_json::to_string(&done)?);
    } else if !args.quiet {
        println!("report: {}", done.report.display());
    }
    Ok(())
}
