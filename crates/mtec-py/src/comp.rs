//! Compensation (mtec-comp): volumetric error maps from a measured grid and their values at
//! points, and an NC program rewritten with an error model.

use crate::columns::{as_path, file_inputs, path_arg, read_table};
use crate::convert::write_output;
use crate::errors::{internal, usage, Result, ARRAYS};
use mtec_comp::gcode::{rewrite, GcodeError, OffsetsFile, OnUnsupported, RewriteOptions, Units};
use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_comp::{advance_through_log, load_error_model, ErrorModel, WithState};
use mtec_io::{InputError, Table};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::{Path, PathBuf};

/// Builds a volumetric error map from a measured grid (trilinear interpolation between nodes).
///
/// `grid` is the grid (CSV path, or a mapping with `x_mm,y_mm,z_mm,ex_um,ey_um,ez_um`, one row
/// per node, any order, every node of the full grid exactly once). `outside` says what the map
/// gives beyond the grid box: `clamp` (default), `extrapolate` or `refuse`; `controller`
/// (`none`, `fanuc-3d`, `linuxcnc`) and `max_points_per_axis` check the controller's limits.
/// `out` writes the map file (`mtec.map/1`) byte for byte as `mtec map fit -o` does.
///
/// Returns the map as a dict: `x_mm`, `y_mm`, `z_mm` (the grid axes, 1-D arrays), `ex_um`,
/// `ey_um`, `ez_um` (arrays of shape (nx, ny, nz): node (i, j, k) at `[i, j, k]`), `outside`,
/// `source`, `format`, `model`.
///
/// >>> import mtec, numpy as np
/// >>> x, y, z = np.meshgrid([0.0, 100.0], [0.0, 50.0], [0.0], indexing="ij")
/// >>> m = mtec.map_fit({"x_mm": x.ravel(), "y_mm": y.ravel(), "z_mm": z.ravel(),
/// ...                   "ex_um": x.ravel() / 10, "ey_um": 0 * x.ravel(), "ez_um": y.ravel() / 50})
/// >>> m["ex_um"].shape, float(m["ex_um"][1, 0, 0])
/// ((2, 2, 1), 10.0)
#[pyfunction]
#[pyo3(signature = (grid, out = None, outside = "clamp", controller = "none", max_points_per_axis = None))]
pub fn map_fit<'py>(
    py: Python<'py>,
    grid: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    outside: &str,
    controller: &str,
    max_points_per_axis: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(run_map_fit(
        py,
        grid,
        out,
        outside,
        controller,
        max_points_per_axis,
    )?)
}

fn run_map_fit<'py>(
    py: Python<'py>,
    grid: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    outside: &str,
    controller: &str,
    max_points_per_axis: Option<usize>,
) -> Result<Bound<'py, PyAny>> {
    let outside = Outside::parse(outside).ok_or_else(|| {
        usage(format!(
            "outside `{outside}`: expected clamp, extrapolate or refuse"
        ))
    })?;
    let mut limits = GridLimits::for_controller(controller).ok_or_else(|| {
        usage(format!(
            "controller `{controller}`: expected none, fanuc-3d or linuxcnc"
        ))
    })?;
    if let Some(n) = max_points_per_axis {
        if n < 1 {
            return Err(usage("max_points_per_axis must be at least 1"));
        }
        limits.max_points_per_axis = Some(n);
    }
    let table = read_table(grid, "grid")?;
    let map = GridMap::from_table(&table, &limits, outside)?;
    let file = map.to_file();
    if let Some(p) = &out {
        let mut json = serde_json::to_string_pretty(&file).map_err(internal)?;
        json.push('\n');
        write_output(p, &file_inputs(&table), json.as_bytes())?;
    }
    let shape = [file.x_mm.len(), file.y_mm.len(), file.z_mm.len()];
    let d = PyDict::new(py);
    d.set_item("format", &file.format)?;
    d.set_item("model", &file.model)?;
    d.set_item("outside", outside.name())?;
    d.set_item("source", &file.source)?;
    for (k, v) in [
        ("x_mm", &file.x_mm),
        ("y_mm", &file.y_mm),
        ("z_mm", &file.z_mm),
    ] {
        d.set_item(k, PyArray1::from_slice(py, v))?;
    }
    for (k, v) in [
        ("ex_um", &file.ex_um),
        ("ey_um", &file.ey_um),
        ("ez_um", &file.ez_um),
    ] {
        d.set_item(k, PyArray1::from_slice(py, v).reshape(shape)?)?;
    }
    Ok(d.into_any())
}

