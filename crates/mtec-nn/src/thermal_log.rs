//! Thermal logs (CSV) read for the neural models of several targets (the rotary route of
//! `thermal fit`) as mtec-thermal's [`ThermalData`], the one data set of every thermal and
//! neural model ([`load`]: several targets, the sequence column, angle harmonics as inputs),
//! which columns are features and targets, and how `thermal fit --model cnn-lstm|bpnn` options
//! become a training configuration. The networks fit and predict on it through
//! [`crate::thermal_fit::NeuralFit`] (mtec-thermal's `Fit`/`Predict`).
//!
//! Decisions where the spec is silent:
//! - Features: the sensors (default every `_c` column but `ambient_c`, as for the regression
//!   models) followed by the extra feature columns (e.g. `angle_deg`, `ambient_c`). An angle
//!   column may enter as its harmonics `cos_k(col)`, `sin_k(col)` (`angle_harmonics`, or named
//!   one by one); the model file stores those names and prediction computes them again from the
//!   angle column.
//! - Rises: the sensor features as rises over each sequence's first row (done by the fit, on
//!   the segments of the data); the model file records how many leading features are rises
//!   (`provenance.rises`) and prediction does the same.
//! - Changes: the targets as their change since each sequence's first row
//!   (`provenance.changes`); prediction adds the first row's measured targets back.
//! - Rows of one sequence are time steps in `time_min` order (sorted here, a repeated time is an
//!   error); the CNN-LSTM's window counts rows, so the time step must be one interval.

use crate::bpnn::Activation;
use crate::bpnn_train::{BpnnTrainConfig, Optimizer};
use crate::cnn_lstm::{Architecture, CnnLstmConfig};
use crate::error::{NnError, Result};
use crate::rotary::{harmonic_feature_names, HarmonicFeature};
use mtec_io::{InputError, Table};
use mtec_thermal::ThermalData;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Which network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NnKind {
    CnnLstm,
    Bpnn,
}

impl NnKind {
    /// The `--model` name (`cnn-lstm`, `bpnn`).
    pub fn name(self) -> &'static str {
        match self {
            NnKind::CnnLstm => "cnn-lstm",
            NnKind::Bpnn => "bpnn",
        }
    }
    /// The kind named `name`.
    pub fn from_name(name: &str) -> Option<NnKind> {
        match name {
            "cnn-lstm" => Some(NnKind::CnnLstm),
            "bpnn" => Some(NnKind::Bpnn),
            _ => None,
        }
    }
}

/// The options of a neural fit on a thermal log (`None`: the network's default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NnFitOptions {
    pub kind: NnKind,
    /// cnn-lstm: the column that splits an experiment into sequences (e.g. `angle_deg`).
    pub sequence_by: Option<String>,
    /// Extra feature columns after the sensors; `cos_K(COL)`/`sin_K(COL)` are harmonics of the
    /// angle column COL (degrees).
    pub features: Vec<String>,
    /// Give each angle feature (name ending in `_deg`) as its first N harmonics.
    pub angle_harmonics: Option<u8>,
    /// The sensors as rises over the first row of each sequence.
    pub rises: bool,
    /// The targets as their change since each sequence's first row; prediction adds the
    /// data's first row back, so the data to predict must hold it.
    pub changes: bool,
    /// Largest number of epochs (bpnn: Levenberg–Marquardt iterations; default 200).
    pub epochs: Option<usize>,
    pub patience: Option<usize>,
    /// cnn-lstm: time steps per window, rows.
    pub window: Option<usize>,
    pub conv_channels: Option<usize>,
    pub lstm_hidden: Option<usize>,
    pub learning_rate: Option<f64>,
    pub final_lr_fraction: Option<f64>,
    pub batch_size: Option<usize>,
    /// bpnn: hidden units.
    pub hidden: Option<usize>,
    /// Weight decay (0: none): bpnn λ·‖w‖² in Levenberg–Marquardt, cnn-lstm AdamW's decay.
    #[serde(default)]
    pub weight_decay: f64,
    /// Seed of the weights and batch order.
    pub seed: u64,
}

