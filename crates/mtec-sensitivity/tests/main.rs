//! The integration tests of mtec-sensitivity, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-sensitivity --test integration <file>::`.

mod error_model;
mod intervals;
mod methods;
mod salib_fixtures;
