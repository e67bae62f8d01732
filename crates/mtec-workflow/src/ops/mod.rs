//! One module per job of the `mtec` command.

pub mod compensate_gcode;
pub mod map;
