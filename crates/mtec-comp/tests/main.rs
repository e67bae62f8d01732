//! The integration tests of mtec-comp, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-comp --test integration <file>::`.

mod bidirectional_tables;
mod gcode_issue15;
mod gcode_offsets_state;
mod gcode_path_bound;
mod gcode_properties;
mod gcode_real_programs;
mod gcode_rewrite;
mod gcode_rotary;
mod gcode_support;
mod gcode_vm;
mod kinematic_file;
mod machine_state;
mod map_compensation;
mod map_grid_csv;
mod map_rt_noalloc;
mod map_scipy;
mod map_vm_truth;
mod production_day;
mod rotary_virtual_machine;
mod table_golden;
mod table_vm_signs;
mod thermal_offset;
