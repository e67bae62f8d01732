//! The neural models as thermal model kinds: mtec-thermal's [`Fit`] and [`Predict`] on
//! [`ThermalData`], so that the networks are validated by the same code, on the same rows and
//! with the same metrics as the regression models: forward (rolling-origin) validation
//! ([`mtec_thermal::validate::forward_cv`]), leave-one-block-out
//! ([`mtec_thermal::validate::block_cv`]), the splits by time or experiment
//! ([`mtec_thermal::model_file::split_rows`]) and [`mtec_thermal::Metrics`] (issue 18, build 2:
//! one data set and one fit/predict/metrics set for every model). The data are a thermal log of
//! one drift target (`ThermalData::from_table`), or a log read by [`crate::thermal_log::load`]
//! with several targets (`more_targets`), inputs that are not temperatures (an angle or its
//! harmonics, [`NeuralFit::inputs`]) and a sequence column (`ThermalData::sequence`: one time
//! series per table angle), as the rotary route of `thermal fit` reads it.
//!
//! How the data become the sequences a network trains on ([`ThermalDataset`], the training
//! representation of this crate):
//! - inputs: the sensors (every `_c` column but `ambient_c`, or the ones named), as rises over
//!   the first row of each segment (experiment, or sequence of it) when `rises` is set, then
//!   the other inputs as they are. They are computed on the whole log before any rows are
//!   chosen, as the regression models' lags are, so a fit on some rows sees the same values a
//!   prediction of the whole log does;
//! - targets: every target of the data, or its change since the segment's first row when
//!   `changes` is set (a prediction then adds that first row's measured targets back);
//! - the rows of a fit form one sequence per run of consecutive rows of one segment. For the
//!   CNN-LSTM the `window − 1` rows before a run (of the same segment) come first as history
//!   (`warmup`: their targets are neither trained on nor scored): a fit on the blocks before a
//!   held-out block still sees the temperatures before each of its own blocks, and never the
//!   drift of a row outside `rows`;
//! - a prediction runs every segment as one sequence from its first row.
//!
//! The network's own early stopping holds out the last 15 % of every training sequence (the
//! library default); the validation of this module's caller is on later rows, never on those.
//!
//! The model file is the network's own format (`mtec.bpnn/1`, `mtec.cnn-lstm/1`): its input and
//! output names are the inputs and the targets, and `provenance` says how it was fitted
//! ([`NeuralThermalModel::to_json`]: `thermal_data: true`, `rises`, `sequence_by`, `changes`,
//! the sampling interval, and whatever the caller adds, e.g. the split and the forward
//! validation); such a file reads back as this model ([`NeuralThermalModel::from_network`]), and so
//! does a rotary file written before the mark. A long training reports its epochs to a
//! [`Monitor`] and stops when asked ([`NeuralFit::fit_rows_monitored`], [`Monitored`]).

use crate::baseline::train_bpnn_baseline_monitored;
use crate::bpnn::Bpnn;
use crate::bpnn_train::TrainReport;
use crate::cnn_lstm::{train_cnn_lstm_monitored, CnnLstm, CnnLstmReport};
use crate::dataset::{Experiment, Sequence, ThermalDataset};
use crate::error::NnError;
use crate::progress::{Monitor, Quiet, StopReason};
use crate::thermal_log::{NnFitOptions, NnKind};
use mtec_thermal::{Fit, Metrics, Predict, ThermalData, ThermalError};
use serde::Serialize;
use std::cell::RefCell;

/// A neural fitter on thermal data: the network and its training ([`NnFitOptions`]), the
/// sensors (every `_c` column when empty) and the inputs after them that are not temperatures
/// (e.g. `angle_deg` or its harmonics, loaded by [`crate::thermal_log::load`]; never rises).
/// It fits every target of the data (`target`, then `more_targets`). `sequence_by`,
/// `features` and `angle_harmonics` of the options are the loader's: a fit with them needs
/// data loaded so (a sequence column, the inputs named).
#[derive(Debug, Clone, PartialEq)]
pub struct NeuralFit {
    pub options: NnFitOptions,
    pub sensors: Vec<String>,
    pub inputs: Vec<String>,
}

/// The trained network.
#[derive(Debug, Clone, PartialEq)]
pub enum Network {
    Bpnn(Bpnn),
    CnnLstm(CnnLstm),
}

/// A network fitted by [`NeuralFit`], with what it needs to build its inputs from a log.
#[derive(Debug, Clone, PartialEq)]
pub struct NeuralThermalModel {
    pub network: Network,
    /// Sensor columns, in input order.
    pub sensors: Vec<String>,
    /// Inputs after the sensors (not temperatures: never rises).
    pub inputs: Vec<String>,
    /// The sensors are rises over the first row of each segment (experiment or sequence).
    pub rises: bool,
    /// The (first) target column it was fitted to.
    pub target: String,
    /// Further targets (the network's further outputs).
    pub more_targets: Vec<String>,
    /// Fitted to the targets' change since each segment's first row: a prediction is the
    /// data's first row plus the predicted change.
    pub changes: bool,
    /// The sequence column of its data (`None`: one sequence per experiment).
    pub sequence_by: Option<String>,
}

