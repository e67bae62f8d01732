//! The integration tests of mtec-thermal, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-thermal --test integration <file>::`.

mod forward;
mod heat_input;
mod methods;
mod reference;
mod scenarios;
mod state_space;
mod stream;
