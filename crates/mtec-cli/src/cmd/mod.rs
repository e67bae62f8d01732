//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod compensate_gcode;
pub mod compensate_table;
pub mod identify_ballbar;
pub mod identify_lines;
pub mod map;
pub mod model_loader;
pub mod sensitivity;
pub mod simulate;
pub mod thermal;
pub mod volumetric;

pub mod compensate;
