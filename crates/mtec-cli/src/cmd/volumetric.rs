//! `mtec volumetric`: volumetric error of the tool tip at commanded points.

use crate::choice::choice;
use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::ops::volumetric::{self as op, Options};
use std::path::PathBuf;

/// Arguments of `mtec volumetric`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Volumetric error at commanded points (HTM or POE, exact or first-order)",
    long_about = text!("volumetric.long"),
    after_long_help = examples!("volumetric.examples")
)]
pub struct Args {
    /// Machine description (TOML).
    #[arg(long)]
    pub machine: PathBuf,
    /// Error set (JSON, "format": "mtec.errors/1"); a simulation's truth.json also works.
    #[arg(long)]
    pub errors: PathBuf,
    /// Commanded points (CSV with x_mm, y_mm, z_mm, ... columns).
    #[arg(long)]
    pub points: PathBuf,
    /// Formalism and order.
    #[arg(long, value_parser = choice::<op::Form>(), default_value = "htm-exact")]
    pub form: op::Form,
    /// Print JSON instead of CSV.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        machine: args.machine,
        errors: args.errors,
        points: args.points,
        form: args.form,
    };
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    super::report(&outcome, args.json, op::Outcome::to_json)
}
