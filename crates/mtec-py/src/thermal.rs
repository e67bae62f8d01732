//! Thermal error models (mtec-thermal): fit a model to a temperature log, predict the drift.
//!
//! The model file is the one `mtec thermal fit -o` writes (`mtec.thermal-model/1`), byte for
//! byte (python/tests/test_thermal.py checks it against the CLI). Its assembly (split, forward
//! validation, envelope, metrics) is at present the CLI's (`crates/mtec-cli/src/cmd/thermal.rs`,
//! `fit`), repeated here; when it moves to `mtec_workflow::ops` this module calls it there.

use crate::columns::{path_arg, read_table};
use crate::convert::{serde_to_py, to_py, write_output};
use crate::errors::{internal, usage, Result, ARRAYS};
use mtec_io::{InputError, Table};
use mtec_thermal::auto::Auto;
use mtec_thermal::guard::{envelope, model_columns, outside_envelope};
use mtec_thermal::heat_input::with_input;
use mtec_thermal::model::{ModelFile, Split, ThermalModel};
use mtec_thermal::validate::{
    duty_cycle_blocks, forward_cv, forward_folds, rows_of_experiments, split_at_time, BlockSpec,
    ForwardCv,
};
use mtec_thermal::{
    ExpAmbient, Fit, HeatInput, Metrics, Mlr, Predict, Ridge, ThermalData, ThermalError,
    MODEL_FORMAT,
};
use numpy::PyArray1;
use pyo3::prelude::*;
use serde_json::json;
use std::path::{Path, PathBuf};

/// The model kinds bound here (the neural ones need the `neural` build of the CLI).
const MODELS: &str = "auto, mlr, ridge, heat-input, exp-ambient";

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Auto,
    Mlr,
    Ridge,
    HeatInput,
    ExpAmbient,
}

/// The options of a fit (those of `mtec thermal fit`).
struct Options {
    kind: Kind,
    sensors: Vec<String>,
    k: Option<f64>,
    lag: bool,
    block_min: Option<f64>,
    max_sensors: Option<usize>,
    input: String,
}

impl Options {
    fn check(&self) -> Result<()> {
        if let Some(b) = self.block_min {
            if !(b > 0.0 && b.is_finite()) {
                return Err(usage("block_min must be a number of minutes > 0"));
            }
        }
        if self.max_sensors == Some(0) {
            return Err(usage("max_sensors must be at least 1"));
        }
        if self.max_sensors.is_some() && self.kind != Kind::Auto {
            return Err(usage("max_sensors goes with model=\"auto\""));
        }
        if self.kind == Kind::Auto && self.lag {
            return Err(usage("model=\"auto\" chooses lags itself (no lag=True)"));
        }
        if self.kind == Kind::ExpAmbient && self.lag {
            return Err(usage("lag applies to the linear models, not exp-ambient"));
        }
        if let Some(k) = self.k {
            if !(k >= 0.0 && k.is_finite()) || self.kind != Kind::Ridge {
                return Err(usage(
                    "k must be a number ≥ 0 and goes with model=\"ridge\"",
                ));
            }
        }
        Ok(())
    }

    fn blocks(&self) -> BlockSpec {
        BlockSpec {
            block_min: self.block_min,
            input: Some(self.input.clone()),
        }
    }

    fn auto(&self, data: &ThermalData) -> Auto {
        let exp = data.ambient_c.is_some() && data.position_mm.is_some() && self.sensors.len() == 2;
        Auto {
            sensors: self.sensors.clone(),
            input: self.input.clone(),
            max_sensors: self
                .max_sensors
                .unwrap_or(mtec_thermal::auto::DEFAULT_MAX_SENSORS),
            block_min: self.block_min,
            exp_ambient: exp.then(|| ExpAmbient {
                up_sensor: self.sensors[0].clone(),
                nut_sensor: self.sensors[1].clone(),
                ..Default::default()
            }),
        }
    }
}

