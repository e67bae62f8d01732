//! `mtec compensate`: the group of compensation outputs.

use crate::help::text;

#[derive(clap::Subcommand)]
pub enum Command {
    /// Rewrite an NC program (G-code) so the machine reaches the programmed points.
    #[command(long_about = text!("compensate_gcode.long_about"))]
    Gcode(super::compensate_gcode::Args),
    /// Controller compensation tables (LinuxCNC, Siemens CEC/LEC, Fanuc, Heidenhain, Beckhoff).
    #[command(long_about = text!("compensate_table.help"))]
    Table(super::compensate_table::Args),
    /// The work-offset update (or Siemens temperature-compensation data) for the thermal state now.
    #[command(name = "thermal-offset", long_about = text!("compensate_thermal_offset.help"))]
    ThermalOffset(super::compensate_thermal_offset::Args),
}