impl NnFitOptions {
    /// The options of `kind` with every default.
    pub fn new(kind: NnKind) -> Self {
        NnFitOptions {
            kind,
            sequence_by: None,
            features: Vec::new(),
            angle_harmonics: None,
            rises: false,
            changes: false,
            epochs: None,
            patience: None,
            window: None,
            conv_channels: None,
            lstm_hidden: None,
            learning_rate: None,
            final_lr_fraction: None,
            batch_size: None,
            hidden: None,
            weight_decay: 0.0,
            seed: 42,
        }
    }

    /// The CNN-LSTM training configuration of these options.
    pub fn cnn_lstm_config(&self) -> CnnLstmConfig {
        let d = CnnLstmConfig::default();
        CnnLstmConfig {
            architecture: Architecture {
                window: self.window.unwrap_or(d.architecture.window),
                conv_channels: self.conv_channels.unwrap_or(d.architecture.conv_channels),
                kernel: d.architecture.kernel,
                lstm_hidden: self.lstm_hidden.unwrap_or(d.architecture.lstm_hidden),
            },
            max_epochs: self.epochs.unwrap_or(d.max_epochs),
            batch_size: self.batch_size.unwrap_or(d.batch_size),
            learning_rate: self.learning_rate.unwrap_or(d.learning_rate),
            final_learning_rate_fraction: self
                .final_lr_fraction
                .unwrap_or(d.final_learning_rate_fraction),
            patience: self.patience.unwrap_or(d.patience),
            weight_decay: self.weight_decay,
            seed: self.seed,
            ..d
        }
    }

    /// The BPNN training configuration of these options (sigmoid, Levenberg–Marquardt).
    pub fn bpnn_config(&self) -> BpnnTrainConfig {
        let d = BpnnTrainConfig::default();
        BpnnTrainConfig {
            hidden: self.hidden.unwrap_or(d.hidden),
            activation: Activation::Sigmoid,
            optimizer: Optimizer::LevenbergMarquardt,
            max_epochs: self.epochs.unwrap_or(200),
            patience: self.patience,
            weight_decay: self.weight_decay,
            seed: self.seed,
            ..d
        }
    }
}

/// Resolves `ez` or `ez_um` against the header (exact name first).
pub fn resolve(t: &Table, name: &str) -> Option<String> {
    if t.has(name) {
        return Some(name.to_string());
    }
    ["_um", "_urad", "_c", "_mm", "_deg"]
        .iter()
        .map(|s| format!("{name}{s}"))
        .find(|n| t.has(n))
}

fn header_error(t: &Table, msg: String) -> NnError {
    NnError::Input(InputError::at(&t.path, t.header_line, 1, msg))
}

/// The columns of a fit: targets, features (sensors first), how many leading features are
/// sensors, and the sequence column.
#[derive(Debug, Clone, PartialEq)]
pub struct Columns {
    pub targets: Vec<String>,
    pub features: Vec<String>,
    pub n_sensors: usize,
    pub sequence_by: Option<String>,
}

