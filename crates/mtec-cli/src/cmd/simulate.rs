//! `mtec simulate SCENARIO --out DIR [--seed N]`: write a scenario's measurement files and truth.

use crate::error::CliError;
use mtec_io::write_output;
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
    for (name, what) in mtec_sim::SCENARIOS {
        s.push_str(&format!("  {name:<18} {what}\n"));
    }
    s
}

pub fn run(args: Args) -> Result<(), CliError> {
    let output = mtec_sim::run_scenario(&args.scenario, args.seed)
        .map_err(|e| CliError::usage(e.to_string()))?;
    let dir = args
        .out
        .unwrap_or_else(|| PathBuf::from(format!("{}-seed{}", args.scenario, args.seed)));
    for f in &output.files {
        write_output(&dir.join(&f.name), f.contents.as_bytes())?;
    }
    let truth =
        serde_json::to_string_pretty(&output.truth).map_err(|e| CliError::Internal(e.into()))?;
    write_output(&dir.join("truth.json"), truth.as_bytes())?;
    println!(
        "{}: wrote {} files and truth.json to {}",
        args.scenario,
        output.files.len(),
        dir.display()
    );
    for f in &output.files {
        println!("  {}", dir.join(&f.name).display());
    }
    Ok(())
}