/// How the network trained.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Training {
    CnnLstm(CnnLstmReport),
    Bpnn(TrainReport),
}

impl Training {
    pub fn stop_reason(&self) -> &StopReason {
        match self {
            Training::CnnLstm(r) => &r.stop_reason,
            Training::Bpnn(r) => &r.stop_reason,
        }
    }
}

/// Relative difference of a time step from the sampling interval that is still that interval
/// (a logger's clock jitter), as for the rotary logs ([`crate::thermal_log`]).
const INTERVAL_TOLERANCE: f64 = 0.01;

/// The sampling interval of a log (the median time step within its experiments, min).
pub fn sample_interval(data: &ThermalData) -> Option<f64> {
    let mut steps: Vec<f64> = data
        .segments()
        .into_iter()
        .flat_map(|(a, b)| (a + 1..b).map(|i| data.time_min[i] - data.time_min[i - 1]))
        .filter(|d| *d > 0.0)
        .collect();
    steps.sort_by(f64::total_cmp);
    steps.get(steps.len() / 2).copied()
}

/// The first row (index) whose time step from the row before (same experiment) is not
/// `interval`, with the reason: a CNN-LSTM's window counts rows, so every step must be one.
pub fn off_interval(data: &ThermalData, interval: f64, trained: bool) -> Option<(usize, String)> {
    data.segments()
        .into_iter()
        .flat_map(|(a, b)| a + 1..b)
        .find(|&i| {
            let dt = data.time_min[i] - data.time_min[i - 1];
            (dt - interval).abs() > INTERVAL_TOLERANCE * interval
        })
        .map(|i| {
            let (t, e) = (data.time_min[i], &data.experiment[i]);
            if t == data.time_min[i - 1] {
                return (i, format!("time {t} min appears twice in one sequence of experiment {e}: a sequence model needs one row per time step"));
            }
            let why = if trained {
                format!("the model was trained on data sampled every {interval} min")
            } else {
                format!("the log is sampled every {interval} min (median step)")
            };
            let dt = data.time_min[i] - data.time_min[i - 1];
            (i, format!("a time step of {dt} min, but {why}: the CNN-LSTM's window counts rows, so it would span other minutes here; resample the log to one step of {interval} min (each gap becomes its own experiment)"))
        })
}

fn nn_error(e: NnError) -> ThermalError {
    match e {
        NnError::Data(m) | NnError::Config(m) | NnError::Model(m) => ThermalError::Invalid(m),
        other => ThermalError::Invalid(other.to_string()),
    }
}

/// The sensor inputs of every row of `data`: `sensors` (every `_c` column when empty) as temperatures, or as
/// rises over the first row of each experiment.
pub fn sensor_inputs(
    data: &ThermalData,
    sensors: &[String],
    rises: bool,
) -> Result<(Vec<String>, Vec<Vec<f64>>), ThermalError> {
    let idx: Vec<usize> = if sensors.is_empty() {
        // every `_c` column (not a heat-input column attached to the data, e.g. spindle_rpm)
        (0..data.sensor_names.len())
            .filter(|&j| data.sensor_names[j].ends_with("_c"))
            .collect()
    } else {
        // the exact name first (a rotary log's `--sensors` resolved against its header)
        sensors
            .iter()
            .map(|s| match data.sensor_names.iter().position(|n| n == s) {
                Some(j) => Ok(j),
                None => data.sensor_index(s),
            })
            .collect::<Result<_, _>>()?
    };
    let names = idx.iter().map(|&j| data.sensor_names[j].clone()).collect();
    let mut x: Vec<Vec<f64>> = (0..data.len())
        .map(|i| idx.iter().map(|&j| data.temps_c[(i, j)]).collect())
        .collect();
    if rises {
        for (start, end) in data.segments() {
            let first = x[start].clone();
            for row in &mut x[start..end] {
                for (v, v0) in row.iter_mut().zip(&first) {
                    *v -= v0;
                }
            }
        }
    }
    Ok((names, x))
}

/// The model inputs of every row: the sensors (as [`sensor_inputs`]) followed by the `inputs`
/// columns by their exact names (never rises).
pub fn model_inputs(
    data: &ThermalData,
    sensors: &[String],
    inputs: &[String],
    rises: bool,
) -> Result<(Vec<String>, Vec<Vec<f64>>), ThermalError> {
    let (mut names, mut x) = sensor_inputs(data, sensors, rises)?;
    for name in inputs {
        let j = (data.sensor_names.iter())
            .position(|s| s == name)
            .ok_or_else(|| ThermalError::MissingColumn(name.clone()))?;
        names.push(name.clone());
        for (i, row) in x.iter_mut().enumerate() {
            row.push(data.temps_c[(i, j)]);
        }
    }
    Ok((names, x))
}

