//! `mtec identify ballbar`: rotary-axis error motions from ballbar readings in five modes.

use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::ops::identify_ballbar::{self as op, Options};
use std::path::PathBuf;

/// Arguments of `mtec identify ballbar`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Rotary-axis error motions from ballbar readings in five modes",
    long_about = text!("identify_ballbar.long_about"),
    after_long_help = examples!("identify_ballbar.examples")
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

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        setup: args.setup,
        data: args.data.clone(),
        temps: args.temps,
        out: op::out_folder(args.out, &args.data, args.json),
    };
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    super::report(&outcome, args.json, op::Outcome::to_json)
}
