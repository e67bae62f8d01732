//! `thermal fit --model bpnn|cnn-lstm` on a thermal log of one target, `--model auto
//! --with-networks` and `thermal cv --model bpnn|cnn-lstm` ([`cv`]): the networks through
//! mtec-thermal's `Fit`/`Predict` ([`mtec_nn::thermal_fit`]), so they are split, validated
//! forward in time and scored by the regression models' own code (`--train-until`,
//! `--train/--test`, `--block-min`, the duty-cycle blocks of `--input`, [`Metrics`]). The
//! rotary logs (several targets, `--sequence-by`, `--features`, `--angle-harmonics`,
//! `--changes`) take [`super::neural`]'s route, on the same types, split by experiments.
//!
//! The model file is the network's own format (`mtec.bpnn/1`, `mtec.cnn-lstm/1`); its
//! `provenance` holds `thermal_data: true`, the data file, the split, the training and test
//! metrics, the forward validation, the sampling interval and (auto) every candidate's forward
//! score. `thermal predict` reads it back as the same [`NeuralThermalModel`] ([`predict_log`]).
//! Every training (one per forward fold, then the final fit) reports its epochs to the observer
//! and stops after the current epoch when the observer asks (Ctrl-C).

use super::{
    load_table, located, metrics_line, write_candidates, CvOptions, CvOutcome, FitOptions,
};
use crate::observer::Relay;
use crate::{Error, Observer, Result};
use mtec_io::{InputError, OutputGuard, Table};
use mtec_nn::cnn_lstm::CnnLstmConfig;
use mtec_nn::thermal_fit::{
    off_interval, sample_interval, sensor_inputs, Monitored, Network, NeuralFit,
    NeuralThermalModel, Training,
};
use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_nn::Quiet;
use mtec_thermal::auto::{CandidateScore, ExtraCandidate};
use mtec_thermal::kind::{validate_forward, Validated};
use mtec_thermal::model_file::{file_of, metrics_on, split_rows, worse_warning, Rows, SplitBy};
use mtec_thermal::registry::{self, ModelSpec};
use mtec_thermal::validate::ForwardCv;
use mtec_thermal::{Fit, Metrics, Predict, ThermalData, ThermalError, ThermalModel};
use serde::Serialize;
use std::cell::RefCell;
use std::fmt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Whether a network fit of `target` with `nn` goes this route (one target, the sensors only).
pub fn takes(target: &str, nn: &NnFitOptions) -> bool {
    !target.contains(',')
        && nn.sequence_by.is_none()
        && nn.features.is_empty()
        && nn.angle_harmonics.is_none()
        && !nn.changes
}

/// A network fitted on a log and written (`output`), with the regression models' scores.
#[derive(Debug, Clone, Serialize)]
pub struct LogFitOutcome {
    pub output: PathBuf,
    pub kind: NnKind,
    /// The model file's format (`mtec.bpnn/1`, `mtec.cnn-lstm/1`).
    pub format: String,
    /// One line: the network, its size and how the training ended.
    pub summary: String,
    pub training: Training,
    pub train_metrics: Metrics,
    pub test_metrics: Option<Metrics>,
    /// Forward validation on the training rows (`None`: fewer than two blocks).
    pub validation: Option<ForwardCv>,
    /// `--model auto --with-networks`: every candidate's forward score.
    pub candidates: Vec<CandidateScore>,
    pub warnings: Vec<String>,
    /// The model file written (JSON).
    #[serde(skip)]
    pub model_json: String,
}

/// The report as `thermal fit` prints it for the regression models.
impl fmt::Display for LogFitOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !self.candidates.is_empty() {
            write_candidates(f, &self.candidates)?;
        }
        writeln!(f, "{}", self.summary)?;
        metrics_line(f, "train", &self.train_metrics)?;
        if let Some(v) = &self.validation {
            writeln!(
                f,
                "forward validation on the training rows: {} folds, pooled RMSE {:.3} um, mean {:.3} ± {:.3} um",
                v.folds.len(),
                v.pooled_rmse_um,
                v.mean_rmse_um(),
                v.rmse_std_error_um
            )?;
        }
        if let Some(m) = &self.test_metrics {
            metrics_line(f, "test", m)?;
        }
        writeln!(f, "wrote {}", self.output.display())
    }
}

