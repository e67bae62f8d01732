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

/// The first of `names` found on PATH; `None` (with `note`) when none is there and `CI` is not
/// set. In CI it is required (`.ci/run` installs `package`): its absence fails the test.
pub fn tool_on_path(names: &[&str], package: &str, note: &str) -> Option<std::path::PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    let found = names.iter().find_map(|n| {
        std::env::split_paths(&path)
            .map(|d| d.join(n))
            .find(|p| p.is_file())
    });
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "{} (package {package}) is required in CI",
            names[0]
        );
        eprintln!(
            "note: {} not installed (package {package}): {note}",
            names[0]
        );
    }
    found
}

/// LinuxCNC's stand-alone interpreter `rs274` on PATH; `None` (with a note) when it is absent
/// and `CI` is not set (in CI it is required: `.ci/run` installs `linuxcnc-uspace`).
pub fn rs274() -> Option<std::path::PathBuf> {
    tool_on_path(&["rs274"], "linuxcnc-uspace", "check skipped")
}

/// `rs274 -g FILE` in a folder of its own that is also its HOME (rs274 maps
/// `$HOME/.tool.mmap`; two runs sharing it crash or read each other's tools). Returns the
/// canonical listing, or rs274's error text.
pub fn run_rs274(bin: &Path, file: &Path) -> Result<String, String> {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(bin)
        .current_dir(dir.path())
        .env("HOME", dir.path())
        .arg("-g")
        .arg(file)
        .output()
        .unwrap();
    if o.status.success() {
        Ok(String::from_utf8_lossy(&o.stdout).into_owned())
    } else {
        Err(text(&o))
    }
}