/// The first row of the segment (experiment or sequence) of every row.
fn segment_starts(data: &ThermalData) -> Vec<usize> {
    let mut s = vec![0; data.len()];
    for (a, b) in data.segments() {
        s[a..b].fill(a);
    }
    s
}

/// Every target of `data` per row (rows × targets), as their change since each segment's first
/// row when `changes`.
fn target_rows(data: &ThermalData, changes: bool) -> Result<Vec<Vec<f64>>, ThermalError> {
    let targets = data.targets();
    if targets.is_empty() {
        data.target_um()?;
    }
    let start = segment_starts(data);
    Ok((0..data.len())
        .map(|i| {
            (targets.iter())
                .map(|(_, y)| if changes { y[i] - y[start[i]] } else { y[i] })
                .collect()
        })
        .collect())
}

/// The sequences of a fit on `rows` (see the module docs): one per run of consecutive rows of
/// one segment (experiment, or sequence of it), after up to `history` earlier rows of that
/// segment as warmup; `targets` per row (rows × targets).
#[cfg(test)]
fn fit_sequences(
    data: &ThermalData,
    inputs: &[Vec<f64>],
    targets: &[Vec<f64>],
    rows: &[usize],
    history: usize,
) -> Vec<Sequence> {
    let runs = fit_runs(data, inputs, targets, rows, history);
    runs.into_iter().map(|(_, seq)| seq).collect()
}

/// [`fit_sequences`], each with the first row of its run (whose experiment it is).
fn fit_runs(
    data: &ThermalData,
    inputs: &[Vec<f64>],
    targets: &[Vec<f64>],
    rows: &[usize],
    history: usize,
) -> Vec<(usize, Sequence)> {
    let start_of = segment_starts(data);
    let mut out = Vec::new();
    let mut k = 0;
    while k < rows.len() {
        let first = rows[k];
        let mut last = first;
        while k + 1 < rows.len()
            && rows[k + 1] == last + 1
            && start_of[rows[k + 1]] == start_of[first]
        {
            k += 1;
            last = rows[k];
        }
        k += 1;
        let from = first.saturating_sub(history).max(start_of[first]);
        let seq = Sequence {
            features: inputs[from..=last].to_vec(),
            targets: targets[from..=last].to_vec(),
            warmup: first - from,
        };
        out.push((first, seq));
    }
    out
}

/// The training representation of sequences (the tensors' source): consecutive sequences of
/// one experiment form one [`Experiment`], numbered by the experiment's label when every label
/// is a number (the rotary logs), in order of appearance otherwise.
fn training_set(
    data: &ThermalData,
    feature_names: Vec<String>,
    target_names: Vec<String>,
    sequences: Vec<(usize, Sequence)>,
) -> ThermalDataset {
    let numbered = data.experiment.iter().all(|e| e.parse::<u32>().is_ok());
    let mut experiments: Vec<Experiment> = Vec::new();
    let mut last: Option<&str> = None;
    for (row, seq) in sequences {
        let label = data.experiment[row].as_str();
        if last != Some(label) {
            let id = match numbered {
                true => label.parse().expect("a number"),
                false => experiments.len() as u32 + 1,
            };
            experiments.push(Experiment {
                id,
                sequences: Vec::new(),
            });
            last = Some(label);
        }
        experiments.last_mut().expect("pushed").sequences.push(seq);
    }
    ThermalDataset {
        feature_names,
        target_names,
        experiments,
    }
}

/// The training representation of `rows` of `data` with the model inputs `sensors` and
/// `inputs` (as rises of the sensors when `rises`), every target (as changes when `changes`),
/// `history` earlier rows of each run as warmup (module docs).
pub(crate) fn training_data(
    data: &ThermalData,
    (sensors, inputs): (&[String], &[String]),
    (rises, changes): (bool, bool),
    rows: &[usize],
    history: usize,
) -> Result<ThermalDataset, ThermalError> {
    let target_names: Vec<String> = (data.targets().iter())
        .map(|(n, _)| n.to_string())
        .collect();
    let targets = target_rows(data, changes)?;
    let (names, x) = model_inputs(data, sensors, inputs, rises)?;
    let runs = fit_runs(data, &x, &targets, rows, history);
    Ok(training_set(data, names, target_names, runs))
}

impl NeuralFit {
    fn history(&self) -> usize {
        match self.options.kind {
            NnKind::CnnLstm => {
                (self.options.cnn_lstm_config().architecture.window).saturating_sub(1)
            }
            NnKind::Bpnn => 0,
        }
    }

