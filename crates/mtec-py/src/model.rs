//! The volumetric error of a machine with an error set at commanded poses (mtec-model).

use crate::columns::{as_path, path_arg, read_table};
use crate::convert::matrix;
use crate::errors::{usage, Result, ARRAYS};
use mtec_io::{InputError, Table};
use mtec_model::{Axis, Formalism, Machine, Order, VolumetricModel};
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::path::Path;

// the readers the CLI and the workflow use
pub use mtec_workflow::inputs::{pose_column, read_errors, read_machine};

/// A pose coordinate outside its axis' travel is refused: the error functions are not known there.
fn check_travel(
    machine: &Machine,
    a: Axis,
    v: f64,
    name: &str,
    at: (&Path, usize, usize),
) -> std::result::Result<(), InputError> {
    let [lo, hi] = machine.travel(a);
    let tol = 1e-9 * (hi - lo).abs().max(1.0);
    if !v.is_finite() {
        return Err(InputError::at(
            at.0,
            at.1,
            at.2,
            format!("{name} is {v}: not a finite number"),
        ));
    }
    if v < lo - tol || v > hi + tol {
        return Err(InputError::at(
            at.0,
            at.1,
            at.2,
            format!("{name} = {v} is outside the travel [{lo}, {hi}] of axis {a}"),
        ));
    }
    Ok(())
}

/// Poses from a table with one pose column per machine axis (`x_mm`, ..., `c_deg`).
fn poses_from_table(
    t: &Table,
    machine: &Machine,
) -> std::result::Result<Vec<Vec<f64>>, InputError> {
    let cols: Vec<usize> = machine
        .axes
        .iter()
        .map(|a| t.column(&pose_column(*a)))
        .collect::<std::result::Result<_, _>>()?;
    let mut out = Vec::with_capacity(t.rows.len());
    for row in &t.rows {
        let mut q = Vec::with_capacity(cols.len());
        for (&c, &a) in cols.iter().zip(&machine.axes) {
            let v = t.cell_f64(row, c)?;
            check_travel(machine, a, v, &t.header[c], (&t.path, row.line, c + 1))?;
            q.push(v);
        }
        out.push(q);
    }
    Ok(out)
}

/// Poses from an (N, number of axes) array, columns in the machine's axis order.
fn poses_from_array(arr: PyReadonlyArray2<'_, f64>, machine: &Machine) -> Result<Vec<Vec<f64>>> {
    let a = arr.as_array();
    let names: Vec<String> = machine.axes.iter().map(|x| pose_column(*x)).collect();
    if a.ncols() != machine.axes.len() {
        return Err(usage(format!(
            "`points` has {} columns; this machine has {} axes ({}): one column per axis, in that order",
            a.ncols(),
            machine.axes.len(),
            names.join(", ")
        )));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (i, row) in a.rows().into_iter().enumerate() {
        for (j, (&v, &ax)) in row.iter().zip(&machine.axes).enumerate() {
            check_travel(machine, ax, v, &names[j], (Path::new(ARRAYS), i + 1, j + 1))?;
        }
        out.push(row.to_vec());
    }
    Ok(out)
}

/// The formalism and order of a form name, as `mtec volumetric --form` spells them.
fn form_of(form: &str) -> Result<(Formalism, Order)> {
    Ok(match form {
        "htm-exact" => (Formalism::Htm, Order::Exact),
        "htm-first" => (Formalism::Htm, Order::FirstOrder),
        "poe-exact" => (Formalism::Poe, Order::Exact),
        "poe-first" => (Formalism::Poe, Order::FirstOrder),
        other => {
            return Err(usage(format!(
                "form `{other}`: expected htm-exact, htm-first, poe-exact or poe-first"
            )))
        }
    })
}

/// The volumetric error (tool tip relative to the workpiece) of a machine with an error set at
/// commanded poses.
///
/// `machine` is the machine TOML, `errors` an error set (`mtec.errors/1`, e.g. written by
/// `identify_lines(errors_out=...)`, or a simulation's `truth.json`). `points` is an
/// (N, number of axes) array in the machine's axis order (mm, degrees for rotary axes), or a CSV
/// path / mapping with one pose column per axis (`x_mm`, `y_mm`, `z_mm`, `c_deg`, ...). A pose
/// outside an axis' travel is refused (`mtec.InputError` at its row and column). `form` is the
/// kinematic formalism and order: `htm-exact` (default), `htm-first`, `poe-exact`, `poe-first`.
///
/// Returns the (N, 3) array of `ex_um, ey_um, ez_um`, the numbers `mtec volumetric` prints; with
/// `orientation=True` a tuple of that and the (N, 3) orientation error in µrad (rotation vector
/// about X, Y, Z).
///
/// >>> import mtec, numpy as np, tempfile
/// >>> d = mtec.simulate("vmc-9line", tempfile.mkdtemp(), seed=1)
/// >>> e = mtec.volumetric(d["machine.toml"], d["truth.json"], np.array([[500.0, 700.0, 250.0]]))
/// >>> e.shape
/// (1, 3)
#[pyfunction]
#[pyo3(signature = (machine, errors, points, form = "htm-exact", orientation = false))]
pub fn volumetric<'py>(
    py: Python<'py>,
    machine: &Bound<'py, PyAny>,
    errors: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    form: &str,
    orientation: bool,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(run(py, machine, errors, points, form, orientation)?)
}

fn run<'py>(
    py: Python<'py>,
    machine: &Bound<'py, PyAny>,
    errors: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
    form: &str,
    orientation: bool,
) -> Result<Bound<'py, PyAny>> {
    let (f, o) = form_of(form)?;
    let m = read_machine(&path_arg(machine, "machine")?)?;
    let e = read_errors(&path_arg(errors, "errors")?)?;
    let poses = if as_path(points)?.is_some() || points.hasattr("keys")? {
        poses_from_table(&read_table(points, "points")?, &m)?
    } else {
        let np = py.import("numpy")?;
        let arr = np.call_method1("asarray", (points, np.getattr("float64")?))?;
        let ndim: usize = arr.getattr("ndim")?.extract()?;
        if ndim != 2 {
            return Err(usage(format!(
                "`points` must be an (N, {}) array, it has {ndim} dimensions",
                m.axes.len()
            )));
        }
        poses_from_array(arr.extract::<PyReadonlyArray2<f64>>()?, &m)?
    };
    let (pos, rot): (Vec<Vec<f64>>, Vec<Vec<f64>>) = py.detach(|| {
        let vm = VolumetricModel::new(&m, &e);
        poses
            .iter()
            .map(|q| {
                let v = vm.error(q, f, o);
                (v.position_um.to_vec(), v.orientation_urad.to_vec())
            })
            .unzip()
    });
    let pos = matrix(py, &pos, 3)?.into_any();
    if orientation {
        let rot = matrix(py, &rot, 3)?.into_any();
        Ok(PyTuple::new(py, [pos, rot])?.into_any())
    } else {
        Ok(pos)
    }
}
