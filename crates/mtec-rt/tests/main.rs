//! The integration tests of mtec-rt, one test binary: each file is a module (a binary per
//! file linked the crate and its dependencies once per file, 93 times over the workspace,
//! which cost CI minutes). Run one file's tests with
//! `cargo test -p mtec-rt --test integration <file>::`.

mod abi;
mod c_header;
mod header;