    /// The training representation of `rows` of `data` (module docs): the inputs and targets
    /// as this fit builds them, one sequence per run of rows with its history.
    pub(crate) fn training_data(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> Result<ThermalDataset, ThermalError> {
        training_data(
            data,
            (&self.sensors, &self.inputs),
            (self.options.rises, self.options.changes),
            rows,
            self.history(),
        )
    }

    /// Every row of `data` as CSV `experiment,sequence,step,<inputs>,<targets>` (experiments
    /// numbered as in training, sequence and step counted from 0 within each), the inputs and
    /// targets as this fit trains on them (rises, changes): the exchange format of
    /// `bench/cnn_lstm.sh` with its PyTorch peer.
    pub fn exchange_csv(&self, data: &ThermalData) -> Result<String, ThermalError> {
        let all: Vec<usize> = (0..data.len()).collect();
        Ok(training_data(
            data,
            (&self.sensors, &self.inputs),
            (self.options.rises, self.options.changes),
            &all,
            0,
        )?
        .to_csv())
    }

    /// [`Fit::fit_rows`] that reports the epochs to `monitor` and stops when it asks (keeping
    /// the best epoch's weights), and returns how the training went.
    pub fn fit_rows_monitored(
        &self,
        data: &ThermalData,
        rows: &[usize],
        monitor: &mut dyn Monitor,
    ) -> Result<(NeuralThermalModel, Training), ThermalError> {
        let o = &self.options;
        if (o.sequence_by.is_some() && data.sequence.is_none())
            || ((!o.features.is_empty() || o.angle_harmonics.is_some()) && self.inputs.is_empty())
        {
            return Err(ThermalError::Invalid(
                "a network with a sequence column, extra features or angle harmonics needs the data loaded with them (mtec_nn::thermal_log::load); a thermal log gives its sensors only".into(),
            ));
        }
        let train = self.training_data(data, rows)?;
        let (names, target_names) = (train.feature_names.clone(), train.target_names.clone());
        let n_sensors = names.len() - self.inputs.len();
        let (network, training) = match o.kind {
            NnKind::Bpnn => {
                let (net, report) =
                    train_bpnn_baseline_monitored(&train, &o.bpnn_config(), monitor)
                        .map_err(nn_error)?;
                (Network::Bpnn(net), Training::Bpnn(report))
            }
            NnKind::CnnLstm => {
                let (net, report) = train_cnn_lstm_monitored(&train, &o.cnn_lstm_config(), monitor)
                    .map_err(nn_error)?;
                (Network::CnnLstm(net), Training::CnnLstm(report))
            }
        };
        let mut target_names = target_names.into_iter();
        let model = NeuralThermalModel {
            network,
            inputs: names[n_sensors..].to_vec(),
            sensors: names[..n_sensors].to_vec(),
            rises: o.rises,
            target: target_names.next().expect("a target"),
            more_targets: target_names.collect(),
            changes: o.changes,
            sequence_by: data.sequence.as_ref().map(|(n, _)| n.clone()),
        };
        Ok((model, training))
    }
}

impl Fit for NeuralFit {
    type Model = NeuralThermalModel;

    fn fit_rows(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> Result<NeuralThermalModel, ThermalError> {
        self.fit_rows_monitored(data, rows, &mut Quiet).map(|m| m.0)
    }
}

/// A [`NeuralFit`] whose every training (one per validation fold) reports to one monitor and
/// stops when it asks: the forward validation of a long training shows progress and obeys
/// Ctrl-C.
pub struct Monitored<'a> {
    pub fit: &'a NeuralFit,
    monitor: RefCell<&'a mut dyn Monitor>,
}

impl<'a> Monitored<'a> {
    pub fn new(fit: &'a NeuralFit, monitor: &'a mut dyn Monitor) -> Self {
        Monitored {
            fit,
            monitor: RefCell::new(monitor),
        }
    }
}

impl Fit for Monitored<'_> {
    type Model = NeuralThermalModel;
    fn fit_rows(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> Result<NeuralThermalModel, ThermalError> {
        let mut m = self.monitor.borrow_mut();
        self.fit
            .fit_rows_monitored(data, rows, &mut **m)
            .map(|m| m.0)
    }
}

/// `provenance.training.model`: the network's own provenance, beside what the caller put
/// under `training` (e.g. the training report).
fn with_training(p: &mut serde_json::Value, model: serde_json::Value) {
    match p.get_mut("training") {
        Some(serde_json::Value::Object(t)) => {
            t.insert("model".into(), model);
        }
        _ => p["training"] = serde_json::json!({ "model": model }),
    }
}

impl NeuralThermalModel {
    /// Every target name, in output order.
    pub fn targets(&self) -> Vec<String> {
        std::iter::once(self.target.clone())
            .chain(self.more_targets.iter().cloned())
            .collect()
    }

    /// Every input name (the sensors, then the other inputs), in input order.
    pub fn input_names(&self) -> Vec<String> {
        self.sensors.iter().chain(&self.inputs).cloned().collect()
    }

    /// The model file: the network's own format, its `provenance` the training's
    /// (`training.model`) and `extra`'s keys, plus `thermal_data: true`, `rises` (the number of
    /// leading inputs that are rises), `sequence_by`, `changes` and the log's sampling interval
    /// (a CNN-LSTM refuses data sampled otherwise).
    pub fn to_json(&self, data: &ThermalData, extra: serde_json::Value) -> String {
        let mut p = serde_json::json!({
            "thermal_data": true,
            "target": self.target,
            "rises": if self.rises { self.sensors.len() } else { 0 },
            "sequence_by": self.sequence_by,
            "changes": self.changes,
            "sample_interval_min": sample_interval(data),
        });
        if let serde_json::Value::Object(extra) = extra {
            p.as_object_mut().expect("object").extend(extra);
        }
        match &self.network {
            Network::Bpnn(n) => {
                let mut n = n.clone();
                with_training(&mut p, std::mem::take(&mut n.provenance));
                n.provenance = p;
                n.to_json()
            }
            Network::CnnLstm(n) => {
                let mut n = n.clone();
                with_training(&mut p, std::mem::take(&mut n.provenance));
                n.provenance = p;
                n.to_json()
            }
        }
    }

