//! The virtual machine's scenarios (mtec-sim): measurement files with a known truth, for
//! examples, tests and trying the module without a machine.

use crate::errors::{internal, usage, Result};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Simulates a scenario's measurement files and its `truth.json` into the folder `out`, as
/// `mtec simulate SCENARIO --out OUT --seed SEED` does (the same seed gives the same bytes).
///
/// Scenarios: `vmc-9line`, `volumetric-grid`, `iso230-2`, `circular-test`, `circular-test-arc`,
/// `spindle-sensors`, `feed-axis-ambient`, `production-day`, `dbb-rotary` (also named
/// `dbb-rotary-constant`), `dbb-rotary-realistic` (docs/formats.md, "Simulation outputs").
/// Returns a dict of file name to path (`str`).
///
/// >>> import mtec, tempfile
/// >>> files = mtec.simulate("iso230-2", tempfile.mkdtemp(), seed=1)
/// >>> sorted(files)
/// ['iso230-2.csv', 'truth.json']
#[pyfunction]
#[pyo3(signature = (scenario, out, seed = 1))]
pub fn simulate<'py>(
    py: Python<'py>,
    scenario: &str,
    out: PathBuf,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    Ok(run(py, scenario, out, seed)?)
}

fn run<'py>(
    py: Python<'py>,
    scenario: &str,
    out: PathBuf,
    seed: u64,
) -> Result<Bound<'py, PyDict>> {
    let output = py
        .detach(|| mtec_sim::run_scenario(scenario, seed))
        .map_err(|e| usage(e.to_string()))?;
    let truth = serde_json::to_string_pretty(&output.truth).map_err(internal)?;
    let files = output
        .files
        .iter()
        .map(|f| (f.name.as_str(), f.contents.as_str()))
        .chain([("truth.json", truth.as_str())]);
    let d = PyDict::new(py);
    for (name, contents) in files {
        let path = out.join(name);
        mtec_io::write_output(&path, contents.as_bytes())?;
        d.set_item(name, path.display().to_string())?;
    }
    Ok(d)
}
