//! `mtec simulate SCENARIO --out DIR [--seed N]`: write a scenario's measurement files and truth.

use crate::error::CliError;
use mtec_io::write_output;
use std::path::PathBuf;

/// Simulate measurements on the virtual machine (known ground truth).
///
/// Writes the scenario's measurement files and `truth.json` (the errors the analysis should
/// find) into --out. The same seed always gives the same files.
///
/// Example:
///   mtec simulate vmc-9line --out d --seed 1
///   mtec identify lines --machine d/machine.toml --data d/lines.csv
#[derive(clap::Args, Debug)]
#[command(after_help = scenario_list())]
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
