//! Runs the bad-input corpus (`tests/bad-input/` at the repository root): every case must exit
//! with code 2, name what is wrong and where, never panic, and leave its inputs untouched.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/bad-input")
}

fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            m.insert(
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            );
        }
    }
    m
}

#[test]
fn every_bad_input_case_fails_cleanly_with_a_located_message() {
    let mut cases: Vec<PathBuf> = std::fs::read_dir(corpus())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    cases.sort();
    assert!(cases.len() >= 20, "the corpus has {} cases", cases.len());
    let mut failures = Vec::new();
    for case in &cases {
        let name = case.file_name().unwrap().to_string_lossy().into_owned();
        let args = std::fs::read_to_string(case.join("args")).unwrap();
        let mut expect = std::fs::read_to_string(case.join("expect")).unwrap();
        // a case of a cargo feature this build lacks must be refused for that reason
        let feature = std::fs::read_to_string(case.join("feature")).unwrap_or_default();
        if feature.trim() == "neural" && !cfg!(feature = "neural") {
            expect = "built without them\n--features neural".into();
        }
        let before = snapshot(case);
        let tmp = tempfile::tempdir().unwrap();
        // run in a copy so that outputs (if any) never land in the corpus
        for (f, bytes) in &before {
            std::fs::write(tmp.path().join(f), bytes).unwrap();
        }
        let out = Command::new(env!("CARGO_BIN_EXE_mtec"))
            .args(args.split_whitespace())
            .current_dir(tmp.path())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let after = snapshot(tmp.path());
        let mut problems = Vec::new();
        if out.status.code() != Some(2) {
            problems.push(format!("exit code {:?}, expected 2", out.status.code()));
        }
        if stderr.contains("panicked") {
            problems.push("panicked".into());
        }
        for line in expect.lines().filter(|l| !l.trim().is_empty()) {
            if !stderr.contains(line.trim()) {
                problems.push(format!("message lacks `{}`", line.trim()));
            }
        }
        for (f, bytes) in &before {
            if after.get(f) != Some(bytes) {
                problems.push(format!("input {f} was changed"));
            }
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{name}: {} | stderr: {}",
                problems.join("; "),
                stderr.trim()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
