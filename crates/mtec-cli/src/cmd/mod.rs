//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod circular;
pub mod iso230_2;
pub mod simulate;
pub mod volumetric;
