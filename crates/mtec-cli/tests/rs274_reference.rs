//! LinuxCNC's own interpreter as the independent reference for `mtec compensate gcode`
//! (issue 15): `tests/rs274/run_all.py` compensates every real program in
//! `../shared/data/gcode/linuxcnc` and every hand-written case in `tests/rs274/cases` with
//! non-zero maps, runs `rs274 -g` on the original and the compensated program and checks that
//! the compensated path, displaced by the model's error, lies on the nominal path within the
//! documented bound. A refused program is not a failure; a wrong one is.
//!
//! Without `rs274` on PATH the test prints a note and passes, except in CI (`CI` set), where the
//! interpreter is required (`.ci/run` installs it).

use std::path::{Path, PathBuf};
use std::process::Command;

/// Maps used here (the driver has two more, `smooth` and `clamp`, for a longer run by hand):
/// `tilt` keeps arcs as arcs, the bumps test splitting; together they stay within ~60 s.
const MAPS: &str = "tilt,bump-line,bump-arc";
const MIN_CASES: usize = 40;

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .map(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
        .unwrap_or(false)
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// `shared/data/gcode/linuxcnc` beside the repository (or beside one of its parents, for a
/// git worktree), or `MTEC_SHARED_GCODE`.
fn shared_programs(root: &Path) -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("MTEC_SHARED_GCODE") {
        return Some(PathBuf::from(dir));
    }
    // `$MTEC_SHARED_DIR` as the other tests of the real programs read it, else beside a parent
    let from_env = std::env::var_os("MTEC_SHARED_DIR")
        .map(|d| PathBuf::from(d).join("data/gcode/linuxcnc"))
        .filter(|d| d.is_dir());
    from_env.or_else(|| {
        root.ancestors()
            .skip(1)
            .map(|a| a.join("shared/data/gcode/linuxcnc"))
            .find(|d| d.is_dir())
    })
}

/// The number in `text` just before `word` on the line starting with `prefix`.
fn count_before(output: &str, prefix: &str, word: &str) -> Option<usize> {
    let line = output.lines().rev().find(|l| l.starts_with(prefix))?;
    let words: Vec<&str> = line.split_whitespace().collect();
    let k = words
        .iter()
        .position(|w| w.trim_end_matches([',', ';']) == word)?;
    words.get(k.checked_sub(1)?)?.parse().ok()
}

/// Whether rs274 and python3 are there; in CI they must be.
fn reference_available() -> bool {
    let in_ci = std::env::var_os("CI").is_some();
    for tool in ["rs274", "python3"] {
        if !on_path(tool) {
            assert!(
                !in_ci,
                "rs274 is required in CI: apt-get install linuxcnc-uspace ({tool} not on PATH)"
            );
            eprintln!("note: {tool} not on PATH, LinuxCNC reference test skipped");
            return false;
        }
    }
    true
}

/// The checker itself: exact compensations of a constant error pass, 3 um off fails, and
/// G18 arcs turn the way LinuxCNC turns them (`tests/rs274/selftest.py`, no mtec involved).
#[test]
fn the_reference_checker_accepts_right_and_rejects_wrong_programs() {
    if !reference_available() {
        return;
    }
    let out = Command::new("python3")
        .arg(repo_root().join("tests/rs274/selftest.py"))
        .output()
        .expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "checker self-test failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn every_compensated_program_follows_the_nominal_path_in_rs274() {
    if !reference_available() {
        return;
    }
    let in_ci = std::env::var_os("CI").is_some();
    let root = repo_root();
    let shared = shared_programs(&root);
    assert!(
        shared.is_some() || !in_ci,
        "the real programs (../shared/data/gcode/linuxcnc) are required in CI"
    );
    let mut cmd = Command::new("python3");
    cmd.arg(root.join("tests/rs274/run_all.py")).args([
        "--mtec",
        env!("CARGO_BIN_EXE_mtec"),
        "--maps",
        MAPS,
    ]);
    if let Some(dir) = &shared {
        cmd.arg("--shared").arg(dir);
    }
    let out = cmd.output().expect("python3 runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");

    let failed = count_before(&stdout, "", "failed");
    assert_eq!(
        failed,
        Some(0),
        "wrong compensated programs or checker crashes (exit {:?}):\n{stdout}\n{stderr}",
        out.status.code()
    );
    assert!(out.status.success(), "driver failed:\n{stdout}\n{stderr}");
    let cases = count_before(&stdout, "programs:", "cases").unwrap_or(0);
    assert!(
        cases >= MIN_CASES,
        "the checker ran on {cases} hand-written cases, expected at least {MIN_CASES}"
    );
    if let Some(dir) = &shared {
        let expected = std::fs::read_dir(dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .map(|e| e.path().extension().is_some_and(|x| x == "ngc"))
                    .unwrap_or(false)
            })
            .count();
        let real = count_before(&stdout, "programs:", "real").unwrap_or(0);
        assert_eq!(real, expected, "every real program must be run");
    }
}
