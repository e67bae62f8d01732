//! Thermal error models (mtec-thermal): fit a model to a temperature log, predict the drift.
//!
//! Both calls are `mtec_workflow::ops::thermal`'s, on a table read from a file or built from
//! arrays: the model file is the one `mtec thermal fit -o` writes (`mtec.thermal-model/1`), byte
//! for byte (python/tests/test_thermal.py checks it against the CLI), and every kind of the
//! registry (`mtec_thermal::registry::KINDS`) is a `model` here as it is a `--model` there.

use crate::columns::{as_path, file_inputs, path_arg, read_table};
use crate::convert::{serde_to_py, write_output};
use crate::errors::{internal, usage, Result};
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
        write_output(p, &file_inputs(&table), text.as_bytes())?;
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

/// Chooses the temperature sensors of a thermal model by VIF and the ridge trace: the library
/// behind `mtec thermal select`.
///
/// `data` is the log (CSV path or mapping, as for `thermal_fit`), `target` the drift column
/// (`radial_um` or `radial`), `sensors` the candidates (every `_c` column but `ambient_c` when
/// empty). The method (docs/methods.md §7): variance inflation factors of the candidates (VIF >
/// 10 is severe collinearity), the ridge trace over k on standardised regressors, elimination
/// by the ridge-trace rules (stable and small, falling to zero, unstable, changing sign), k
/// where the kept coefficients settle, and the comparison with the all-sensor and the simple-
/// correlation models (R², max |residual|, SSE, MSE, F).
///
/// Returns the document `mtec thermal select --json` prints (`mtec.thermal-selection/1`):
/// `vif` (a list of `{sensor, vif, severe}`), `steps` (what each rule removed at which k),
/// `selected`, `k`, `coefficients` and `standardised_coefficients` of the selected sensors,
/// `intercept_um`, `comparison` (the three models' metrics), `trace` (k and the coefficients
/// along it). `out` (a folder) also gets the CLI's ridge_trace.csv, ridge_trace.svg and
/// selection.json.
///
/// >>> import mtec, numpy as np
/// >>> rng = np.random.default_rng(7)
/// >>> t = np.arange(0.0, 600.0, 5.0)
/// >>> s1 = 20 + 4 * (1 - np.exp(-t / 90))
/// >>> s2 = s1 + 0.02 * rng.standard_normal(t.size)          # nearly a copy of s1
/// >>> s3 = 20 + 0.3 * np.sin(t / 40)
/// >>> r = mtec.thermal_select({"time_min": t, "s1_c": s1, "s2_c": s2, "s3_c": s3,
/// ...                          "dz_um": 3 * (s1 - 20) + 0.05 * rng.standard_normal(t.size)},
/// ...                         target="dz_um")
/// >>> [v["severe"] for v in r["vif"]]
/// [True, True, False]
/// >>> len(r["selected"]), "s3_c" in r["selected"]
/// (1, False)
#[pyfunction]
#[pyo3(signature = (data, target, *, sensors = Vec::new(), out = None))]
pub fn thermal_select<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    target: &str,
    sensors: Vec<String>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(select(py, data, target, &sensors, out)?)
}

fn select<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    target: &str,
    sensors: &[String],
    out: Option<PathBuf>,
) -> Result<Bound<'py, PyAny>> {
    // the folder is settled before any work: none of its files the log
    if let (Some(dir), Some(log)) = (&out, as_path(data)?) {
        op::check_selection_out(dir, &[&log])?;
    }
    let table = read_table(data, "data")?;
    let outcome = py.detach(|| op::select_table(&table, target, sensors))?;
    if let Some(dir) = &out {
        let inputs = file_inputs(&table);
        let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        op::write_selection(&outcome, dir, &inputs)?;
    }
    serde_to_py(py, &outcome)
}

/// Validates a thermal model kind forward in time: the library behind `mtec thermal cv`.
///
/// `data`, `target`, `model` and the options are those of `thermal_fit` (the networks need the
/// CLI's `neural` build). The log is cut into blocks (experiments, the steps of the `input`
/// column, or `block_min` minutes); fold i fits on every block before block i + 1 and scores
/// it (the first block only trains). `loo=True` leaves one block out at a time instead: optimistic for a model that must
/// predict forward, because it trains on the future of the block it scores.
///
/// Returns the document `mtec thermal cv --json` prints: forward (`mtec.thermal-cv/2`) with
/// `folds` (per fold: `train_from_min`, `train_to_min`, `test_from_min`, `test_to_min`,
/// `metrics` of the scored block (`rmse_um`, `max_abs_residual_um`, `r2`, ...) and
/// `uncompensated_rmse_um`), `pooled_rmse_um`, `pooled_max_abs_um`, `rmse_std_error_um` and
/// `folds_worse_than_uncompensated` (1-based); leave-one-block-out (`mtec.thermal-cv/1`) with
/// its blocks.
///
/// >>> import mtec, numpy as np
/// >>> t = np.arange(0.0, 960.0, 2.0)
/// >>> rpm = np.where((t // 240) % 2 == 0, 3000.0, 0.0)      # 4 h steps: on, off, on, off
/// >>> s1 = 20 + np.cumsum(np.where(rpm > 0, 0.01, -0.01))
/// >>> cv = mtec.thermal_cv({"time_min": t, "spindle_rpm": rpm, "s1_c": s1,
/// ...                       "dz_um": 2.5 * (s1 - 20)}, "dz_um", "mlr")
/// >>> cv["protocol"], len(cv["folds"]), cv["pooled_rmse_um"] < 1e-9
/// ('forward', 2, True)
#[pyfunction]
#[pyo3(signature = (data, target, model = "auto", *, sensors = Vec::new(), k = None, lag = false,
    block_min = None, max_sensors = None, input = "spindle_rpm".to_string(),
    up_sensors = Vec::new(), nut_sensors = Vec::new(), loo = false))]
#[allow(clippy::too_many_arguments)]
pub fn thermal_cv<'py>(
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
    up_sensors: Vec<String>,
    nut_sensors: Vec<String>,
    loo: bool,
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
    Ok(cv(py, data, target, model, &fit, loo)?)
}

fn cv<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    target: &str,
    model: &str,
    fit: &FitOptions,
    loo: bool,
) -> Result<Bound<'py, PyAny>> {
    let table = read_table(data, "data")?;
    let outcome = py.detach(|| op::cv_table(&table, target, model, fit, loo))?;
    serde_to_py(py, &outcome)
}
