//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod identify;
pub mod identify_lines;
pub mod simulate;
pub mod volumetric;