/// What `--model auto --with-networks` chose: a regression model (its `mtec.thermal-model/1`
/// file) or a network (its own file).
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum AutoOutcome {
    Regression(Box<super::FitOutcome>),
    Network(Box<LogFitOutcome>),
}

impl fmt::Display for AutoOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AutoOutcome::Regression(o) => write!(f, "{o}"),
            AutoOutcome::Network(o) => write!(f, "{o}"),
        }
    }
}

impl AutoOutcome {
    /// The model file written.
    pub fn model_json(&self) -> Result<String> {
        Ok(match self {
            AutoOutcome::Regression(o) => serde_json::to_string_pretty(&o.file)?,
            AutoOutcome::Network(o) => o.model_json.clone(),
        })
    }
    pub fn warnings(&self) -> &[String] {
        match self {
            AutoOutcome::Regression(o) => &o.warnings,
            AutoOutcome::Network(o) => &o.warnings,
        }
    }
}

/// Auto's model: one of its own candidates' or a network.
#[derive(Debug, Clone)]
pub enum AutoModel {
    Regression(ThermalModel),
    Network(NeuralThermalModel),
}

impl From<ThermalModel> for AutoModel {
    fn from(m: ThermalModel) -> Self {
        AutoModel::Regression(m)
    }
}

impl Predict for AutoModel {
    fn predict(&self, data: &ThermalData) -> std::result::Result<Vec<f64>, ThermalError> {
        match self {
            AutoModel::Regression(m) => m.predict(data),
            AutoModel::Network(m) => m.predict(data),
        }
    }
    fn predictors(&self) -> usize {
        match self {
            AutoModel::Regression(m) => m.predictors(),
            AutoModel::Network(m) => m.predictors(),
        }
    }
}

/// A network as auto's candidate (a fitter of [`AutoModel`]); `last` keeps the report of its
/// latest training (after auto's choice: the refit on every training row).
/// A network takes every sensor it is given, so within auto's sensor budget (issue 17:
/// `--max-sensors`, default 6) it is a candidate only when those are few enough.
struct NetworkCandidate {
    fit: NeuralFit,
    max_sensors: usize,
    last: Rc<RefCell<Option<Training>>>,
}