/// Points (mm) and where each came from (file, line, column of its `x_mm`) for messages.
struct Points {
    path: PathBuf,
    xyz: Vec<[f64; 3]>,
    lines: Vec<usize>,
    x_column: usize,
}

fn points_of(py: Python<'_>, points: &Bound<'_, PyAny>) -> Result<Points> {
    if as_path(points)?.is_some() || points.hasattr("keys")? {
        let t = read_table(points, "points")?;
        let cols = [t.column("x_mm")?, t.column("y_mm")?, t.column("z_mm")?];
        let mut xyz = Vec::with_capacity(t.rows.len());
        for row in &t.rows {
            let mut p = [0.0; 3];
            for (pa, &c) in p.iter_mut().zip(&cols) {
                *pa = t.cell_f64(row, c)?;
            }
            xyz.push(p);
        }
        return Ok(Points {
            lines: t.rows.iter().map(|r| r.line).collect(),
            path: t.path,
            xyz,
            x_column: cols[0] + 1,
        });
    }
    let np = py.import("numpy")?;
    let arr = np.call_method1("asarray", (points, np.getattr("float64")?))?;
    let shape: Vec<usize> = arr.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(usage(format!(
            "`points` must be an (N, 3) array of x, y, z in mm, its shape is {shape:?}"
        )));
    }
    let a = arr.extract::<PyReadonlyArray2<f64>>()?;
    let a = a.as_array();
    let mut xyz = Vec::with_capacity(a.nrows());
    for (i, r) in a.rows().into_iter().enumerate() {
        if let Some(j) = r.iter().position(|v| !v.is_finite()) {
            return Err(InputError::at(
                Path::new(ARRAYS),
                i + 1,
                j + 1,
                format!("{} is not a finite number", r[j]),
            )
            .into());
        }
        xyz.push([r[0], r[1], r[2]]);
    }
    Ok(Points {
        path: PathBuf::from(ARRAYS),
        lines: (1..=xyz.len()).collect(),
        xyz,
        x_column: 1,
    })
}

/// Evaluates an error model at points: the batch form of `mtec map eval`.
///
/// `model` is any model file mtec compensates with (`mtec.map/1` from `map_fit`,
/// `mtec.kinematic-model/1` from `identify_lines`, `mtec.bpnn/1`, `mtec.machine-error/1`).
/// `points` is an (N, 3) array of x, y, z (mm), or a CSV path / mapping with `x_mm,y_mm,z_mm`.
/// Returns the (N, 3) array of `ex_um, ey_um, ez_um`. A point the model has no value at (outside
/// a map whose policy is `refuse`) raises `mtec.InputError` naming its row.
///
/// >>> import mtec, numpy as np, tempfile, os
/// >>> path = os.path.join(tempfile.mkdtemp(), "map.json")
/// >>> _ = mtec.map_fit({"x_mm": [0, 100], "y_mm": [0, 0], "z_mm": [0, 0],
/// ...                   "ex_um": [0, 10], "ey_um": [0, 0], "ez_um": [0, 0]}, out=path)
/// >>> mtec.map_eval(path, np.array([[25.0, 0, 0], [50.0, 0, 0]]))[:, 0].tolist()
/// [2.5, 5.0]
#[pyfunction]
#[pyo3(signature = (model, points))]
pub fn map_eval<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(run_map_eval(py, model, points)?)
}