/// Which columns of `t` the fit reads: the comma-separated `target` names, the `sensors`
/// (every `_c` column but `ambient_c` when empty), then the options' extra features (with
/// harmonics). Missing columns are located at the header; inconsistent options are
/// [`NnError::Config`].
pub fn resolve_columns(
    t: &Table,
    target: &str,
    sensors: &[String],
    o: &NnFitOptions,
) -> Result<Columns> {
    let mut targets = Vec::new();
    for name in target.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        targets.push(resolve(t, name).ok_or_else(|| {
            header_error(
                t,
                format!(
                    "missing target column `{name}`; the header has: {}",
                    t.header.join(", ")
                ),
            )
        })?);
    }
    if targets.is_empty() {
        return Err(NnError::Config("--target needs at least one column".into()));
    }
    let mut features: Vec<String> = if sensors.is_empty() {
        t.columns_with_suffix("_c")
            .into_iter()
            .filter(|c| c != "ambient_c")
            .collect()
    } else {
        sensors
            .iter()
            .map(|s| {
                resolve(t, s).ok_or_else(|| header_error(t, format!("missing sensor column `{s}`")))
            })
            .collect::<Result<_>>()?
    };
    let n_sensors = features.len();
    if o.angle_harmonics == Some(0) {
        return Err(NnError::Config(
            "--angle-harmonics needs at least 1 harmonic".into(),
        ));
    }
    if o.angle_harmonics.is_some()
        && !o
            .features
            .iter()
            .any(|f| resolve(t, f).is_some_and(|name| name.ends_with("_deg")))
    {
        return Err(NnError::Config(
            "--angle-harmonics needs an angle column in degrees (name ending in `_deg`) among --features".into(),
        ));
    }
    for f in &o.features {
        let derived = HarmonicFeature::parse(f);
        let column = derived.as_ref().map_or(f.as_str(), |h| h.column.as_str());
        let name = resolve(t, column)
            .ok_or_else(|| header_error(t, format!("missing feature column `{column}`")))?;
        let names = match (derived, o.angle_harmonics) {
            (Some(h), _) => vec![HarmonicFeature { column: name, ..h }.name()],
            (None, Some(n)) if name.ends_with("_deg") => harmonic_feature_names(&name, n),
            (None, _) => vec![name],
        };
        for name in names {
            if !features.contains(&name) {
                features.push(name);
            }
        }
    }
    if features.is_empty() {
        return Err(header_error(
            t,
            "no feature columns: the file has no `_c` sensor column and no --features".into(),
        ));
    }
    let kernel = CnnLstmConfig::default().architecture.kernel;
    if o.kind == NnKind::CnnLstm && features.len() < kernel {
        return Err(header_error(
            t,
            format!(
                "the CNN-LSTM's convolution (width {kernel}) needs at least {kernel} features; the data have {}: {} (add --features columns)",
                features.len(),
                features.join(", ")
            ),
        ));
    }
    if let Some(f) = features.iter().find(|f| targets.contains(f)) {
        return Err(NnError::Config(format!(
            "`{f}` is both a feature and a target"
        )));
    }
    let sequence_by = match &o.sequence_by {
        Some(c) => Some(
            resolve(t, c)
                .ok_or_else(|| header_error(t, format!("missing column `{c}` (--sequence-by)")))?,
        ),
        None => None,
    };
    Ok(Columns {
        targets,
        features,
        n_sensors,
        sequence_by,
    })
}

/// A thermal log as mtec-thermal's [`ThermalData`] (the one data set of every thermal and
/// neural model), read for a network: its `sensor_names`/`temps_c` are the features (sensors
/// first, then the extra inputs such as `angle_deg` or its harmonics), its `target` and
/// `more_targets` the targets, its `sequence` the sequence column; the rows are ordered by
/// experiment (numerically), sequence value and time, so that every sequence is one contiguous
/// [`ThermalData::segments`] run.
#[derive(Debug, Clone)]
pub struct LogData {
    pub data: ThermalData,
    /// The data hold every target (prediction without them: `target` is `None`).
    pub has_targets: bool,
    /// The sampling interval of the sequences (median time step, min), when any has two rows.
    pub interval_min: Option<f64>,
}

/// Relative difference of a time step from the interval that is still the same interval (a
/// logger's clock jitter); a larger one changes what a window of rows spans.
const INTERVAL_TOLERANCE: f64 = 0.01;