impl Fit for NetworkCandidate {
    type Model = AutoModel;
    fn fit_rows(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> std::result::Result<AutoModel, ThermalError> {
        let n = sensor_inputs(data, &self.fit.sensors, false)?.0.len();
        if n > self.max_sensors {
            return Err(ThermalError::Invalid(format!(
                "a network takes all its {n} sensors, more than --max-sensors {}: name at most that many with --sensors, or raise --max-sensors",
                self.max_sensors
            )));
        }
        let (model, training) = self.fit.fit_rows_monitored(data, rows, &mut Quiet)?;
        *self.last.borrow_mut() = Some(training);
        Ok(AutoModel::Network(model))
    }
}

/// The options of the regression models that a network does not take.
fn refuse_regression_options(fit: &mtec_thermal::FitOptions) -> Result<()> {
    if fit.k.is_some() || fit.lag || fit.max_sensors.is_some() || !fit.up_sensors.is_empty() {
        return Err(Error::usage(
            "--k, --lag, --max-sensors and --up-sensors/--nut-sensors go with the regression models, not with --model bpnn|cnn-lstm",
        ));
    }
    Ok(())
}

/// The log, its training and test rows, and a CNN-LSTM's check that the log has one sampling
/// interval (its window counts rows).
fn prepared(
    table: &Table,
    target: &str,
    fit: &mtec_thermal::FitOptions,
    split: &SplitBy,
    cnn_lstm: bool,
) -> Result<(ThermalData, Rows)> {
    let data = load_table(table, Some(target), true, Some((fit.input.as_str(), false)))?;
    if let SplitBy::Experiments { train, test } = split {
        if train.is_empty() && !test.is_empty() {
            return Err(Error::usage("--test needs --train"));
        }
    }
    let rows = split_rows(&data, split).map_err(|e| located(&data, &table.path, e))?;
    if rows.train.is_empty() {
        return Err(Error::usage("the training selection holds no rows"));
    }
    if cnn_lstm {
        // the convolution runs over the inputs: at least its width of them
        let kernel = CnnLstmConfig::default().architecture.kernel;
        let (names, _) = sensor_inputs(&data, &fit.sensors, false)
            .map_err(|e| located(&data, &table.path, e))?;
        if names.len() < kernel {
            return Err(Error::Input(InputError::at(&table.path, table.header_line, 1, format!(
                "the CNN-LSTM's convolution (width {kernel}) needs at least {kernel} features; the data have {}: {}",
                names.len(),
                names.join(", ")
            ))));
        }
        check_interval(&data, table, None)?;
    }
    Ok((data, rows))
}

/// A CNN-LSTM's refusal of a log sampled at other steps than `trained` (or than its own median
/// step), located at the first such row's time.
fn check_interval(data: &ThermalData, table: &Table, trained: Option<f64>) -> Result<()> {
    if let Some(interval) = trained.or_else(|| sample_interval(data)) {
        if let Some((i, why)) = off_interval(data, interval, trained.is_some()) {
            let column = table.header.iter().position(|h| h == "time_min");
            return Err(Error::Input(InputError::at(
                &table.path,
                data.lines[i],
                column.map_or(0, |c| c + 1),
                why,
            )));
        }
    }
    Ok(())
}

/// The network's summary line.
fn summary(model: &NeuralThermalModel, training: &Training, interval: Option<f64>) -> String {
    match (&model.network, training) {
        (Network::Bpnn(n), Training::Bpnn(r)) => format!(
            "BPNN {}-{}-{} ({} parameters) on {}: {} Levenberg-Marquardt iterations, best {}; {}",
            n.n_in(),
            n.n_hidden(),
            n.n_out(),
            n.param_count(),
            model.sensors.join(","),
            r.epochs,
            r.best_epoch,
            r.stop_reason
        ),
        (Network::CnnLstm(n), Training::CnnLstm(r)) => format!(
            "CNN-LSTM ({} parameters, window {} rows = {}, {} filters, LSTM {}) on {}: {} epochs, best {}; {}",
            r.parameters,
            n.architecture.window,
            interval
                .map(|i| format!("{} min", i * n.architecture.window as f64))
                .unwrap_or_else(|| "? min".into()),
            n.architecture.conv_channels,
            n.architecture.lstm_hidden,
            model.sensors.join(","),
            r.epochs,
            r.best_epoch,
            r.stop_reason
        ),
        _ => unreachable!("the training report is the network's"),
    }
}

/// The outcome and model file of a network fitted on `rows.train` and validated (`validation`,
/// `candidates`).
#[allow(clippy::too_many_arguments)]
fn network_outcome(
    table: &Table,
    data: &ThermalData,
    rows: Rows,
    model: NeuralThermalModel,
    training: Training,
    validation: Option<ForwardCv>,
    candidates: Vec<CandidateScore>,
    mut warnings: Vec<String>,
    output: &Path,
) -> Result<LogFitOutcome> {
    let err = |e| located(data, &table.path, e);
    warnings.extend(validation.as_ref().and_then(worse_warning));
    if matches!(training.stop_reason(), mtec_nn::StopReason::User { .. }) {
        warnings.push(
            "the training was stopped by the user: the file holds the best epoch so far".into(),
        );
    }
    let pred = model.predict(data).map_err(err)?;
    let train_metrics = metrics_on(&model, data, &rows.train, &pred).map_err(err)?;
    let test_metrics = match rows.test.is_empty() {
        true => None,
        false => Some(metrics_on(&model, data, &rows.test, &pred).map_err(err)?),
    };
    let interval = sample_interval(data);
    let extra = serde_json::json!({
        "data": table.path.display().to_string(),
        "split": rows.split,
        "train_metrics": train_metrics,
        "test_metrics": test_metrics,
        "validation": validation,
        "candidates": candidates,
        "stop_reason": training.stop_reason(),
        "warnings": warnings,
    });
    let model_json = model.to_json(data, extra);
    let (kind, format) = match &model.network {
        Network::Bpnn(_) => (NnKind::Bpnn, mtec_comp::bpnn::FORMAT.to_string()),
        Network::CnnLstm(n) => (NnKind::CnnLstm, n.format.clone()),
    };
    Ok(LogFitOutcome {
        output: output.to_path_buf(),
        kind,
        format,
        summary: summary(&model, &training, interval),
        training,
        train_metrics,
        test_metrics,
        validation,
        candidates,
        warnings,
        model_json,
    })
}

/// [`fit`] of a log already read: the outcome with the model file (`model_json`), not written.
pub fn fit_table(
    table: &Table,
    opts: &FitOptions,
    nn: &NnFitOptions,
    obs: &mut dyn Observer,
) -> Result<LogFitOutcome> {
    refuse_regression_options(&opts.fit)?;
    let (data, rows) = prepared(
        table,
        &opts.target,
        &opts.fit,
        &opts.split,
        nn.kind == NnKind::CnnLstm,
    )?;
    let fitter = NeuralFit {
        options: nn.clone(),
        sensors: opts.fit.sensors.clone(),
        inputs: Vec::new(),
    };
    let mut relay = Relay(obs);
    // forward validation on the blocks of the training rows, as for the regression models;
    // every fold's training reports to the observer and obeys a stop
    let (validation, warnings) = validate_forward(
        &Monitored::new(&fitter, &mut relay),
        &data,
        &rows.train,
        &opts.fit.blocks(),
    );
    let (model, training) = fitter
        .fit_rows_monitored(&data, &rows.train, &mut relay)
        .map_err(|e| located(&data, &table.path, e))?;
    network_outcome(
        table,
        &data,
        rows,
        model,
        training,
        validation,
        Vec::new(),
        warnings,
        &opts.output,
    )
}

/// Fits a BPNN or CNN-LSTM (`nn.kind`) on the training rows of the log, validates it forward
/// on their blocks, scores it on both sets of rows and writes the network's model file.
pub fn fit(opts: &FitOptions, nn: &NnFitOptions, obs: &mut dyn Observer) -> Result<LogFitOutcome> {
    // where the model goes is settled before any work (an input, a directory: exit 2)
    let dest = OutputGuard::new(&[&opts.data]).check(&opts.output)?;
    let outcome = fit_table(&Table::read(&opts.data)?, opts, nn, obs)?;
    dest.write(outcome.model_json.as_bytes())?;
    super::warn_all(obs, &outcome.warnings);
    Ok(outcome)
}

/// The networks `--with-networks` names, with the options of `nn` (its kind ignored).
pub fn network_options(names: &[String], nn: &NnFitOptions) -> Result<Vec<NnFitOptions>> {
    names
        .iter()
        .map(|n| match NnKind::from_name(n.trim()) {
            Some(kind) => Ok(NnFitOptions { kind, ..nn.clone() }),
            None => Err(Error::usage(format!(
                "--with-networks takes bpnn and cnn-lstm, got `{n}`"
            ))),
        })
        .collect()
}

/// [`fit_auto`] of a log already read: the outcome with the model file, not written.
pub fn fit_auto_table(
    table: &Table,
    opts: &FitOptions,
    networks: &[NnFitOptions],
    obs: &mut dyn Observer,
) -> Result<AutoOutcome> {
    let kind = super::checked_kind(&opts.model, &opts.fit)?;
    if kind.name != "auto" || networks.is_empty() {
        return Err(Error::usage("--with-networks goes with --model auto"));
    }
    let cnn = networks.iter().any(|n| n.kind == NnKind::CnnLstm);
    let (data, rows) = prepared(table, &opts.target, &opts.fit, &opts.split, cnn)?;
    let err = |e| located(&data, &table.path, e);
    let ModelSpec::Auto(auto) = ModelSpec::from_options("auto", &opts.fit, &data).map_err(err)?
    else {
        unreachable!("the auto kind's spec")
    };
    // after auto's own families (ranks 0-5): the BPNN, then the CNN-LSTM
    let reports: Vec<Rc<RefCell<Option<Training>>>> =
        networks.iter().map(|_| Rc::default()).collect();
    let extra: Vec<ExtraCandidate<AutoModel>> = networks
        .iter()
        .zip(&reports)
        .map(|(nn, last)| {
            let (name, rank) = match nn.kind {
                NnKind::Bpnn => ("bpnn", 6),
                NnKind::CnnLstm => ("cnn-lstm", 7),
            };
            let fitter: Box<dyn Fit<Model = AutoModel>> = Box::new(NetworkCandidate {
                fit: NeuralFit {
                    options: nn.clone(),
                    sensors: opts.fit.sensors.clone(),
                    inputs: Vec::new(),
                },
                max_sensors: auto.max_sensors,
                last: Rc::clone(last),
            });
            (name.to_string(), rank, fitter)
        })
        .collect();
    obs.progress("auto: scoring every candidate on the forward folds (the networks train once per fold, without progress)");
    let fit = auto
        .fit_with_extra(&data, &rows.train, &registry::auto_offers(), extra)
        .map_err(err)?;
    match fit.model {
        AutoModel::Regression(model) => {
            let validated = Validated {
                model,
                validation: Some(fit.validation),
                candidates: fit.candidates,
                warnings: Vec::new(),
            };
            let file = file_of(validated, &data, rows).map_err(err)?;
            Ok(AutoOutcome::Regression(Box::new(super::FitOutcome {
                output: opts.output.clone(),
                warnings: file.warnings.clone(),
                file,
            })))
        }
        AutoModel::Network(model) => {
            // the report of auto's refit of the chosen network (its last training)
            let i = networks
                .iter()
                .position(|n| {
                    matches!(
                        (&model.network, n.kind),
                        (Network::Bpnn(_), NnKind::Bpnn) | (Network::CnnLstm(_), NnKind::CnnLstm)
                    )
                })
                .expect("a network of the list");
            let training = reports[i].borrow_mut().take().expect("auto refitted it");
            network_outcome(
                table,
                &data,
                rows,
                model,
                training,
                Some(fit.validation),
                fit.candidates,
                Vec::new(),
                &opts.output,
            )
            .map(|o| AutoOutcome::Network(Box::new(o)))
        }
    }
}

/// `thermal fit --model auto --with-networks`: auto's candidates and the networks scored on the
/// same forward folds; the chosen model's file written (a regression model's
/// `mtec.thermal-model/1`, or the network's own format).
pub fn fit_auto(
    opts: &FitOptions,
    networks: &[NnFitOptions],
    obs: &mut dyn Observer,
) -> Result<AutoOutcome> {
    let dest = OutputGuard::new(&[&opts.data]).check(&opts.output)?;
    let outcome = fit_auto_table(&Table::read(&opts.data)?, opts, networks, obs)?;
    dest.write(outcome.model_json()?.as_bytes())?;
    super::warn_all(obs, outcome.warnings());
    Ok(outcome)
}

/// The predictions of a network fitted on a log ([`NeuralThermalModel`]) for every row of the
/// log `path` (the target when it has it), after a CNN-LSTM's check of the sampling interval.
pub fn predict_log(
    path: &Path,
    model: &NeuralThermalModel,
    trained_interval: Option<f64>,
) -> Result<(ThermalData, Vec<f64>)> {
    let table = Table::read(path)?;
    let data = load_table(&table, Some(&model.target), false, None)?;
    if matches!(model.network, Network::CnnLstm(_)) {
        check_interval(&data, &table, trained_interval)?;
    }
    let pred = model.predict(&data).map_err(|e| located(&data, path, e))?;
    Ok((data, pred))
}

/// `thermal cv --model bpnn|cnn-lstm`: a network of one target and its sensors (`nn`, its kind
/// `opts.model`'s) validated over the whole log by the regression models' own code
/// ([`super::cv`]: the same forward folds or left-out blocks, the same [`Metrics`]); every
/// training reports its epochs to the observer and stops when it asks. Slow: one training per
/// fold. A regression model goes to [`super::cv`].
pub fn cv(opts: &CvOptions, nn: &NnFitOptions, obs: &mut dyn Observer) -> Result<CvOutcome> {
    let Some(kind) = NnKind::from_name(&opts.model) else {
        return super::cv(opts, obs);
    };
    let nn = &NnFitOptions { kind, ..nn.clone() };
    if !takes(&opts.target, nn) {
        return Err(Error::usage("thermal cv validates a network of one target and its sensors (no --sequence-by, --features, --angle-harmonics or --changes; those split by --train/--test experiments in thermal fit)"));
    }
    refuse_regression_options(&opts.fit)?;
    let table = Table::read(&opts.data)?;
    let cnn_lstm = nn.kind == NnKind::CnnLstm;
    let (data, _) = prepared(&table, &opts.target, &opts.fit, &SplitBy::All, cnn_lstm)?;
    let fitter = NeuralFit {
        options: nn.clone(),
        sensors: opts.fit.sensors.clone(),
        inputs: Vec::new(),
    };
    let outcome = {
        let mut relay = Relay(obs);
        super::validate_cv(&Monitored::new(&fitter, &mut relay), &data, opts)?
    };
    if let CvOutcome::Forward(o) = &outcome {
        super::warn_all(obs, &o.warnings);
    }
    Ok(outcome)
}
