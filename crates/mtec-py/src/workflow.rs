//! The project workflow (`mtec run PROJECT.toml`) in the Python module: `mtec.run_project`.
//!
//! It calls `mtec_workflow::project::run` in-process, the call `mtec run` makes, so a project
//! run from Python writes the same files as from the command line (python/tests/
//! test_workflow.py compares them byte for byte). The run releases the GIL; its warnings are
//! collected and then issued as Python warnings (`warnings.warn`), and returned.

use crate::convert::serde_to_py;
use crate::errors::Result;
use mtec_workflow::project::{self, RunOptions};
use mtec_workflow::Collect;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Runs the whole pipeline of a project file and writes report.html: the library behind
/// `mtec run PROJECT.toml`.
///
/// `project` is the project file (TOML, docs/formats.md "Project TOML"; paths in it are
/// relative to it); `out` the output folder (default: `<project name>-results` beside the
/// project file). Every stage runs in-process; a stage that fails raises its located error
/// (`mtec.InputError` with file, line and column, or `ValueError`) after report.html is written
/// with the failure as its last section.
///
/// Returns a dict: `format` (`mtec.run/1`), `out`, `report` (the path of report.html),
/// `outputs` (every file written, in order) and `warnings` (also issued with `warnings.warn`).
///
/// >>> import mtec, os, tempfile
/// >>> d = tempfile.mkdtemp()
/// >>> rows = [f"{t},{r},{dr},{t / 100 + r + (0.5 if dr == '-' else 0.0)}"
/// ...         for r in range(1, 6) for dr in ("+", "-") for t in (0, 100, 200, 300, 400)]
/// >>> _ = open(os.path.join(d, "runs.csv"), "w").write(
/// ...     "target_mm,run,direction,deviation_um\n" + "\n".join(rows) + "\n")
/// >>> _ = open(os.path.join(d, "p.toml"), "w").write('[[iso230_2]]\ndata = "runs.csv"\n')
/// >>> r = mtec.run_project(os.path.join(d, "p.toml"), out=os.path.join(d, "results"))
/// >>> r["format"], [os.path.basename(f) for f in r["outputs"]]
/// ('mtec.run/1', ['iso230-2-runs.json', 'report.html'])
#[pyfunction]
#[pyo3(signature = (project, out = None))]
pub fn run_project<'py>(
    py: Python<'py>,
    project: PathBuf,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(run(py, project, out)?)
}

fn run(py: Python<'_>, project: PathBuf, out: Option<PathBuf>) -> Result<Bound<'_, PyAny>> {
    let opts = RunOptions {
        project,
        out,
        title: None,
    };
    let mut obs = Collect::default();
    let done = py.detach(|| project::run(&opts, &mut obs));
    let warn = py.import("warnings")?.getattr("warn")?;
    for w in &obs.warnings {
        warn.call1((w.as_str(),))?;
    }
    let done = done?;
    let dict = serde_to_py(py, &done)?;
    dict.set_item("outputs", &done.outputs)?;
    dict.set_item("warnings", &obs.warnings)?;
    Ok(dict)
}
