//! `mtec`: the command-line front of the toolkit. Each subcommand lives in `cmd/<name>.rs` and
//! only wires files to the library crates; all numerical work happens in the libraries.

mod cmd;
mod error;
mod inputs;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

const WORKFLOW: &str = "\
mtec makes CNC machine tools more accurate: it measures, identifies, models and compensates their
geometric and thermal errors.

The workflow, and the commands for each step:
  simulate      a virtual machine with a known truth writes measurement files to practise on
  volumetric    volumetric error Ex, Ey, Ez of the tool tip at commanded points (HTM or POE)
  map           volumetric error maps: fit a grid (trilinear) and evaluate it at points
  compensate    compensation: controller tables (`compensate table`) from an error model

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
    /// Simulate measurements on the virtual machine (known truth).
    Simulate(cmd::simulate::Args),
    /// Volumetric error at commanded points (HTM or POE, exact or first-order).
    Volumetric(cmd::volumetric::Args),
    /// Volumetric error maps: `map fit` (grid CSV -> map JSON), `map eval` (errors at points).
    Map(cmd::map::Args),
    /// Compensation from an error model: `compensate table` (controller tables).
    Compensate(CompensateArgs),
}

#[derive(clap::Args)]
struct CompensateArgs {
    #[command(subcommand)]
    command: CompensateCommand,
}

#[derive(Subcommand)]
enum CompensateCommand {
    /// Controller compensation tables (LinuxCNC, Siemens CEC/LEC, Fanuc, Heidenhain, Beckhoff).
    #[command(long_about = cmd::compensate_table::HELP)]
    Table(cmd::compensate_table::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: Result<(), error::CliError> = match cli.command {
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Volumetric(a) => cmd::volumetric::run(a),
        Command::Map(a) => cmd::map::run(a),
        Command::Compensate(c) => match c.command {
            CompensateCommand::Table(a) => cmd::compensate_table::run(a),
        },
    };
    error::exit(result)
}
