//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.
pub mod compensate_gcode;
pub mod model_loader;
