//! The integration tests of mtec-identify, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-identify --test integration <file>::`.

mod ballbar_dbb;
mod compensation_rate;
mod lines_bad_input;
mod lines_identifiability;
mod lines_realistic;
mod lines_recovery;
mod lines_reference;
mod support;
