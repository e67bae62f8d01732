//! The README's five-minute tour, run verbatim in a fresh folder (issue 24): every line after the
//! first is given to bash as written, with `set -e` so a failing line fails the test. The first
//! line builds the release binary and puts it on PATH; here the binary under test is put on
//! PATH instead, and the test checks that line is still the one it replaces.

use std::path::Path;
use std::process::Command;

const BUILD_LINE: &str = "cargo build --release && export PATH=$PWD/target/release:$PATH";

/// The lines of the first code block after the heading `## A five-minute tour`.
fn tour(readme: &str) -> Vec<String> {
    let start = readme
        .find("## A five-minute tour")
        .expect("README has the tour");
    let rest = &readme[start..];
    let open = rest.find("\n```\n").expect("the tour has a code block") + 5;
    let close = open + rest[open..].find("\n```").expect("the code block ends");
    rest[open..close].lines().map(str::to_string).collect()
}

#[test]
fn the_readme_tour_runs_verbatim_in_a_fresh_folder() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let lines = tour(&readme);
    assert!(lines.len() > 20, "the tour has {} lines", lines.len());
    assert_eq!(lines[0], BUILD_LINE, "the tour's first line changed");
    let bin = Path::new(env!("CARGO_BIN_EXE_mtec")).parent().unwrap();
    let script = format!(
        "set -euo pipefail\nexport PATH={}:$PATH\n{}\n",
        bin.display(),
        lines[1..].join("\n")
    );
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new("bash")
        .arg("-c")
        .arg(&script)
        .current_dir(dir.path())
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "the tour failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    // what the last steps promise is there
    let tour_dir = dir.path().join("mtec-tour");
    for f in [
        "d/errors.json",
        "t/model.json",
        "g/map.json",
        "part-compensated.ngc",
        "x.comp",
        "mtec-demo/report.html",
        "results/report.html",
    ] {
        assert!(tour_dir.join(f).is_file(), "{f} was not written");
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.lines().any(|l| l.starts_with("G10 L2 P1 X-312.4")),
        "no work-offset update in:\n{stdout}"
    );
}
