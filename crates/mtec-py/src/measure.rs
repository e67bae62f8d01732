//! ISO 230-2 positioning statistics (mtec-measure).

use crate::columns::read_table;
use crate::convert::to_py;
use crate::errors::{internal, Result};
use mtec_measure::{evaluate_iso230_2, vdi3441, PositioningData};
use pyo3::prelude::*;
use serde_json::json;

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