impl Fit for Options {
    type Model = ThermalModel;
    fn fit_rows(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> std::result::Result<ThermalModel, ThermalError> {
        Ok(match self.kind {
            Kind::Auto => self.auto(data).fit_rows(data, rows)?,
            Kind::Mlr => ThermalModel::Linear(
                Mlr {
                    sensors: self.sensors.clone(),
                    lag: self.lag,
                    blocks: self.blocks(),
                }
                .fit_rows(data, rows)?,
            ),
            Kind::Ridge => ThermalModel::Linear(
                Ridge {
                    sensors: self.sensors.clone(),
                    k: self.k,
                    lag: self.lag,
                    blocks: self.blocks(),
                }
                .fit_rows(data, rows)?,
            ),
            Kind::HeatInput => ThermalModel::HeatInput(
                HeatInput {
                    input: self.input.clone(),
                    block_min: self.block_min,
                    ..Default::default()
                }
                .fit_rows(data, rows)?,
            ),
            Kind::ExpAmbient => {
                let [up, nut] = self.sensors.as_slice() else {
                    return Err(ThermalError::Invalid(
                        "exp-ambient needs sensors=[UP, NUT]: the upper-bearing sensor, then the ball-screw-nut sensor".into(),
                    ));
                };
                ThermalModel::ExpAmbient(Box::new(
                    ExpAmbient {
                        up_sensor: up.clone(),
                        nut_sensor: nut.clone(),
                        ..Default::default()
                    }
                    .fit_rows(data, rows)?,
                ))
            }
        })
    }
}

/// A thermal error about the data: a missing column is located at the header.
fn located(data: &ThermalData, path: &Path, e: ThermalError) -> InputError {
    match e {
        ThermalError::MissingColumn(c) => data.header_error(format!("missing column `{c}`")),
        other => InputError::file(path, other.to_string()),
    }
}

/// The log with the heat-source column attached (required, or when the table has it).
fn load(
    t: &Table,
    target: Option<&str>,
    require_target: bool,
    input: Option<(&str, bool)>,
) -> Result<ThermalData> {
    let d = ThermalData::from_table(t, target, require_target)?;
    match input {
        Some((name, required)) if required || t.has(name) => {
            let v = t.f64_column(name)?;
            Ok(with_input(&d, name, &v).map_err(|e| InputError::file(&t.path, e.to_string()))?)
        }
        _ => Ok(d),
    }
}

/// Forward validation of the fitter on the training rows, and its warnings.
fn validate_forward(
    o: &Options,
    data: &ThermalData,
    train: &[usize],
) -> (Option<ForwardCv>, Vec<String>) {
    let folds = forward_folds(&duty_cycle_blocks(data, train, &o.blocks()));
    if folds.is_empty() {
        return (None, vec!["no forward validation: the training rows hold fewer than two blocks, so the model carries no uncertainty (use a longer record, experiments, or --block-min)".into()]);
    }
    match forward_cv(o, data, &folds) {
        Ok(v) => (Some(v), Vec::new()),
        Err(e) => (None, vec![format!("forward validation failed: {e}")]),
    }
}

/// The warning of a model worse than no compensation on some forward folds.
fn worse_warning(v: &ForwardCv) -> Option<String> {
    let worse = v.folds_worse_than_uncompensated();
    (!worse.is_empty()).then(|| {
        let list: Vec<String> = worse
            .iter()
            .map(|&f| {
                let s = &v.folds[f - 1];
                format!(
                    "fold {f} ({:.0}–{:.0} min): {:.2} µm against {:.2} µm uncompensated",
                    s.test_from_min, s.test_to_min, s.metrics.rmse_um, s.uncompensated_rmse_um
                )
            })
            .collect();
        format!(
            "WORSE THAN NO COMPENSATION on forward validation, {}: do not apply this model",
            list.join("; ")
        )
    })
}

fn metrics_on(
    model: &ThermalModel,
    data: &ThermalData,
    rows: &[usize],
    pred: &[f64],
) -> std::result::Result<Metrics, ThermalError> {
    let y = data.target_um()?;
    let yt: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
    let pt: Vec<f64> = rows.iter().map(|&i| pred[i]).collect();
    Ok(Metrics::new(&yt, &pt, model.predictors()))
}

/// The training and test rows and how they were chosen.
fn split(
    data: &ThermalData,
    train: &[String],
    test: &[String],
    train_until: Option<f64>,
) -> std::result::Result<(Vec<usize>, Vec<usize>, Split), ThermalError> {
    let all: Vec<usize> = (0..data.len()).collect();
    Ok(if let Some(t) = train_until {
        let (tr, te) = split_at_time(data, t);
        let s = Split {
            train_until_min: Some(t),
            ..Default::default()
        };
        (tr, te, s)
    } else if !train.is_empty() {
        let tr = rows_of_experiments(data, train)?;
        let te = if test.is_empty() {
            all.iter().copied().filter(|i| !tr.contains(i)).collect()
        } else {
            rows_of_experiments(data, test)?
        };
        let test_exps = if test.is_empty() {
            data.experiments()
                .into_iter()
                .filter(|e| !train.contains(e))
                .collect()
        } else {
            test.to_vec()
        };
        let s = Split {
            train_experiments: train.to_vec(),
            test_experiments: test_exps,
            ..Default::default()
        };
        (tr, te, s)
    } else {
        (all, Vec::new(), Split::default())
    })
}

/// Fits a thermal error model to a temperature log: the library behind `mtec thermal fit`.
///
/// `data` is the log (CSV path, or a mapping with `experiment` (optional), `time_min`, one
/// `<sensor>_c` column per temperature sensor, optionally `ambient_c`, `position_mm` and the
/// heat-input column, and the target `<target>_um`). `model` is one of `auto`, `mlr`, `ridge`,
/// `heat-input`, `exp-ambient`; `sensors` the sensors to use (all `_c` columns when empty;
/// `[UP, NUT]` for exp-ambient), `k` the ridge parameter (chosen by forward validation when
/// None), `lag` adds first-order lags, `block_min` the validation block length, `input` the
/// heat-input column. The split: `train`/`test` experiment names, or `train_until` (minutes).
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
    test = Vec::new(), train_until = None, out = None))]
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
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = match model {
        "auto" => Kind::Auto,
        "mlr" => Kind::Mlr,
        "ridge" => Kind::Ridge,
        "heat-input" => Kind::HeatInput,
        "exp-ambient" => Kind::ExpAmbient,
        other => return Err(usage(format!("model `{other}`: expected one of {MODELS}")).into()),
    };
    let o = Options {
        kind,
        sensors,
        k,
        lag,
        block_min,
        max_sensors,
        input,
    };
    Ok(fit(py, data, target, &o, &train, &test, train_until, out)?)
}

