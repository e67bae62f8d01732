//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod identify_ballbar;
pub mod simulate;
pub mod volumetric;
