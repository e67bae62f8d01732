//! The integration tests of mtec-io, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-io --test integration <file>::`.

mod outputs;
mod random_text;
mod stream;
