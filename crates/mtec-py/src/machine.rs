//! The machine error model with a state (`mtec.machine-error/1`): built from a geometric model
//! and fitted thermal models, and a recorded day replayed through the real-time code path; the
//! jobs of `mtec machine build` and `mtec machine replay`.

use crate::convert::{matrix, serde_to_py};
use crate::errors::{refuse_stdout, Result};
use mtec_workflow::ops::machine::{self as op, BuildOptions, Part, ReplayOptions};
use numpy::PyArray1;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Builds a machine error model file: the library behind `mtec machine build`.
///
/// `output` is the machine file (`mtec.machine-error/1`; its paths are written relative to
/// it). `geometric` a static model (map, kinematic model, BPNN); `thermal` the thermal parts,
/// each `"AXIS=MODEL.json"` or `"AXIS=MODEL.json,sign=-1"` as the CLI's `--thermal` (sign 1:
/// the model's target is the tool's displacement relative to the workpiece). The training
/// envelope of each part (the range of every input; outside it the thermal correction fades
/// over `fade_c` °C for temperatures and `fade_other` of the range for other inputs) comes
/// from the model files, or from `data` (the log they were fitted on) with its `guard` columns
/// guarding every part.
///
/// Returns the machine file as written, as a dict (`geometric`, `thermal` with each part's
/// `axis`, `sign`, `model`, `envelope`, `fade`).
///
/// >>> import mtec, numpy as np, tempfile, os
/// >>> d = tempfile.mkdtemp()
/// >>> t = np.arange(0.0, 240.0, 2.0)
/// >>> s1 = 20 + 5 * (1 - np.exp(-t / 60))
/// >>> _ = mtec.thermal_fit({"time_min": t, "s1_c": s1, "dz_um": 2 * (s1 - 20)}, "dz_um",
/// ...                      "mlr", out=os.path.join(d, "dz.json"))
/// >>> m = mtec.machine_build(os.path.join(d, "machine.json"),
/// ...                        thermal=["z=" + os.path.join(d, "dz.json")])
/// >>> part = m["thermal"][0]
/// >>> part["axis"], part["model"], [round(v, 3) for v in part["envelope"]["s1_c"]]
/// ('z', 'dz.json', [20.0, 24.905])
#[pyfunction]
#[pyo3(signature = (output, *, geometric = None, thermal = Vec::new(), data = None,
    guard = Vec::new(), fade_c = None, fade_other = None))]
#[allow(clippy::too_many_arguments)]
pub fn machine_build<'py>(
    py: Python<'py>,
    output: PathBuf,
    geometric: Option<PathBuf>,
    thermal: Vec<String>,
    data: Option<PathBuf>,
    guard: Vec<String>,
    fade_c: Option<f64>,
    fade_other: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let build = || -> Result<Bound<'py, PyAny>> {
        refuse_stdout(&output, "output")?;
        let defaults = BuildOptions::new(geometric, Part::parse_all(&thermal)?, &output);
        let opts = BuildOptions {
            data,
            guard,
            fade_c: fade_c.unwrap_or(defaults.fade_c),
            fade_other: fade_other.unwrap_or(defaults.fade_other),
            ..defaults
        };
        let outcome = py.detach(|| op::build(&opts, &mut mtec_workflow::Collect::default()))?;
        serde_to_py(py, &outcome.file)
    };
    Ok(build()?)
}

/// Compensates a recorded day through the real-time code path: the library behind `mtec
/// machine replay`.
///
/// `model` is any model file mtec compensates with (a machine error model follows the state),
/// `state` the controller's state log (CSV: `time_min` and the model's state inputs), `probes`
/// the probe readings of the day (CSV: `time_min,[probe,]x_mm,y_mm,z_mm,ex_um,ey_um,ez_um`,
/// actual minus commanded). Each reading is corrected with the state at its time, as the
/// controller component would have, and compared before and after. `output` also writes every
/// reading as the CLI's CSV.
///
/// Returns the document `mtec machine replay --json` prints (`mtec.machine-replay/1`: per
/// component and for the vector `rms_before_um`, `rms_after_um`, `max_before_um`,
/// `max_after_um`, `compensation_rate`, `worst_reduction`; `worse`, `faded`, ...) and
/// `samples`: every reading as arrays (`time_min`, `probe`, `position_mm`, `before_um`,
/// `correction_um`, `after_um` as (N, 3), `thermal_weight`, `outside`).
///
/// >>> import mtec, tempfile, os
/// >>> d = mtec.simulate("production-day", tempfile.mkdtemp())
/// >>> dz = os.path.join(os.path.dirname(d["train.csv"]), "dz.json")
/// >>> _ = mtec.thermal_fit(d["train.csv"], "dz_um", "heat-input", out=dz)
/// >>> machine = os.path.join(os.path.dirname(dz), "machine.json")
/// >>> _ = mtec.machine_build(machine, thermal=["z=" + dz])
/// >>> r = mtec.machine_replay(machine, d["day-state.csv"], d["day-probes.csv"])
/// >>> r["format"], r["samples"]["after_um"].shape[1], r["z"]["rms_after_um"] < r["z"]["rms_before_um"]
/// ('mtec.machine-replay/1', 3, True)
#[pyfunction]
#[pyo3(signature = (model, state, probes, *, output = None))]
pub fn machine_replay<'py>(
    py: Python<'py>,
    model: PathBuf,
    state: PathBuf,
    probes: PathBuf,
    output: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let replay = || -> Result<Bound<'py, PyAny>> {
        if let Some(o) = &output {
            refuse_stdout(o, "output")?;
        }
        let opts = ReplayOptions {
            model,
            state,
            probes,
            output,
        };
        let outcome = py.detach(|| op::replay(&opts, &mut mtec_workflow::Collect::default()))?;
        let doc = serde_to_py(py, &outcome)?;
        let s = &outcome.samples;
        let col = |f: fn(&mtec_comp::replay::ReplaySample) -> f64| -> Vec<f64> {
            s.iter().map(f).collect()
        };
        let rows = |f: fn(&mtec_comp::replay::ReplaySample) -> [f64; 3]| -> Vec<Vec<f64>> {
            s.iter().map(|r| f(r).to_vec()).collect()
        };
        let samples = pyo3::types::PyDict::new(py);
        samples.set_item("time_min", PyArray1::from_vec(py, col(|r| r.time_min)))?;
        samples.set_item(
            "probe",
            s.iter().map(|r| r.probe.clone()).collect::<Vec<_>>(),
        )?;
        samples.set_item("position_mm", matrix(py, &rows(|r| r.position_mm), 3)?)?;
        samples.set_item("before_um", matrix(py, &rows(|r| r.before_um), 3)?)?;
        samples.set_item("correction_um", matrix(py, &rows(|r| r.correction_um), 3)?)?;
        samples.set_item("after_um", matrix(py, &rows(|r| r.after_um), 3)?)?;
        samples.set_item(
            "thermal_weight",
            PyArray1::from_vec(py, col(|r| r.thermal_weight)),
        )?;
        samples.set_item(
            "outside",
            s.iter().map(|r| r.outside.clone()).collect::<Vec<_>>(),
        )?;
        doc.set_item("samples", samples)?;
        Ok(doc)
    };
    Ok(replay()?)
}
