//! The integration tests of mtec-workflow, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-workflow --test integration <file>::`.

mod circular;
mod compensate_table;
mod compensate_table_iso230_2;
mod compensate_thermal_offset;
mod identify_ballbar;
mod identify_lines;
mod iso230_2;
mod machine;
mod map_eval;
mod selective;
mod sensitivity;
mod simulate;
mod thermal;
mod thermal_neural_log;
mod volumetric;