    /// The model a file of [`NeuralThermalModel::to_json`] holds (`None`: a network fitted
    /// otherwise, e.g. on a volumetric grid), and the sampling interval it was trained on. A
    /// file marked `thermal_data` is one of a log of one target; a file with `sequence_by`,
    /// `rises` and `changes` in its provenance but no mark is one of the rotary route (several
    /// targets, extra inputs), read the same way: the first `rises` inputs are the sensors.
    pub fn from_network(network: Network) -> Option<(NeuralThermalModel, Option<f64>)> {
        let (p, inputs, targets) = match &network {
            Network::Bpnn(n) => (&n.provenance, &n.input_names, &n.output_names),
            Network::CnnLstm(n) => (&n.provenance, &n.feature_names, &n.target_names),
        };
        let marked = p.get("thermal_data").and_then(|v| v.as_bool()) == Some(true);
        let routed =
            p.get("changes").is_some_and(|v| v.is_boolean()) && p.get("sequence_by").is_some();
        if !(marked || routed) || targets.is_empty() {
            return None;
        }
        let k = p.get("rises").and_then(|v| v.as_u64()).unwrap_or(0) as usize;
        let rises = k > 0;
        let n_sensors = if rises {
            k.min(inputs.len())
        } else {
            inputs.len()
        };
        let interval = p.get("sample_interval_min").and_then(|v| v.as_f64());
        let model = NeuralThermalModel {
            sensors: inputs[..n_sensors].to_vec(),
            inputs: inputs[n_sensors..].to_vec(),
            rises,
            target: targets[0].clone(),
            more_targets: targets[1..].to_vec(),
            changes: p.get("changes").and_then(|v| v.as_bool()) == Some(true),
            sequence_by: (p.get("sequence_by").and_then(|v| v.as_str())).map(str::to_string),
            network,
        };
        Some((model, interval))
    }

    /// Predicted targets (rows × targets, in [`NeuralThermalModel::targets`] order) for every
    /// row of `data`: a CNN-LSTM runs every segment as one sequence from its first row. A model
    /// of changes adds each segment's first measured targets, which the data must hold.
    pub fn predict_targets(&self, data: &ThermalData) -> Result<Vec<Vec<f64>>, ThermalError> {
        let (names, inputs) = model_inputs(data, &self.sensors, &self.inputs, self.rises)?;
        let targets = self.targets();
        let mut pred: Vec<Vec<f64>> = match &self.network {
            Network::Bpnn(net) => inputs
                .iter()
                .map(|x| net.predict(x).map_err(|e| nn_error(e.into())))
                .collect::<Result<_, _>>()?,
            Network::CnnLstm(net) => {
                let sequences = data
                    .segments()
                    .into_iter()
                    .map(|(a, b)| Sequence {
                        features: inputs[a..b].to_vec(),
                        targets: vec![vec![0.0; targets.len()]; b - a],
                        warmup: 0,
                    })
                    .collect();
                let all = ThermalDataset {
                    feature_names: names,
                    target_names: targets.clone(),
                    experiments: vec![Experiment { id: 1, sequences }],
                };
                net.predict(&all).map_err(nn_error)?
            }
        };
        if self.changes {
            let measured = data.targets();
            if measured.len() != targets.len() {
                return Err(ThermalError::Invalid("the model predicts changes since each sequence's first row (fit --changes): the data must hold the targets, at least of that first row".into()));
            }
            let start = segment_starts(data);
            for (i, p) in pred.iter_mut().enumerate() {
                for (v, (_, y)) in p.iter_mut().zip(&measured) {
                    *v += y[start[i]];
                }
            }
        }
        Ok(pred)
    }
}

/// mtec-thermal's [`Metrics`] of predictions `pred` (rows × targets) of every target of
/// `measured` (the same rows), per target in the data's order, for a model of `predictors`
/// inputs: the one metrics set of every model, applied to each output of a network.
pub fn target_metrics(
    measured: &ThermalData,
    pred: &[Vec<f64>],
    predictors: usize,
) -> Result<Vec<(String, Metrics)>, ThermalError> {
    let targets = measured.targets();
    if targets.is_empty() {
        measured.target_um()?;
    }
    if pred.len() != measured.len() || pred.iter().any(|p| p.len() != targets.len()) {
        return Err(ThermalError::Invalid(format!(
            "{} predictions of {} targets for {} rows",
            pred.len(),
            targets.len(),
            measured.len()
        )));
    }
    Ok((targets.iter().enumerate())
        .map(|(c, (name, y))| {
            let p: Vec<f64> = pred.iter().map(|r| r[c]).collect();
            (name.to_string(), Metrics::new(y, &p, predictors))
        })
        .collect())
}

impl Predict for NeuralThermalModel {
    /// The (first) target's predictions; [`NeuralThermalModel::predict_targets`] gives every
    /// target's.
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        Ok(self
            .predict_targets(data)?
            .into_iter()
            .map(|y| y[0])
            .collect())
    }