/// How to read a log.
#[derive(Debug, Clone, Default)]
pub struct LoadSpec<'a> {
    pub features: &'a [String],
    /// Empty, or absent columns with `need_targets = false`: no targets (prediction only).
    pub targets: &'a [String],
    pub sequence_by: Option<&'a str>,
    pub need_targets: bool,
    /// A time may not repeat within a sequence, and the time step must be one interval
    /// throughout (the CNN-LSTM's window counts rows): `trained_interval_min` when the model
    /// recorded it, the median step of the file otherwise; the first row off it is refused.
    pub strict_time: bool,
    pub trained_interval_min: Option<f64>,
}

/// Reads the log `path` into [`ThermalData`] whose segments are the sequences (one per
/// experiment, or per value of the sequence column within it). Errors on the file's content
/// are located ([`NnError::Input`]).
pub fn load(path: &Path, s: &LoadSpec) -> Result<LogData> {
    let t = Table::read(path)?;
    t.require(&["time_min"])?;
    let exp: Vec<i64> = if t.has("experiment") {
        t.i64_column("experiment")?
    } else {
        vec![1; t.rows.len()]
    };
    let time = t.f64_column("time_min")?;
    let seq_col = match s.sequence_by {
        Some(c) => Some(t.f64_column(c)?),
        None => None,
    };
    // a column of the file, or a harmonic `cos_k(col)` of one (the file's column wins)
    let feats: Vec<Vec<f64>> = s
        .features
        .iter()
        .map(|n| match HarmonicFeature::parse(n).filter(|_| !t.has(n)) {
            Some(h) => Ok(t
                .f64_column(&h.column)?
                .into_iter()
                .map(|deg| h.value(deg))
                .collect()),
            None => t.f64_column(n),
        })
        .collect::<std::result::Result<_, InputError>>()?;
    let targets = s.targets;
    let has_targets = !targets.is_empty() && targets.iter().all(|n| t.has(n));
    if s.need_targets && !has_targets {
        let missing: Vec<&str> = targets
            .iter()
            .filter(|n| !t.has(n))
            .map(|s| s.as_str())
            .collect();
        return Err(header_error(
            &t,
            format!(
                "missing target column(s) {}; the header has: {}",
                missing.join(", "),
                t.header.join(", ")
            ),
        ));
    }
    let targ: Vec<Vec<f64>> = if has_targets {
        targets
            .iter()
            .map(|n| t.f64_column(n))
            .collect::<std::result::Result<_, _>>()?
    } else {
        Vec::new()
    };
    // experiment → sequence key → [(time, row)]
    let mut groups: BTreeMap<u32, BTreeMap<i64, Vec<(f64, usize)>>> = BTreeMap::new();
    for (i, row) in t.rows.iter().enumerate() {
        let e = u32::try_from(exp[i]).map_err(|_| {
            NnError::Input(t.error_at(row, "experiment", "experiment numbers must be 0 or more"))
        })?;
        let key = seq_col.as_ref().map_or(0, |c| (c[i] * 1e6).round() as i64);
        groups
            .entry(e)
            .or_default()
            .entry(key)
            .or_default()
            .push((time[i], i));
    }
    // the file's rows in data order, and the experiment of each
    let mut order: Vec<(u32, usize)> = Vec::with_capacity(t.rows.len());
    // (time step, row of its later sample) of every sequence
    let mut steps: Vec<(f64, usize)> = Vec::new();
    for (e, seqs) in groups {
        for (_, mut rows) in seqs {
            rows.sort_by(|a, b| a.0.total_cmp(&b.0));
            steps.extend(rows.windows(2).map(|w| (w[1].0 - w[0].0, w[1].1)));
            for w in rows.windows(2) {
                if s.strict_time && w[0].0 == w[1].0 {
                    return Err(NnError::Input(t.error_at(
                        &t.rows[w[1].1],
                        "time_min",
                        format!(
                            "time {} min appears twice in one sequence of experiment {e}{}",
                            w[1].0,
                            s.sequence_by
                                .map(|c| format!(" (same {c})"))
                                .unwrap_or_default()
                        ),
                    )));
                }
            }
            order.extend(rows.iter().map(|&(_, i)| (e, i)));
        }
    }
    if order.is_empty() {
        return Err(NnError::Input(InputError::file(
            path,
            "the log has no rows",
        )));
    }
    let pick = |c: &Vec<f64>| order.iter().map(|&(_, i)| c[i]).collect::<Vec<f64>>();
    let named = |names: &[String], cols: &[Vec<f64>]| -> Vec<(String, Vec<f64>)> {
        names.iter().cloned().zip(cols.iter().map(pick)).collect()
    };
    let mut all_targets = named(targets, &targ).into_iter();
    // a value a network cannot take (the reader takes `nan` and `inf` as numbers)
    for (c, name) in feats
        .iter()
        .chain(&targ)
        .zip(s.features.iter().chain(targets))
    {
        if let Some(&(_, i)) = order.iter().find(|&&(_, i)| !c[i].is_finite()) {
            return Err(NnError::Input(t.error_at(
                &t.rows[i],
                &HarmonicFeature::parse(name).map_or(name.clone(), |h| h.column),
                "a non-finite value",
            )));
        }
    }
    let data = ThermalData {
        experiment: order.iter().map(|(e, _)| e.to_string()).collect(),
        time_min: pick(&time),
        sensor_names: s.features.to_vec(),
        temps_c: DMatrix::from_fn(order.len(), feats.len(), |r, j| feats[j][order[r].1]),
        ambient_c: None,
        position_mm: None,
        target: all_targets.next(),
        more_targets: all_targets.collect(),
        sequence: s
            .sequence_by
            .zip(seq_col.as_ref())
            .map(|(n, c)| (n.to_string(), pick(c))),
        source: Some((path.to_path_buf(), t.header_line)),
        lines: order.iter().map(|&(_, i)| t.rows[i].line).collect(),
    };
    let interval_min = median_step(&steps);
    if s.strict_time {
        if let Some(expected) = s.trained_interval_min.or(interval_min) {
            if let Some(&(dt, row)) = steps
                .iter()
                .find(|(dt, _)| (dt - expected).abs() > INTERVAL_TOLERANCE * expected)
            {
                let why = match s.trained_interval_min {
                    Some(_) => {
                        format!("the model was trained on data sampled every {expected} min")
                    }
                    None => format!("the log is sampled every {expected} min (median step)"),
                };
                return Err(NnError::Input(t.error_at(
                    &t.rows[row],
                    "time_min",
                    format!(
                        "a time step of {dt} min, but {why}: the CNN-LSTM's window counts rows, \
                         so it would span other minutes here; resample the log to one step of \
                         {expected} min (each gap becomes its own experiment)"
                    ),
                )));
            }
        }
    }
    Ok(LogData {
        data,
        has_targets,
        interval_min,
    })
}

/// The median of the time steps (min), if there is one.
fn median_step(steps: &[(f64, usize)]) -> Option<f64> {
    let mut v: Vec<f64> = steps.iter().map(|s| s.0).filter(|d| *d > 0.0).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weight decay reaches both networks' training configurations, and options written
    /// before it existed still read (as no decay).
    #[test]
    fn weight_decay_reaches_both_trainers_and_defaults_to_none() {
        let mut o = NnFitOptions::new(NnKind::CnnLstm);
        assert_eq!(o.cnn_lstm_config().weight_decay, 0.0);
        o.weight_decay = 0.25;
        assert_eq!(o.cnn_lstm_config().weight_decay, 0.25);
        assert_eq!(o.bpnn_config().weight_decay, 0.25);
        let mut old = serde_json::to_value(NnFitOptions::new(NnKind::Bpnn)).unwrap();
        old.as_object_mut().unwrap().remove("weight_decay").unwrap();
        let read: NnFitOptions = serde_json::from_value(old).unwrap();
        assert_eq!(read, NnFitOptions::new(NnKind::Bpnn));
    }
}
