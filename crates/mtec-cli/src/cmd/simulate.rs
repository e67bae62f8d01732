//! `mtec simulate SCENARIO --out DIR [--seed N]`: write a scenario's measurement files and truth.

use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::ops::simulate::{self as op, Options, SCENARIOS};
use std::path::PathBuf;

/// Arguments of `mtec simulate`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Simulate measurements on the virtual machine (known truth)",
    long_about = text!("simulate.long"),
    after_help = scenario_list(),
    after_long_help = format!("{}\n{}", scenario_list(), examples!("simulate.examples"))
)]
pub struct Args {
    /// Scenario name (see the list below).
    pub scenario: String,
    /// Output folder (default: ./<scenario>-seed<N>).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Random seed: noise, ground-truth shapes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

fn scenario_list() -> String {
    let mut s = String::from("Scenarios:\n");
    for (name, what) in SCENARIOS {
        s.push_str(&format!("  {name:<18} {what}\n"));
    }
    s
}

pub fn run(args: Args) -> Result<(), CliError> {
    let opts = Options {
        scenario: args.scenario,
        out: args.out,
        seed: args.seed,
    };
    let outcome = op::run(&opts, &mut crate::observer::Stderr::default())?;
    super::emit(&outcome.to_string())
}
