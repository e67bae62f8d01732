//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod simulate;
pub mod volumetric;
pub mod compensate_table;
pub mod map;