fn run_map_eval<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    points: &Bound<'py, PyAny>,
) -> Result<Bound<'py, PyAny>> {
    let m = load_error_model(&path_arg(model, "model")?)?;
    let pts = points_of(py, points)?;
    // one batch call (a grid map's fast path), without the GIL
    let values: Vec<[f64; 3]> = py.detach(|| {
        let mut out = vec![[0.0; 3]; pts.xyz.len()];
        m.eval_batch(&pts.xyz, &mut out);
        out
    });
    if let Some(i) = values.iter().position(|e| !e.iter().all(|v| v.is_finite())) {
        let p = pts.xyz[i];
        return Err(InputError::at(
            &pts.path,
            pts.lines[i],
            pts.x_column,
            format!(
                "the model has no value at ({}, {}, {}) mm (outside the map's grid, whose policy is refuse; see `mtec map fit --outside`)",
                p[0], p[1], p[2]
            ),
        )
        .into());
    }
    // the (N, 3) array takes the values' buffer as it is (no copy, no row vectors)
    let n = values.len();
    let flat = PyArray1::from_vec(py, values.into_flattened());
    Ok(flat.reshape([n, 3]).map_err(internal)?.into_any())
}

/// A model with a state brought to the state after the log's last row (a static model as it is).
fn model_in_state(
    mut model: Box<dyn ErrorModel>,
    model_path: &Path,
    state: Option<&Path>,
) -> Result<Box<dyn ErrorModel>> {
    let inputs = model.state_inputs().to_vec();
    match (inputs.is_empty(), state) {
        (true, None) => Ok(model),
        (true, Some(_)) => Err(usage(format!(
            "state: {} is a static model (no temperatures or other state inputs); leave state out",
            model_path.display()
        ))),
        (false, None) => Err(usage(format!(
            "{} has a state (inputs: {}): its thermal part depends on the machine's readings now, \
             and without them it would be left out silently. Give state=LOG.csv with time_min \
             and these columns, one row per reading in time order",
            model_path.display(),
            inputs.join(", ")
        ))),
        (false, Some(log)) => {
            let table = Table::read(log)?;
            let status = advance_through_log(model.as_mut(), &table)?;
            let line = status.describe(&log.display().to_string());
            Ok(Box::new(WithState::new(model, &line)))
        }
    }
}

/// Rewrites an NC program (G-code text) so that the machine, with the errors of `model`, cuts
/// the programmed path: every commanded point t becomes p with p + e(p) = t, feed moves split
/// until the path stays within `tolerance_um`. The library behind `mtec compensate gcode`.
///
/// `model` is a model file as for `map_eval`; `state` the log (CSV) that brings a model with a
/// thermal state to the machine's state now. `offsets` a TOML file of work offsets (program
/// coordinates are otherwise machine coordinates). `start_position_mm` the machine position at
/// program start (x, y, z). `name` is the program's name in located errors. The other options
/// are those of `mtec compensate gcode` with the same defaults.
///
/// Returns `(text, report)`: the compensated program (byte-identical to the input where nothing
/// changes) and a dict (`lines_read`, `lines_written`, `moves_compensated`, `lines_added`,
/// `arcs_linearised`, `max_correction_um`, `warnings` as `"line:column: message"`, ...). A block
/// mtec cannot compensate raises `mtec.InputError` at its line and column (with
/// `on_unsupported="refuse"`, the default).
///
/// >>> import mtec, tempfile, os
/// >>> path = os.path.join(tempfile.mkdtemp(), "map.json")
/// >>> _ = mtec.map_fit({"x_mm": [0, 100], "y_mm": [0, 0], "z_mm": [0, 0],
/// ...                   "ex_um": [0, 10], "ey_um": [0, 0], "ez_um": [0, 0]}, out=path)
/// >>> text, report = mtec.compensate_gcode("G21 G90\nG0 X0 Y0 Z0\nG1 X50 F100\nM2\n", path)
/// >>> report["moves_compensated"], text.splitlines()[-2]
/// (1, 'G1 X49.995')
#[pyfunction]
#[pyo3(signature = (program, model, *, state = None, offsets = None, start_position_mm = None,
    tolerance_um = 0.5, max_segment_mm = 10.0, chord_tolerance_um = 0.5, max_correction_um = 500.0,
    on_unsupported = "refuse", default_units = "mm", name = "<program>"))]
