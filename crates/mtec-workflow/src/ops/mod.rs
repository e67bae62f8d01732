//! One module per job of the `mtec` command.

pub mod circular;
pub mod compensate_gcode;
pub mod compensate_table;
pub mod compensate_thermal_offset;
pub mod identify_ballbar;
pub mod identify_lines;
pub mod iso230_2;
pub mod machine;
pub mod map;
pub mod selective;
pub mod sensitivity;
pub mod simulate;
pub mod thermal;
pub mod volumetric;