    /// The inputs (sensors and the others): what adjusted R² and F count as regressors.
    fn predictors(&self) -> usize {
        self.sensors.len() + self.inputs.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::baseline::train_bpnn_baseline;
    use mtec_thermal::validate::{forward_cv, forward_folds, split_at_time};
    use nalgebra::DMatrix;

    /// Two experiments of a three-body thermal network: sensors s1 (fast), s2 (slow) and s3
    /// (slower, on the far side) follow a heat input that steps on and off; the drift is
    /// 2·s1 + 3·lag(s2) µm, the lag an unsensed body between s2 and s3.
    fn log() -> ThermalData {
        let (mut exp, mut time, mut temps, mut y) = (vec![], vec![], vec![], vec![]);
        for (e, on) in [("1", 60.0), ("2", 100.0)] {
            let (mut s1, mut s2, mut lag, mut s3) = (20.0, 20.0, 20.0, 20.0);
            for k in 0..120 {
                let t = k as f64 * 2.0;
                let q = if t < on { 1.0 } else { 0.0 };
                s1 += 0.2 * (20.0 + 8.0 * q - s1);
                s2 += 0.05 * (s1 - s2);
                lag += 0.1 * (s2 - lag);
                s3 += 0.03 * (lag - s3);
                exp.push(e.to_string());
                time.push(t);
                temps.push([s1, s2, s3]);
                y.push(2.0 * (s1 - 20.0) + 3.0 * (lag - 20.0));
            }
        }
        let n = y.len();
        ThermalData {
            experiment: exp,
            time_min: time,
            sensor_names: vec!["s1_c".into(), "s2_c".into(), "s3_c".into()],
            temps_c: DMatrix::from_fn(n, 3, |i, j| temps[i][j]),
            ambient_c: None,
            position_mm: None,
            target: Some(("ez_um".into(), y)),
            more_targets: Vec::new(),
            sequence: None,
            source: None,
            lines: (2..n + 2).collect(),
        }
    }

    fn bpnn() -> NeuralFit {
        let mut options = NnFitOptions::new(NnKind::Bpnn);
        options.hidden = Some(4);
        options.epochs = Some(60);
        options.rises = true;
        NeuralFit {
            options,
            sensors: vec![],
            inputs: vec![],
        }
    }

    #[test]
    fn sequences_are_runs_of_one_experiment_with_earlier_rows_as_history() {
        let data = log();
        let (_, x) = sensor_inputs(&data, &[], false).unwrap();
        let y = data.target_um().unwrap();
        // rows 10..20 and 30..40 of experiment 1, 118..122 across the experiments' border
        let rows: Vec<usize> = (10..20).chain(30..40).chain(118..122).collect();
        let yy: Vec<Vec<f64>> = y.iter().map(|&v| vec![v]).collect();
        let seqs = fit_sequences(&data, &x, &yy, &rows, 5);
        let shape: Vec<(usize, usize)> = seqs.iter().map(|s| (s.len(), s.warmup)).collect();
        // 118..120 is the end of experiment 1 (history 113..118), 120..122 the start of 2 (none)
        assert_eq!(shape, vec![(15, 5), (15, 5), (7, 5), (2, 0)]);
        assert_eq!(seqs[1].features[0], x[25]);
        assert_eq!(seqs[1].targets[5], vec![y[30]]);
        assert_eq!(seqs[3].features[0], x[120]);
    }

    #[test]
    fn rises_start_at_each_experiment() {
        let data = log();
        let (names, x) = sensor_inputs(&data, &["s2".into()], true).unwrap();
        assert_eq!(names, vec!["s2_c".to_string()]);
        assert_eq!((x[0][0], x[120][0]), (0.0, 0.0));
        let t = &data.temps_c;
        assert!((x[130][0] - (t[(130, 1)] - t[(120, 1)])).abs() < 1e-12);
    }

    #[test]
    fn a_bpnn_fitted_through_fit_rows_is_the_one_trained_on_the_same_rows_by_hand() {
        let data = log();
        let (train, _) = split_at_time(&data, 150.0);
        let model = bpnn().fit_rows(&data, &train).unwrap();
        // by hand: the same rows as one plain sequence per experiment, the library's training
        let (_, x) = sensor_inputs(&data, &[], true).unwrap();
        let y = data.target_um().unwrap();
        let seq = |r: std::ops::Range<usize>| Sequence {
            features: x[r.clone()].to_vec(),
            targets: y[r].iter().map(|&v| vec![v]).collect(),
            warmup: 0,
        };
        let by_hand = ThermalDataset {
            feature_names: vec!["s1_c".into(), "s2_c".into(), "s3_c".into()],
            target_names: vec!["ez_um".into()],
            experiments: vec![Experiment {
                id: 1,
                sequences: vec![seq(0..76), seq(120..196)],
            }],
        };
        let (net, _) = train_bpnn_baseline(&by_hand, &bpnn().options.bpnn_config()).unwrap();
        let pred = model.predict(&data).unwrap();
        for i in [0, 80, 119, 200, 239] {
            assert_eq!(pred[i], net.predict(&x[i]).unwrap()[0], "row {i}");
        }
    }

    #[test]
    fn forward_validation_of_a_network_is_the_regression_models_own() {
        let data = log();
        let blocks: Vec<Vec<usize>> = vec![
            (0..120).collect(),
            (120..180).collect(),
            (180..240).collect(),
        ];
        let folds = forward_folds(&blocks);
        let cv = forward_cv(&bpnn(), &data, &folds).unwrap();
        assert_eq!(cv.folds.len(), folds.len());
        // each fold scored on its own later rows; the network must beat leaving the drift
        // uncompensated (the drift spans 0-40 um) on every fold
        for f in &cv.folds {
            assert!(!f.worse_than_uncompensated(), "{f:?}");
        }
        assert!(cv.pooled_rmse_um < 3.0, "pooled RMSE {}", cv.pooled_rmse_um);
    }

    #[test]
    fn a_cnn_lstm_fits_and_predicts_every_row() {
        let data = log();
        let mut options = NnFitOptions::new(NnKind::CnnLstm);
        (options.window, options.conv_channels, options.lstm_hidden) = (Some(4), Some(2), Some(4));
        options.epochs = Some(3);
        let fit = NeuralFit {
            options,
            sensors: vec!["s1".into(), "s2".into(), "s3".into()],
            inputs: vec![],
        };
        let (train, _) = split_at_time(&data, 150.0);
        let model = fit.fit_rows(&data, &train).unwrap();
        let pred = model.predict(&data).unwrap();
        assert_eq!(pred.len(), data.len());
        assert!(pred.iter().all(|v| v.is_finite()));
        assert_eq!(model.predictors(), 3);
    }

    #[test]
    fn the_model_file_reads_back_as_the_same_model() {
        let data = log();
        let model = bpnn().fit(&data).unwrap();
        let text = model.to_json(&data, serde_json::json!({"split": {"train_rows": 240}}));
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["format"], "mtec.bpnn/1");
        assert_eq!(v["provenance"]["split"]["train_rows"], 240);
        assert_eq!(v["provenance"]["rises"], 3);
        let net = Network::Bpnn(Bpnn::from_json(&text).unwrap());
        let (back, interval) = NeuralThermalModel::from_network(net).unwrap();
        // the same weights up to serde_json's parsing of the last digit (its `float_roundtrip`
        // feature is off): 1e-12 um
        let (b, m) = (back.predict(&data).unwrap(), model.predict(&data).unwrap());
        assert!(b.iter().zip(&m).all(|(b, m)| (b - m).abs() < 1e-12));
        assert_eq!((back.rises, back.target.as_str()), (true, "ez_um"));
        assert_eq!(interval, Some(2.0));
        // a network fitted otherwise (no `thermal_data` mark) is not read as one
        let mut other = Bpnn::from_json(&text).unwrap();
        other.provenance = serde_json::Value::Null;
        assert!(NeuralThermalModel::from_network(Network::Bpnn(other)).is_none());
    }

