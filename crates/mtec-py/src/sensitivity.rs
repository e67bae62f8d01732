//! Global sensitivity of a machine's volumetric error or of a test function, with a
//! confidence interval for every index (mtec-sensitivity, through `ops::sensitivity`).

use crate::convert::serde_to_py;
use crate::errors::{usage, Result};
use mtec_workflow::ops::sensitivity::{self as op, MethodKind, Options};
use mtec_workflow::Silent;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Sobol, EFAST or Morris indices with their confidence intervals: the library behind
/// `mtec sensitivity --json`, returned as the same dict (docs/formats.md, "Sensitivity result
/// JSON").
///
/// Give `function` (`"ishigami"`, `"sobol-g"`, `"linear"`) or `machine` and `stats` (TOML and
/// error-statistics CSV paths) with one pose `at` (axis positions), a `points` CSV path, or
/// `lhs_poses` poses by Latin hypercube over the travels (`--sampling lhs:N`).
/// `method` is `"efast"` (default; `samples` points per curve, default 1200, `resamples`
/// random-phase repetitions, default 10), `"sobol"` (`samples` base points, default 1024) or
/// `"morris"` (`samples` trajectories, default 100). Every index has the half width of its
/// interval at `conf_level` (`S1_conf`, `ST_conf`, `mu_star_conf`): EFAST's from the
/// repetitions, Sobol's and Morris's from `num_resamples` bootstrap replicates.
///
/// >>> import mtec
/// >>> r = mtec.sensitivity(function="ishigami", method="sobol", samples=1024, seed=3)
/// >>> r["conf_level"], len(r["S1"]), len(r["S1_conf"]), len(r["ST_conf"])
/// (0.95, 3, 3, 3)
/// >>> all(abs(s - a) <= c + 0.01 for s, a, c in zip(r["ST"], r["analytic"]["ST"], r["ST_conf"]))
/// True
#[pyfunction]
#[pyo3(signature = (*, function = None, machine = None, stats = None, method = "efast",
    samples = None, at = None, points = None, interference = 4, resamples = 10, levels = 4,
    num_resamples = 100, conf_level = 0.95, seed = 1, target_um = 25.0, coverage = 2.0,
    lhs_poses = None))]
#[allow(clippy::too_many_arguments)]
pub fn sensitivity<'py>(
    py: Python<'py>,
    function: Option<String>,
    machine: Option<PathBuf>,
    stats: Option<PathBuf>,
    method: &str,
    samples: Option<usize>,
    at: Option<Vec<f64>>,
    points: Option<PathBuf>,
    interference: usize,
    resamples: usize,
    levels: usize,
    num_resamples: usize,
    conf_level: f64,
    seed: u64,
    target_um: f64,
    coverage: f64,
    lhs_poses: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let method = MethodKind::from_name(method).ok_or_else(|| {
        usage(format!(
            "method `{method}`: expected \"efast\", \"sobol\" or \"morris\""
        ))
    })?;
    let opts = Options {
        machine,
        stats,
        function,
        method,
        samples,
        interference,
        resamples,
        levels,
        num_resamples,
        conf_level,
        seed,
        at,
        points,
        target_um,
        coverage,
        lhs_poses,
    };
    Ok(run(py, &opts)?)
}

fn run<'py>(py: Python<'py>, opts: &Options) -> Result<Bound<'py, PyAny>> {
    let done = py.detach(|| op::run(opts, &mut Silent))?;
    serde_to_py(py, &done)
}
