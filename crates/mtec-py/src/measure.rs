//! ISO 230-2 positioning statistics and ISO 230-4 circular tests (mtec-measure).

use crate::columns::read_table;
use crate::convert::{serde_to_py, to_py};
use crate::errors::{internal, Result};
use mtec_measure::{evaluate_iso230_2, vdi3441, PositioningData};
use mtec_workflow::ops::circular as circular_op;
use pyo3::prelude::*;
use serde_json::json;
use std::path::PathBuf;

/// ISO 230-2:2014 positioning statistics of a linear axis, and the VDI/DGQ 3441 values.
///
/// `data` is the run file (CSV path with `target_mm,run,direction,deviation_um`) or a mapping
/// with these four columns (`direction` holds `"+"` or `"-"`). Returns the document
/// `mtec iso230-2 --json` prints (`format` `mtec.iso230-2/1`): the axis values (`A_um`, `E_um`,
/// `R_um`, `B_um`, `M_um`, ... in µm), `targets` and `vdi3441["targets"]` as dicts of numpy
/// arrays (one entry per target position), `runs_up`, `runs_down` and `warnings` (what ISO 230-2
/// asks for that the data does not meet). Raises `mtec.InputError` at the offending row.
///
/// >>> import mtec
/// >>> r = mtec.iso230_2({"target_mm": [0, 10, 0, 10, 0, 10, 0, 10],
/// ...                    "run": [1, 1, 2, 2, 1, 1, 2, 2],
/// ...                    "direction": ["+", "+", "+", "+", "-", "-", "-", "-"],
/// ...                    "deviation_um": [1, 2, 3, 4, 0, 1, 1, 2]})
/// >>> r["B_um"], r["targets"]["mean_up_um"].tolist()
/// (1.5, [2.0, 3.0])
#[pyfunction]
#[pyo3(signature = (data))]
pub fn iso230_2<'py>(py: Python<'py>, data: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    Ok(run(py, data)?)
}

fn run<'py>(py: Python<'py>, data: &Bound<'py, PyAny>) -> Result<Bound<'py, PyAny>> {
    let table = read_table(data, "data")?;
    let runs = PositioningData::from_table(&table)?;
    let iso = evaluate_iso230_2(&runs);
    let vdi = vdi3441(&iso);
    // the document of `mtec iso230-2 --json`, without the corrections it was not asked for
    let mut doc = json!({
        "format": "mtec.iso230-2/1",
        "file": table.path.display().to_string(),
        "runs_up": iso.runs_up,
        "runs_down": iso.runs_down,
    });
    let obj = doc
        .as_object_mut()
        .ok_or_else(|| internal("not an object"))?;
    if let serde_json::Value::Object(axis) = serde_json::to_value(&iso.axis).map_err(internal)? {
        obj.extend(axis);
    }
    obj.insert(
        "targets".into(),
        serde_json::to_value(&iso.targets).map_err(internal)?,
    );
    obj.insert(
        "vdi3441".into(),
        serde_json::to_value(&vdi).map_err(internal)?,
    );
    obj.insert("warnings".into(), json!(runs.warnings));
    Ok(to_py(py, &doc)?)
}

/// An ISO 230-4 circular test of two linear axes (ballbar) and its diagnostics: the library
/// behind `mtec circular`.
///
/// `run` is the trace (CSV path with `angle_deg,direction,dl_um`, `direction` `ccw` or `cw`,
/// and header comments `# radius_mm = 100`, `# plane = XY`, `# feed_mm_min = 1000`; or a
/// mapping of those three columns). `radius_mm`, `plane` (`XY`, `YZ`, `ZX`), `feed_mm_min`
/// (needed for the servo mismatch in ms) override the header; arrays have no header, so they
/// need `radius_mm`. `arc_start_deg` and `arc_end_deg` (both or neither) evaluate a partial arc
/// traced ccw from start to end (at least 90°); `threshold_um` is the contribution from which a
/// fault is reported as present. `out` (a folder) also gets circular.json and polar.svg.
///
/// Returns the document `mtec circular --json` prints (`mtec.circular/1`): `radius_mm`,
/// `plane`, `samples`, `iso230_4` (circular deviation `G_um` of each direction and
/// bidirectional, hysteresis `H_um`, the least-squares circles) and `diagnostics` (the faults
/// ranked by contribution: backlash, lateral play, squareness, scale mismatch, straightness,
/// cyclic error, servo mismatch, ...).
///
/// >>> import mtec, numpy as np
/// >>> a = np.arange(0.0, 360.0, 1.0)
/// >>> dl = 3.0 * np.cos(np.radians(2 * a))       # an ellipse: ±3 µm
/// >>> r = mtec.circular({"angle_deg": np.concatenate([a, a]),
/// ...                    "direction": ["ccw"] * 360 + ["cw"] * 360,
/// ...                    "dl_um": np.concatenate([dl, dl])}, radius_mm=150.0)
/// >>> round(r["iso230_4"]["G_bidirectional_um"], 6), round(r["iso230_4"]["H_um"], 6)
/// (6.0, 0.0)
/// >>> f = r["diagnostics"]["faults"][0]      # 2·3 µm over 150 mm: 40 ppm between the axes
/// >>> f["id"], round(f["value"], 6), f["unit"]
/// ('scale_mismatch', 40.0, 'ppm')
#[pyfunction]
#[pyo3(signature = (run, *, radius_mm = None, plane = None, feed_mm_min = None,
    arc_start_deg = None, arc_end_deg = None, threshold_um = 0.3, out = None))]
#[allow(clippy::too_many_arguments)]
pub fn circular<'py>(
    py: Python<'py>,
    run: &Bound<'py, PyAny>,
    radius_mm: Option<f64>,
    plane: Option<String>,
    feed_mm_min: Option<f64>,
    arc_start_deg: Option<f64>,
    arc_end_deg: Option<f64>,
    threshold_um: f64,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let arc = [arc_start_deg, arc_end_deg];
    let given = CircularArgs {
        radius_mm,
        plane,
        feed_mm_min,
        arc,
        threshold_um,
        out,
    };
    Ok(evaluate_circular(py, run, given)?)
}

/// The keyword arguments of [`circular`].
struct CircularArgs {
    radius_mm: Option<f64>,
    plane: Option<String>,
    feed_mm_min: Option<f64>,
    arc: [Option<f64>; 2],
    threshold_um: f64,
    out: Option<PathBuf>,
}

fn evaluate_circular<'py>(
    py: Python<'py>,
    run: &Bound<'py, PyAny>,
    a: CircularArgs,
) -> Result<Bound<'py, PyAny>> {
    let table = read_table(run, "run")?;
    let opts = circular_op::Options {
        radius_mm: a.radius_mm,
        feed_mm_min: a.feed_mm_min,
        plane: a
            .plane
            .as_deref()
            .map(circular_op::parse_plane)
            .transpose()?,
        arc_deg: circular_op::arc_deg(a.arc[0], a.arc[1])?,
        threshold_um: a.threshold_um,
        out: a.out,
        ..circular_op::Options::new(&table.path)
    };
    let outcome = py.detach(|| circular_op::run_table(&table, &opts))?;
    serde_to_py(py, &outcome)
}
