//! `mtec`: the command-line front of the toolkit. Each subcommand lives in `cmd/<name>.rs` and
//! only wires files to the library crates; all numerical work happens in the libraries.

mod choice;
mod cmd;
mod error;
mod help;
mod observer;

use clap::{Parser, Subcommand};
use help::text;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "mtec",
    version,
    about = "Measure, identify, model and compensate machine-tool errors",
    long_about = text!("main.workflow")
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    // Leaf commands take their about, long help and examples from their `Args` (a doc comment
    // here would replace them with one line).
    Simulate(cmd::simulate::Args),
    Volumetric(cmd::volumetric::Args),
    /// Identify error elements or error motions from measurements.
    #[command(subcommand)]
    Identify(Identify),
    #[command(name = "iso230-2")]
    Iso230_2(cmd::iso230_2::Args),
    Circular(cmd::circular::Args),
    /// Volumetric error maps: `map fit` (grid CSV -> map JSON), `map eval` (errors at points).
    Map(cmd::map::Args),
    /// Compensation outputs: corrected NC programs, controller tables.
    #[command(subcommand)]
    Compensate(cmd::compensate::Command),
    /// Thermal error models: ridge-trace sensor selection, MLR/ridge/exp-ambient fit, predict.
    Thermal(cmd::thermal::Args),
    /// The machine error model with a state: `machine build` (geometric + thermal models with
    /// their training envelopes), `machine replay` (a recorded day through the real-time path).
    Machine(cmd::machine::Args),
    Sensitivity(cmd::sensitivity::Args),
    Run(cmd::run::Args),
    Demo(cmd::demo::Args),
}

#[derive(Subcommand)]
enum Identify {
    /// Error elements of a 3-axis machine from line measurements (9-line method).
    #[command(long_about = text!("identify_lines.long_about"))]
    Lines(cmd::identify_lines::Args),
    /// Rotary-axis error motions from ballbar readings in five installation modes.
    #[command(long_about = text!("identify_ballbar.long_about"))]
    Ballbar(cmd::identify_ballbar::Args),
}

fn main() -> ExitCode {
    // Behave like other Unix tools when the reader of stdout goes away (`mtec ... | head`):
    // end quietly instead of panicking on a broken pipe.
    #[cfg(unix)]
    // SAFETY: resetting a signal disposition to its default before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result: Result<(), error::CliError> = match cli.command {
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::Volumetric(a) => cmd::volumetric::run(a),
        Command::Identify(Identify::Lines(a)) => cmd::identify_lines::run(a),
        Command::Identify(Identify::Ballbar(a)) => cmd::identify_ballbar::run(a),
        Command::Iso230_2(a) => cmd::iso230_2::run(a),
        Command::Circular(a) => cmd::circular::run(a),
        Command::Map(a) => cmd::map::run(a),
        Command::Compensate(cmd::compensate::Command::Gcode(a)) => cmd::compensate_gcode::run(a),
        Command::Compensate(cmd::compensate::Command::Table(a)) => cmd::compensate_table::run(a),
        Command::Compensate(cmd::compensate::Command::ThermalOffset(a)) => {
            cmd::compensate_thermal_offset::run(a)
        }
        Command::Thermal(a) => cmd::thermal::run(a),
        Command::Machine(a) => cmd::machine::run(a),
        Command::Sensitivity(a) => cmd::sensitivity::run(a),
        Command::Run(a) => cmd::run::run(a),
        Command::Demo(a) => cmd::demo::run(a),
    };
    // what the readers assumed about the input files (e.g. a spreadsheet export's dialect)
    for note in mtec_io::notes::take() {
        eprintln!("note: {note}");
    }
    error::exit(result)
}
