//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod compensate_table;
pub mod map;
pub mod simulate;
pub mod volumetric;
