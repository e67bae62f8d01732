//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod sensitivity;
pub mod simulate;
pub mod volumetric;