#[allow(clippy::too_many_arguments)]
pub fn compensate_gcode<'py>(
    py: Python<'py>,
    program: &str,
    model: &Bound<'py, PyAny>,
    state: Option<PathBuf>,
    offsets: Option<PathBuf>,
    start_position_mm: Option<[f64; 3]>,
    tolerance_um: f64,
    max_segment_mm: f64,
    chord_tolerance_um: f64,
    max_correction_um: f64,
    on_unsupported: &str,
    default_units: &str,
    name: &str,
) -> PyResult<Bound<'py, PyTuple>> {
    let options = RewriteOptions {
        max_segment_mm,
        chord_tolerance_um,
        max_correction_um,
        start_position_mm,
        ..RewriteOptions::with_tolerance(tolerance_um)
    };
    Ok(run_gcode(
        py,
        program,
        model,
        state,
        offsets,
        options,
        on_unsupported,
        default_units,
        name,
    )?)
}

#[allow(clippy::too_many_arguments)]
fn run_gcode<'py>(
    py: Python<'py>,
    program: &str,
    model: &Bound<'py, PyAny>,
    state: Option<PathBuf>,
    offsets: Option<PathBuf>,
    mut options: RewriteOptions,
    on_unsupported: &str,
    default_units: &str,
    name: &str,
) -> Result<Bound<'py, PyTuple>> {
    options.on_unsupported = match on_unsupported {
        "refuse" => OnUnsupported::Refuse,
        "pass-through-with-warning" => OnUnsupported::PassThroughWithWarning,
        other => {
            return Err(usage(format!(
                "on_unsupported `{other}`: expected refuse or pass-through-with-warning"
            )))
        }
    };
    options.default_units = match default_units {
        "mm" => Units::Mm,
        "inch" => Units::Inch,
        other => {
            return Err(usage(format!(
                "default_units `{other}`: expected mm or inch"
            )))
        }
    };
    if let Some(p) = &offsets {
        let file: OffsetsFile = mtec_io::read_toml(p)?;
        options.offsets = file.validate().map_err(|m| InputError::file(p, m))?;
    }
    options.validate().map_err(usage)?;
    let model_path = path_arg(model, "model")?;
    let m = model_in_state(
        load_error_model(&model_path)?,
        &model_path,
        state.as_deref(),
    )?;
    options.check_for(m.as_ref()).map_err(usage)?;
    let mut out: Vec<u8> = Vec::with_capacity(program.len() + program.len() / 8);
    let report = py
        .detach(|| rewrite(program.as_bytes(), &mut out, m.as_ref(), &options))
        .map_err(|e| match e {
            GcodeError::At(d) => {
                InputError::at(Path::new(name), d.line, d.column, d.message).into()
            }
            GcodeError::Io(e) => internal(format!("{name}: {e}")),
        })?;
    let text = String::from_utf8(out)
        .map_err(|e| internal(format!("{name}: output is not UTF-8: {e}")))?;
    let r = PyDict::new(py);
    r.set_item("lines_read", report.lines_read)?;
    r.set_item("lines_written", report.lines_written)?;
    r.set_item("lines_added", report.lines_added)?;
    r.set_item("moves_compensated", report.moves_compensated)?;
    r.set_item("arcs_linearised", report.arcs_linearised)?;
    r.set_item("rapids_not_compensated", report.rapids_not_compensated)?;
    r.set_item("moves_end_point_only", report.moves_end_point_only)?;
    r.set_item("max_correction_um", report.max_correction_um)?;
    r.set_item("points_outside_model", report.points_outside_model)?;
    r.set_item("warnings_total", report.warnings_total)?;
    let warnings: Vec<String> = report
        .warnings
        .iter()
        .map(|w| format!("{}:{}: {}", w.line, w.column, w.message))
        .collect();
    r.set_item("warnings", warnings)?;
    Ok(PyTuple::new(
        py,
        [
            pyo3::types::PyString::new(py, &text).into_any(),
            r.into_any(),
        ],
    )?)
}
