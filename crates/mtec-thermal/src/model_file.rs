//! The model file, the versioned JSON document `thermal fit` writes (`mtec.thermal-model/1`,
//! [`ModelFile`]), and how it is fitted: the train/test split, the fit of a registered kind with
//! its forward validation, the metrics on both sets of rows, the training envelope and the
//! warnings.

use crate::auto::CandidateScore;
use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::fit::Predict;
use crate::guard::{envelope, InputRange};
use crate::kind::Validated;
use crate::metrics::Metrics;
use crate::model::ThermalModel;
use crate::options::BlockSpec;
use crate::registry::ModelSpec;
use crate::validate::{rows_of_experiments, split_at_time, ForwardCv};
use serde::{Deserialize, Serialize};

/// The format tag of a model file.
pub const MODEL_FORMAT: &str = "mtec.thermal-model/1";

/// Which rows a model was trained (and tested) on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Split {
    pub train_experiments: Vec<String>,
    pub test_experiments: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub train_until_min: Option<f64>,
    pub train_rows: usize,
    pub test_rows: usize,
}

/// The JSON model file: `{"format": "mtec.thermal-model/1", "target": …, "model": {…}, …}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    pub format: String,
    pub target: String,
    pub model: ThermalModel,
    pub split: Split,
    pub train_metrics: Metrics,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub test_metrics: Option<Metrics>,
    /// Forward (rolling-origin) validation on the training rows: the error on blocks the model
    /// had not seen; its pooled RMSE is the uncertainty `predict` reports.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub validation: Option<ForwardCv>,
    /// Training range of every column the model reads (`predict` flags rows outside).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub envelope: Vec<InputRange>,
    /// `--model auto`: every candidate's forward score and which was chosen.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub candidates: Vec<CandidateScore>,
    /// Warnings of the fit (also printed by `fit`).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub warnings: Vec<String>,
}

impl ModelFile {
    /// Checks the format tag after reading.
    pub fn check_format(&self) -> Result<(), ThermalError> {
        if self.format != MODEL_FORMAT {
            return Err(ThermalError::Invalid(format!(
                "`format` is `{}`: this mtec reads `{MODEL_FORMAT}`",
                self.format
            )));
        }
        Ok(())
    }
}

/// Which rows train the model and which test it.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum SplitBy {
    /// Every row trains; nothing is tested.
    #[default]
    All,
    /// Rows with `time_min ≤` this train, the rest test.
    Until(f64),
    /// These experiments train; `test` (every other experiment when empty) test.
    Experiments {
        train: Vec<String>,
        test: Vec<String>,
    },
}

impl SplitBy {
    /// Rows up to `until` (the command line's `--train-until`) when given, else the `train` and
    /// `test` experiments (`--train`, `--test`).
    pub fn from_options(until: Option<f64>, train: Vec<String>, test: Vec<String>) -> SplitBy {
        match until {
            Some(t) => SplitBy::Until(t),
            None => SplitBy::Experiments { train, test },
        }
    }
}

/// The rows of a split and how the model file records it.
#[derive(Debug, Clone, PartialEq)]
pub struct Rows {
    pub train: Vec<usize>,
    pub test: Vec<usize>,
    pub split: Split,
}

/// The training and test rows of `data` (`Invalid` for an experiment the log does not have).
pub fn split_rows(data: &ThermalData, by: &SplitBy) -> Result<Rows, ThermalError> {
    let all: Vec<usize> = (0..data.len()).collect();
    let (train, test, mut split) = match by {
        SplitBy::Until(t) => {
            let (tr, te) = split_at_time(data, *t);
            let s = Split {
                train_until_min: Some(*t),
                ..Default::default()
            };
            (tr, te, s)
        }
        SplitBy::Experiments { train, test } if !train.is_empty() => {
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
                test.clone()
            };
            let s = Split {
                train_experiments: train.clone(),
                test_experiments: test_exps,
                ..Default::default()
            };
            (tr, te, s)
        }
        _ => (all, Vec::new(), Split::default()),
    };
    if split.train_experiments.is_empty() && split.train_until_min.is_none() {
        split.train_experiments = data.experiments();
    }
    split.train_rows = train.len();
    split.test_rows = test.len();
    Ok(Rows { train, test, split })
}

/// Metrics of the predictions `pred` (every row of `data`) on the rows `rows`.
pub fn metrics_on<P: Predict + ?Sized>(
    model: &P,
    data: &ThermalData,
    rows: &[usize],
    pred: &[f64],
) -> Result<Metrics, ThermalError> {
    let y = data.target_um()?;
    let yt: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
    let pt: Vec<f64> = rows.iter().map(|&i| pred[i]).collect();
    Ok(Metrics::new(&yt, &pt, model.predictors()))
}

/// The warning of a model worse than no compensation on some forward folds.
pub fn worse_warning(v: &ForwardCv) -> Option<String> {
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

/// Fits `spec` on the training rows, validates it forward on their blocks (`blocks`), scores
/// it on both sets of rows and records the training envelope: the model file.
pub fn fit_file(
    spec: &ModelSpec,
    data: &ThermalData,
    rows: Rows,
    blocks: &BlockSpec,
) -> Result<ModelFile, ThermalError> {
    file_of(spec.fit_validated(data, &rows.train, blocks)?, data, rows)
}

/// The model file of a model fitted and validated on `rows.train` (e.g. chosen by auto among
/// candidates of other crates too): its metrics on both sets of rows, envelope and warnings.
pub fn file_of(
    validated: Validated,
    data: &ThermalData,
    rows: Rows,
) -> Result<ModelFile, ThermalError> {
    let Validated {
        model,
        validation,
        candidates,
        mut warnings,
    } = validated;
    warnings.splice(0..0, model.warnings());
    warnings.extend(validation.as_ref().and_then(worse_warning));
    let pred = model.predict(data)?;
    let train_metrics = metrics_on(&model, data, &rows.train, &pred)?;
    let test_metrics = if rows.test.is_empty() {
        None
    } else {
        Some(metrics_on(&model, data, &rows.test, &pred)?)
    };
    Ok(ModelFile {
        format: MODEL_FORMAT.into(),
        target: data.target_name().unwrap_or_default().to_string(),
        envelope: envelope(&model, data, &rows.train),
        model,
        split: rows.split,
        train_metrics,
        test_metrics,
        validation,
        candidates,
        warnings,
    })
}