    #[test]
    fn a_time_step_off_the_interval_is_found_where_it_is() {
        let mut data = log();
        assert_eq!(off_interval(&data, 2.0, false), None);
        data.time_min[50] += 0.5;
        let (row, why) = off_interval(&data, sample_interval(&data).unwrap(), true).unwrap();
        assert_eq!(row, 50);
        assert!(
            why.contains("a time step of 2.5 min") && why.contains("trained"),
            "{why}"
        );
        // the step from one experiment to the next is not a time step
        assert_eq!(data.time_min[120], 0.0);
    }

    #[test]
    fn rotary_options_are_refused() {
        let mut f = bpnn();
        f.options.sequence_by = Some("angle_deg".into());
        let data = log();
        assert!(matches!(f.fit(&data), Err(ThermalError::Invalid(_))));
    }

    /// A rotary log of two targets, three sensors and one sequence per table angle, written in
    /// time-major order with experiment 2 first: the loader orders it by experiment, angle and
    /// time; a fit through [`NeuralFit`] (rises, changes, angle harmonics) is the network the
    /// sequence data of the rotary route trained by hand (the `ThermalDataset` methods
    /// `rises` and `target_changes`), and its predictions add each sequence's first targets.
    #[test]
    fn a_rotary_fit_through_fit_rows_is_the_sequence_training_by_hand() {
        use crate::cnn_lstm::train_cnn_lstm;
        use crate::thermal_log::{load, LoadSpec};
        let angles = [0.0, 90.0, 180.0, 270.0];
        let mut csv = String::from("experiment,time_min,angle_deg,T1_c,T2_c,T3_c,a_um,b_um\n");
        let temps = |e: f64, t: f64| {
            [
                20.0 + e * 0.3 + 0.05 * t,
                21.0 + 0.02 * t * e,
                19.5 + (t / 30.0).sin(),
            ]
        };
        let motion = |e: f64, t: f64, c: f64| {
            let r = f64::to_radians(c);
            let [t1, t2, _] = temps(e, t);
            [
                2.0 * r.cos() + 0.4 * (t1 - 20.0),
                (2.0 * r).sin() - 0.3 * (t2 - 21.0) + e,
            ]
        };
        for e in [2.0, 1.0, 3.0] {
            for k in 0..12 {
                let t = 20.0 * k as f64;
                for c in angles {
                    let [t1, t2, t3] = temps(e, t);
                    let [a, b] = motion(e, t, c);
                    csv.push_str(&format!("{e},{t},{c},{t1},{t2},{t3},{a},{b}\n"));
                }
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rotary.csv");
        std::fs::write(&path, &csv).unwrap();
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let (sensors, inputs) = (
            s(&["T1_c", "T2_c", "T3_c"]),
            s(&["cos_1(angle_deg)", "sin_1(angle_deg)"]),
        );
        let features: Vec<String> = sensors.iter().chain(&inputs).cloned().collect();
        let targets = s(&["a_um", "b_um"]);
        let spec = LoadSpec {
            features: &features,
            targets: &targets,
            sequence_by: Some("angle_deg"),
            need_targets: true,
            strict_time: true,
            trained_interval_min: None,
        };
        let loaded = load(&path, &spec).unwrap();
        let data = &loaded.data;
        assert_eq!(loaded.interval_min, Some(20.0));
        assert_eq!(data.segments().len(), 3 * 4);
        assert_eq!((data.experiment[0].as_str(), data.time_min[1]), ("1", 20.0));
        // the first row of experiment 1 at 90 deg is the file's line 2 + 12·4 + 1
        assert_eq!(data.lines[12], 2 + 48 + 1);
        let train = mtec_thermal::validate::rows_of_experiments(data, &s(&["1", "2"])).unwrap();
        // by hand: one sequence per (experiment, angle), rows in time order
        let by_hand = ThermalDataset {
            feature_names: features.clone(),
            target_names: targets.clone(),
            experiments: [1u32, 2]
                .iter()
                .map(|&e| Experiment {
                    id: e,
                    sequences: angles
                        .iter()
                        .map(|&c| Sequence {
                            features: (0..12)
                                .map(|k| {
                                    let t = 20.0 * k as f64;
                                    let mut f = temps(e as f64, t).to_vec();
                                    f.extend([c.to_radians().cos(), c.to_radians().sin()]);
                                    f
                                })
                                .collect(),
                            targets: (0..12)
                                .map(|k| motion(e as f64, 20.0 * k as f64, c).to_vec())
                                .collect(),
                            warmup: 0,
                        })
                        .collect(),
                })
                .collect(),
        }
        .rises(3)
        .target_changes();
        let mut options = NnFitOptions::new(NnKind::Bpnn);
        (
            options.hidden,
            options.epochs,
            options.rises,
            options.changes,
        ) = (Some(3), Some(20), true, true);
        let fit = NeuralFit {
            options,
            sensors: sensors.clone(),
            inputs: inputs.clone(),
        };
        let model = fit.fit_rows(data, &train).unwrap();
        let (net, _) = train_bpnn_baseline(&by_hand, &fit.options.bpnn_config()).unwrap();
        let pred = model.predict_targets(data).unwrap();
        // experiment 3 (rows 96..144), angle 180 (rows 120..132): first targets + change
        let (_, x) = model_inputs(data, &sensors, &inputs, true).unwrap();
        let y0 = motion(3.0, 0.0, 180.0);
        for i in [120, 125, 131] {
            let change = net.predict(&x[i]).unwrap();
            for c in 0..2 {
                assert!((pred[i][c] - (y0[c] + change[c])).abs() < 1e-12, "row {i}");
            }
        }
        assert_eq!(model.targets(), targets);
        assert_eq!(model.predictors(), 5);
        // the CNN-LSTM the same way (tiny, two epochs): the same weights, the same predictions
        let mut options = NnFitOptions::new(NnKind::CnnLstm);
        (options.window, options.conv_channels, options.lstm_hidden) = (Some(3), Some(2), Some(3));
        (options.epochs, options.rises, options.changes) = (Some(2), true, true);
        let fit = NeuralFit {
            options,
            sensors,
            inputs,
        };
        let model = fit.fit_rows(data, &train).unwrap();
        let (net, _) = train_cnn_lstm(&by_hand, &fit.options.cnn_lstm_config()).unwrap();
        let Network::CnnLstm(fitted) = &model.network else {
            panic!("a CNN-LSTM")
        };
        assert_eq!(fitted.weights, net.weights);
    }
}
