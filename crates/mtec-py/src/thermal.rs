//! Thermal error models (mtec-thermal): fit a model to a temperature log, predict the drift.
//!
//! Both calls are `mtec_workflow::ops::thermal`'s, on a table read from a file or built from
//! arrays: the model file is the one `mtec thermal fit -o` writes (`mtec.thermal-model/1`), byte
//! for byte (python/tests/test_thermal.py checks it against the CLI), and every kind of the
//! registry (`mtec_thermal::registry::KINDS`) is a `model` here as it is a `--model` there.

use crate::columns::{path_arg, read_table};
use crate::convert::{serde_to_py, write_output};
use crate::errors::{internal, usage, Result, ARRAYS};
use mtec_thermal::model_file::SplitBy;
use mtec_thermal::registry::FitOptions;
use mtec_workflow::ops::thermal as op;
use numpy::PyArray1;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};

/// Fits a thermal error model to a temperature log: the library behind `mtec thermal fit`.
///
/// `data` is the log (CSV path, or a mapping with `experiment` (optional), `time_min`, one
/// `<sensor>_c` column per temperature sensor, optionally `ambient_c`, `position_mm` and the
/// heat-input column, and the target `<target>_um`). `model` is a kind of `mtec thermal fit
/// --model` (`auto`, `mlr`, `ridge`, `ridge-select`, `exp-ambient`, `lag-select`, `heat-input`;
/// the neural kinds need the CLI's `neural` build); `sensors` the sensors to use (all `_c`
/// columns when empty; `[UP, NUT]` for exp-ambient, or `up_sensors`/`nut_sensors` groups), `k`
/// the ridge parameter (chosen by forward validation when None), `lag` adds first-order lags,
/// `block_min` the validation block length, `max_sensors` auto's sensor budget, `input` the
/// heat-input column. The split: `train`/`test` experiment names, or `train_until` (minutes).
/// Options are checked as the CLI checks them, and refused with its option names (`--k`).
///
/// Returns the model file (`mtec.thermal-model/1`) as a dict (`train_metrics["rmse_um"]`,
/// `validation["pooled_rmse_um"]`, `warnings`, ...); `out` writes it byte for byte as
/// `mtec thermal fit -o` does, for `thermal_predict` and the CLI.
///
/// >>> import mtec, numpy as np
/// >>> t = np.arange(0.0, 240.0, 2.0)
/// >>> s1, s2 = 20 + 5 * (1 - np.exp(-t / 60)), 20 + 0.01 * t
/// >>> m = mtec.thermal_fit({"time_min": t, "s1_c": s1, "s2_c": s2,
/// ...                       "dz_um": 3 * (s1 - 20) - 2 * (s2 - 20) + 1},
/// ...                      target="dz_um", model="mlr")
/// >>> [round(c, 9) for c in m["model"]["coefficients"]], round(m["model"]["intercept_um"], 9)
/// ([3.0, -2.0], -19.0)
#[pyfunction]
#[pyo3(signature = (data, target, model = "auto", *, sensors = Vec::new(), k = None, lag = false,
    block_min = None, max_sensors = None, input = "spindle_rpm".to_string(), train = Vec::new(),
    test = Vec::new(), train_until = None, up_sensors = Vec::new(), nut_sensors = Vec::new(),
    out = None))]
#[allow(clippy::too_many_arguments)]
pub fn thermal_fit<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    target: &str,
    model: &str,
    sensors: Vec<String>,
    k: Option<f64>,
    lag: bool,
    block_min: Option<f64>,
    max_sensors: Option<usize>,
    input: String,
    train: Vec<String>,
    test: Vec<String>,
    train_until: Option<f64>,
    up_sensors: Vec<String>,
    nut_sensors: Vec<String>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let fit = FitOptions {
        sensors,
        k,
        lag,
        block_min,
        max_sensors,
        input,
        up_sensors,
        nut_sensors,
    };
    let split = match train_until {
        Some(t) if train.is_empty() && test.is_empty() => SplitBy::Until(t),
        Some(_) => return Err(usage("train_until goes without train and test").into()),
        None => SplitBy::Experiments { train, test },
    };
    Ok(fit_model(py, data, target, model, &fit, &split, out)?)
}

fn fit_model<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    target: &str,
    model: &str,
    fit: &FitOptions,
    split: &SplitBy,
    out: Option<PathBuf>,
) -> Result<Bound<'py, PyAny>> {
    let table = read_table(data, "data")?;
    let file = py.detach(|| op::fit_table(&table, target, model, fit, split))?;
    if let Some(p) = &out {
        let text = serde_json::to_string_pretty(&file).map_err(internal)?;
        let inputs: Vec<PathBuf> = if table.path == Path::new(ARRAYS) {
            Vec::new()
        } else {
            vec![table.path.clone()]
        };
        write_output(p, &inputs, text.as_bytes())?;
    }
    serde_to_py(py, &file)
}

/// Predicts the thermal drift (µm) with a model file: the library behind `mtec thermal predict`.
///
/// `model` is a model file from `thermal_fit(out=...)` or `mtec thermal fit -o`; `data` the log
/// (CSV path or mapping, as for `thermal_fit`; the target column is optional). `history` is the
/// log before `data` (a path), for models with a state (lags, heat input) whose filters would
/// otherwise start in equilibrium with the first row.
///
/// Returns the document `mtec thermal predict --json` prints (`mtec.thermal-prediction/1`):
/// `predictions` (numpy array, one per row), `uncertainty_um` (the forward validation's pooled
/// RMSE, None without one), `rows_outside_training_range`, and where the log has the target
/// `rmse_um`, `mae_um`, `max_abs_residual_um` and `metrics`.
///
/// >>> import mtec, numpy as np, tempfile, os
/// >>> t = np.arange(0.0, 240.0, 2.0)
/// >>> s1 = 20 + 5 * (1 - np.exp(-t / 60))
/// >>> path = os.path.join(tempfile.mkdtemp(), "model.json")
/// >>> _ = mtec.thermal_fit({"time_min": t, "s1_c": s1, "dz_um": 2 * (s1 - 20)},
/// ...                      target="dz_um", model="mlr", out=path)
/// >>> p = mtec.thermal_predict(path, {"time_min": [0.0, 1.0], "s1_c": [20.0, 22.5]})
/// >>> (np.round(p["predictions"], 6) + 0.0).tolist()
/// [0.0, 5.0]
#[pyfunction]
#[pyo3(signature = (model, data, history = None))]
pub fn thermal_predict<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
    history: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(predict(py, model, data, history)?)
}

fn predict<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
    history: Option<&Bound<'py, PyAny>>,
) -> Result<Bound<'py, PyAny>> {
    let file = op::read_model(&path_arg(model, "model")?)?;
    let table = read_table(data, "data")?;
    let history = history.map(|h| read_table(h, "history")).transpose()?;
    let p = py.detach(|| op::predict_table(&file, &table, history.as_ref()))?;
    let out = serde_to_py(py, &p)?;
    out.set_item("outside_training_range", &p.outside_training_range)?;
    out.set_item("predictions", PyArray1::from_vec(py, p.predictions))?;
    Ok(out)
}
