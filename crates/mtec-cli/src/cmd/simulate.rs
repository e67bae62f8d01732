//! `mtec simulate SCENARIO --out DIR [--seed N]`: write a scenario's measurement files and truth.

use crate::error::CliError;
use mtec_workflow::ops::simulate::{self as op, Options, SCENARIOS};
use std::path::PathBuf;

const LONG: &str = "\
Simulate measurements on the virtual machine (known ground truth).

Writes the scenario's measurement files and `truth.json` (the errors the analysis should find)
into --out. The same seed always gives the same files; another seed gives other noise and other
error shapes. The files are described in docs/formats.md, \"Simulation outputs\".";

const EXAMPLES: &str = crate::help::examples!(
    "  # 9-line laser measurements of a 3-axis machining centre, and its truth
  $ mtec simulate vmc-9line --out d --seed 1
  # the errors identified from the lines: compare d/errors.json, d/truth.json
  $ mtec identify lines --machine d/machine.toml --data d/lines.csv \\
      -o d/errors.json
  # another machine of the same kind: other noise, other error shapes
  $ mtec simulate vmc-9line --out d2 --seed 2"
);

/// Arguments of `mtec simulate`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Simulate measurements on the virtual machine (known truth)",
    long_about = LONG,
    after_help = scenario_list(),
    after_long_help = format!("{}\n{EXAMPLES}", scenario_list())
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

impl Args {
    fn options(&self) -> Options {
        Options {
            scenario: self.scenario.clone(),
            out: self.out.clone(),
            seed: self.seed,
        }
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let outcome = op::run(&args.options(), &mut crate::observer::Stderr::default())?;
    super::emit(&outcome.to_string())
}
