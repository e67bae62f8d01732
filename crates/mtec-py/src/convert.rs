//! Results to Python: the CLI's JSON documents as Python objects, lists of flat numeric records
//! as dicts of numpy arrays, and output files written through `mtec_io`.

use crate::errors::{internal, Result};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A JSON value as a Python object; a list of objects whose values are all numbers (the
/// per-target rows of ISO 230-2, the per-angle motions of a ballbar) becomes a dict of 1-D
/// `float64` arrays, one per key, in the order of the first record.
pub fn to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => match numeric_records(items) {
            Some(cols) => {
                let d = PyDict::new(py);
                for (k, col) in cols {
                    d.set_item(k, PyArray1::from_vec(py, col))?;
                }
                d.into_any()
            }
            None => {
                let l = PyList::empty(py);
                for x in items {
                    l.append(to_py(py, x)?)?;
                }
                l.into_any()
            }
        },
        Value::Object(map) => {
            let d = PyDict::new(py);
            for (k, x) in map {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// The columns of a non-empty list of objects with the same keys and only numeric values (a
/// JSON `null` is a NaN: serde_json writes non-finite numbers so).
fn numeric_records(items: &[Value]) -> Option<Vec<(String, Vec<f64>)>> {
    let first = items.first()?.as_object()?;
    if first.is_empty() {
        return None;
    }
    let mut cols: Vec<(String, Vec<f64>)> = first
        .keys()
        .map(|k| (k.clone(), Vec::with_capacity(items.len())))
        .collect();
    for it in items {
        let o = it.as_object()?;
        if o.len() != cols.len() {
            return None;
        }
        for (k, col) in cols.iter_mut() {
            let x = match o.get(k)? {
                Value::Number(n) => n.as_f64()?,
                Value::Null => f64::NAN,
                _ => return None,
            };
            col.push(x);
        }
    }
    // a list of all-null records is no table
    cols.iter()
        .any(|(_, c)| c.iter().any(|x| !x.is_nan()))
        .then_some(cols)
}

/// Any serialisable value as a Python object (see [`to_py`]).
pub fn serde_to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> Result<Bound<'py, PyAny>> {
    let value = serde_json::to_value(v).map_err(internal)?;
    Ok(to_py(py, &value)?)
}

/// Rows of equal length as an (N, M) `float64` array.
pub fn matrix<'py>(
    py: Python<'py>,
    rows: &[Vec<f64>],
    width: usize,
) -> Result<Bound<'py, PyArray2<f64>>> {
    if rows.is_empty() {
        return Ok(PyArray2::zeros(py, [0, width], false));
    }
    PyArray2::from_vec2(py, rows).map_err(internal)
}

/// Writes `bytes` to `out` through mtec-io (atomically; `-` is stdout), refusing to overwrite any
/// of `inputs` or a directory (a usage error).
pub fn write_output(out: &Path, inputs: &[PathBuf], bytes: &[u8]) -> Result<()> {
    let dest = mtec_io::OutputGuard::new(inputs).check(out)?;
    dest.write(bytes)?;
    Ok(())
}
