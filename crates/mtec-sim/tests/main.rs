//! The integration tests of mtec-sim, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-sim --test integration <file>::`.

mod geometric;
mod nine_line_independent;
