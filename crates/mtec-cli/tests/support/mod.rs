//! Shared by the CLI tests: run the built `mtec` binary, read its output, write a scenario's
//! files. (Each test crate uses part of it.)
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs the built `mtec` with `args`.
pub fn mtec(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
        .args(args)
        .output()
        .expect("mtec runs")
}

/// Standard output, then standard error, as text.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes every file of scenario `name` (seed `seed`) into `dir`.
pub fn write_scenario(name: &str, seed: u64, dir: &Path) {
    let out = mtec_sim::run_scenario(name, seed).unwrap();
    for f in out.files {
        std::fs::write(dir.join(&f.name), f.contents).unwrap();
    }
}

/// `mtec identify ballbar` on the `dbb-rotary` files in `dir` (setup.toml, dbb.csv, temps.csv),
/// writing into `dir/id`.
pub fn identify_ballbar(dir: &Path) -> Output {
    let p = |n: &str| dir.join(n).to_string_lossy().into_owned();
    mtec(&[
        "identify",
        "ballbar",
        "--setup",
        &p("setup.toml"),
        "--data",
        &p("dbb.csv"),
        "--temps",
        &p("temps.csv"),
        "--out",
        &p("id"),
    ])
}