#[allow(clippy::too_many_arguments)]
fn fit<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    target: &str,
    o: &Options,
    train: &[String],
    test: &[String],
    train_until: Option<f64>,
    out: Option<PathBuf>,
) -> Result<Bound<'py, PyAny>> {
    o.check()?;
    if train_until.is_some() && !(train.is_empty() && test.is_empty()) {
        return Err(usage("train_until goes without train and test"));
    }
    if train.is_empty() && !test.is_empty() {
        return Err(usage("test needs train"));
    }
    let table = read_table(data, "data")?;
    let d = load(
        &table,
        Some(target),
        true,
        Some((o.input.as_str(), o.kind == Kind::HeatInput)),
    )?;
    let path = table.path.clone();
    let err = |e| located(&d, &path, e);
    let (train_rows, test_rows, mut split) = split(&d, train, test, train_until).map_err(err)?;
    if train_rows.is_empty() {
        return Err(usage("the training selection holds no rows"));
    }
    let file = py.detach(|| -> std::result::Result<ModelFile, ThermalError> {
        let (model, candidates, validation, mut warnings) = if o.kind == Kind::Auto {
            let f = o.auto(&d).fit_auto(&d, &train_rows)?;
            (f.model, f.candidates, Some(f.validation), Vec::new())
        } else {
            let model = o.fit_rows(&d, &train_rows)?;
            let (v, w) = validate_forward(o, &d, &train_rows);
            (model, Vec::new(), v, w)
        };
        warnings.splice(0..0, model.warnings());
        warnings.extend(validation.as_ref().and_then(worse_warning));
        let pred = model.predict(&d)?;
        let train_metrics = metrics_on(&model, &d, &train_rows, &pred)?;
        let test_metrics = if test_rows.is_empty() {
            None
        } else {
            Some(metrics_on(&model, &d, &test_rows, &pred)?)
        };
        if split.train_experiments.is_empty() && split.train_until_min.is_none() {
            split.train_experiments = d.experiments();
        }
        split.train_rows = train_rows.len();
        split.test_rows = test_rows.len();
        Ok(ModelFile {
            format: MODEL_FORMAT.into(),
            target: d.target_name().unwrap_or_default().to_string(),
            envelope: envelope(&model, &d, &train_rows),
            model,
            split,
            train_metrics,
            test_metrics,
            validation,
            candidates,
            warnings,
        })
    });
    let file = file.map_err(err)?;
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
    let model_path = path_arg(model, "model")?;
    let file: ModelFile = mtec_io::read_json(&model_path)?;
    file.check_format()
        .map_err(|e| InputError::file(&model_path, e.to_string()))?;
    // a non-temperature column the model reads (the heat input) must be in the data
    let input_name = model_columns(&file.model)
        .into_iter()
        .find(|c| !c.ends_with("_c") && c != "position_mm");
    let input = input_name.as_deref().map(|n| (n, true));
    let table = read_table(data, "data")?;
    let d = load(&table, Some(&file.target), false, input)?;
    let (pred, outside) = match history {
        Some(h) => {
            let ht = read_table(h, "history")?;
            let hist = load(&ht, None, false, input)?;
            let all = hist
                .followed_by(&d)
                .map_err(|e| InputError::file(&ht.path, e.to_string()))?;
            let p = py
                .detach(|| file.model.predict(&all))
                .map_err(|e| located(&all, &table.path, e))?;
            let o = outside_envelope(&file.envelope, &all);
            (p[hist.len()..].to_vec(), o[hist.len()..].to_vec())
        }
        None => {
            let p = py
                .detach(|| file.model.predict(&d))
                .map_err(|e| located(&d, &table.path, e))?;
            (p, outside_envelope(&file.envelope, &d))
        }
    };
    let uncertainty = file.validation.as_ref().map(|v| v.pooled_rmse_um);
    let n_out = outside.iter().filter(|o| !o.is_empty()).count();
    let mut doc = json!({
        "format": "mtec.thermal-prediction/1",
        "target": file.target,
        "n": pred.len(),
        "uncertainty_um": uncertainty,
        "rows_outside_training_range": n_out,
        "outside_training_range": outside.iter().map(|o| o.join(";")).collect::<Vec<_>>(),
    });
    if let Ok(y) = d.target_um() {
        let m = Metrics::new(y, &pred, file.model.predictors());
        doc["rmse_um"] = m.rmse_um.into();
        doc["mae_um"] = m.mae_um.into();
        doc["max_abs_residual_um"] = m.max_abs_residual_um.into();
        doc["metrics"] = serde_json::to_value(&m).map_err(internal)?;
    }
    let out = to_py(py, &doc)?;
    out.set_item("predictions", PyArray1::from_vec(py, pred))?;
    Ok(out)
}
