//! Every example project under `examples/` runs through `mtec run` and produces a report with a
//! plot for each stage it asks for.

use std::path::Path;
use std::process::Command;

/// Runs `mtec run` on an example project and checks exit 0, report.html, and that the report
/// has a section with at least one `<figure>` for each expected analysis stage (by the start of
/// its section title; `[compensation]` writes files and a table, no plot).
fn run_example(project: &str, stages: &[&str]) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let project = root.join(project);
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_mtec"))
        .arg("run")
        .arg(&project)
        .arg("--out")
        .arg(tmp.path())
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "mtec run {} failed ({:?}): {}",
        project.display(),
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(tmp.path().join("report.html")).expect("report.html");
    let sections: Vec<&str> = html.split("<section").skip(1).collect();
    for stage in stages {
        let mine: Vec<&&str> = sections
            .iter()
            .filter(|s| s.contains(&format!("<h2>{stage}")))
            .collect();
        assert!(
            !mine.is_empty(),
            "{}: no section `{stage}`",
            project.display()
        );
        for s in mine {
            assert!(
                s.contains("<figure"),
                "{}: section `{stage}` has no figure",
                project.display()
            );
        }
    }
    assert!(
        html.contains("<h2>Compensation outputs") || !stages.contains(&"Volumetric error map"),
        "{}: no compensation section",
        project.display()
    );
}

#[test]
fn vmc_example_runs() {
    run_example(
        "examples/vmc/project.toml",
        &[
            "Positioning (ISO 230-2)",
            "Identified geometric errors",
            "Global sensitivity",
            "Circular test (ISO 230-4)",
            "Thermal model: radial_um",
            "Volumetric error map",
        ],
    );
}

#[test]
fn fl_thermal_split_example_runs() {
    run_example(
        "examples/fl-thermal/project-split.toml",
        &["Thermal model: ch1_um"],
    );
}

#[test]
fn fl_thermal_full_example_runs() {
    run_example(
        "examples/fl-thermal/project.toml",
        &["Thermal model: ch1_um", "Thermal model: ch2_um"],
    );
}
