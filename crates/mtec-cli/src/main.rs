//! `mtec`: the command-line front of the toolkit. Each subcommand lives in `cmd/<name>.rs` and
//! only wires files to the library crates; all numerical work happens in the libraries.

mod cmd;
mod error;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

const WORKFLOW: &str = "\
mtec makes CNC machine tools more accurate: it measures, identifies, models and compensates their
geometric and thermal errors.

The workflow, and the commands for each step:
  simulate      a virtual machine with a known truth writes measurement files to practise on
  volumetric    volumetric error Ex, Ey, Ez of the tool tip at commanded points (HTM or POE)
  compensate gcode  rewrite an NC program so every commanded point is corrected

Units: positions mm, angles deg, linear errors um, angular errors urad, temperatures C, time min.
Every CSV column name carries its unit suffix (x_mm, ex_um, ...). Exit codes: 0 success,
2 bad input (the message names file, line and column), 1 internal failure.";

#[derive(Parser)]
#[command(name = "mtec", version, about = "Measure, identify, model and compensate machine-tool errors", long_about = WORKFLOW)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compensation outputs: corrected NC programs, controller tables.
    #[command(subcommand)]
    Compensate(CompensateCommand),
}

#[derive(Subcommand)]
enum CompensateCommand {
    Gcode(cmd::compensate_gcode::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: Result<(), error::CliError> = match cli.command {
        Command::Compensate(CompensateCommand::Gcode(a)) => cmd::compensate_gcode::run(a),
    };
    error::exit(result)
}
