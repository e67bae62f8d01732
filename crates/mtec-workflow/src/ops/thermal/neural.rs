//! `thermal fit|predict` with the neural models of `mtec-nn` (cargo feature `neural`):
//! `cnn-lstm` and `bpnn`. [`fit_thermal`] sends a log of one target and its sensors to
//! [`super::neural_log`] (split by time or experiments, validated forward like the regression
//! models), and `--model auto --with-networks` there too; the rotary logs (several targets,
//! `--sequence-by`, `--features`, `--angle-harmonics`, `--changes`) take this module's route
//! ([`fit`]), split by whole experiments. Both routes are the same types: the log as
//! mtec-thermal's `ThermalData` (here read by [`mtec_nn::thermal_log::load`]), the network
//! fitted through [`NeuralFit`] (mtec-thermal's `Fit`), predicted through
//! [`NeuralThermalModel`] and scored with mtec-thermal's `Metrics` per target.
//!
//! The model file is the network's own versioned format (`mtec.cnn-lstm/1`, `mtec.bpnn/1`),
//! written by [`NeuralThermalModel::to_json`]; this job adds under `provenance` the data file,
//! the split and the metrics, and [`predict`] reads it back through
//! [`NeuralThermalModel::from_network`]. The training reports its epochs to the observer
//! ([`Observer::progress`]) and stops after the current epoch, keeping the best epoch's
//! weights, when [`Observer::stop_requested`] turns true (the file is still written). candle's
//! thread count is the calling program's to set ([`mtec_nn::threads`]).

use super::neural_log::{self, AutoOutcome, LogFitOutcome};
use super::PredictOptions;
use crate::{Error, Observer, Result};
use mtec_identify::ballbar::{Measurements, Setup};
use mtec_io::{CsvWriter, InputError, OutputGuard, Table};
use mtec_nn::rotary::{
    reading_metrics, reading_rows, MotionRow, ReadingComparison, ReadingRow, TARGET_NAMES,
};
use mtec_nn::thermal_fit::{Network, NeuralFit, NeuralThermalModel};
use mtec_nn::thermal_log::{self, LoadSpec, NnFitOptions, NnKind};
use mtec_nn::{Bpnn, CnnLstm, NnError};
use mtec_thermal::model_file::{split_rows, SplitBy};
use mtec_thermal::{Predict, TargetMetrics, ThermalData};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// Options of [`fit`].
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Thermal log (CSV).
    pub data: PathBuf,
    /// Target columns, comma-separated (`ez_um` or `ez`).
    pub target: String,
    /// Sensor columns (every `_c` column but `ambient_c` when empty).
    pub sensors: Vec<String>,
    /// Experiments to train on (all when empty).
    pub train: Vec<String>,
    /// Experiments to test on (every other one when empty).
    pub test: Vec<String>,
    /// Model file to write (JSON; `-`: stdout).
    pub output: PathBuf,
    /// The network and its training.
    pub nn: NnFitOptions,
}

impl FitOptions {
    /// The neural fit that `thermal fit` options ask for: the data, target, sensors,
    /// experiment split and output of `opts`, and the network `nn`. What goes with the
    /// regression models only is refused (a ridge k, lag features, validation blocks, a split
    /// by time): the networks are validated on whole experiments.
    pub fn from_thermal_fit(opts: &super::FitOptions, nn: NnFitOptions) -> Result<FitOptions> {
        let f = &opts.fit;
        let (train, test) = match &opts.split {
            SplitBy::Experiments { train, test }
                if f.k.is_none() && !f.lag && f.block_min.is_none() =>
            {
                (train.clone(), test.clone())
            }
            _ => return Err(Error::usage(
                "--k, --lag, --block-min and --train-until go with the regression models and with a network on one target and its sensors; a network of several targets, --sequence-by, --features, --angle-harmonics or --changes splits by --train/--test experiments",
            )),
        };
        Ok(FitOptions {
            data: opts.data.clone(),
            target: opts.target.clone(),
            sensors: f.sensors.clone(),
            train,
            test,
            output: opts.output.clone(),
            nn,
        })
    }
}

pub use mtec_nn::thermal_fit::Training;

/// What [`fit_thermal`] fitted.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum NeuralFitOutcome {
    /// A network on a rotary log (this module's route).
    Rotary(Box<FitOutcome>),
    /// A network on a log of one target ([`super::neural_log`]).
    Log(Box<LogFitOutcome>),
    /// `--model auto --with-networks`.
    Auto(AutoOutcome),
}

impl fmt::Display for NeuralFitOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NeuralFitOutcome::Rotary(o) => write!(f, "{o}"),
            NeuralFitOutcome::Log(o) => write!(f, "{o}"),
            NeuralFitOutcome::Auto(o) => write!(f, "{o}"),
        }
    }
}

/// `thermal fit` with a network (`nn.kind`), or `--model auto` with the networks named in
/// `with_networks` (their options `nn`'s) as candidates: a log of one target and its sensors
/// goes through [`super::neural_log`], a rotary log through [`fit`].
pub fn fit_thermal(
    opts: &super::FitOptions,
    nn: &NnFitOptions,
    with_networks: &[String],
    obs: &mut dyn Observer,
) -> Result<NeuralFitOutcome> {
    let log = neural_log::takes(&opts.target, nn);
    if !with_networks.is_empty() {
        if opts.model != "auto" {
            return Err(Error::usage("--with-networks goes with --model auto"));
        }
        if !log {
            return Err(Error::usage("--with-networks takes a log of one target and its sensors (no --sequence-by, --features, --angle-harmonics or --changes)"));
        }
        let networks = neural_log::network_options(with_networks, nn)?;
        return neural_log::fit_auto(opts, &networks, obs).map(NeuralFitOutcome::Auto);
    }
    if log {
        return neural_log::fit(opts, nn, obs).map(|o| NeuralFitOutcome::Log(Box::new(o)));
    }
    fit(&FitOptions::from_thermal_fit(opts, nn.clone())?, obs)
        .map(|o| NeuralFitOutcome::Rotary(Box::new(o)))
}

/// The trained network (written to `output`) and its scores.
#[derive(Debug, Clone, Serialize)]
pub struct FitOutcome {
    pub output: PathBuf,
    pub kind: NnKind,
    /// The model file's format (`mtec.cnn-lstm/1`, `mtec.bpnn/1`).
    pub format: String,
    pub train_experiments: Vec<u32>,
    pub test_experiments: Option<Vec<u32>>,
    /// One line: the network, its size and how the training ended.
    pub summary: String,
    pub training: Training,
    /// mtec-thermal's [`mtec_thermal::Metrics`] of every target.
    pub train_metrics: Vec<TargetMetrics>,
    pub test_metrics: Option<Vec<TargetMetrics>>,
    /// The model file written (JSON).
    #[serde(skip)]
    pub model_json: String,
    pub warnings: Vec<String>,
}

/// Metrics per target as a small table (R², RMSE, MAE, max |residual|, and the residual ratio
/// max |residual| / max |measured| of [`mtec_thermal::Metrics`]).
pub fn metrics_table(what: &str, m: &[TargetMetrics]) -> String {
    let mut s = format!(
        "{what}\n  {:<14} {:>6} {:>8} {:>10} {:>10} {:>10} {:>8}\n",
        "target", "n", "R2", "RMSE", "MAE", "max|res|", "ratio"
    );
    let opt = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |v| format!("{v:.p$}"));
    for t in m {
        let c = &t.metrics;
        s.push_str(&format!(
            "  {:<14} {:>6} {:>8} {:>10.4} {:>10.4} {:>10.4} {:>8}\n",
            t.target,
            c.n,
            opt(c.r2, 4),
            c.rmse_um,
            c.mae_um,
            c.max_abs_residual_um,
            opt(c.residual_ratio, 3)
        ));
    }
    s
}

/// The `thermal fit --model cnn-lstm|bpnn` report.
impl fmt::Display for FitOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.summary)?;
        write!(f, "{}", metrics_table("train", &self.train_metrics))?;
        if let Some(m) = &self.test_metrics {
            write!(f, "{}", metrics_table("test", m))?;
        }
        writeln!(f, "wrote {}", self.output.display())
    }
}

/// A network error about the file `path`: bad data or model located there, bad options a
/// usage error, the rest internal.
fn nn_error(path: &Path, e: NnError) -> Error {
    match e {
        NnError::Data(m) | NnError::Model(m) => Error::Input(InputError::file(path, m)),
        NnError::Input(e) => Error::Input(e),
        NnError::Config(m) => Error::Usage(m),
        other => Error::Internal(anyhow::anyhow!(other)),
    }
}

fn parse_ids(list: &[String], what: &str) -> Result<Vec<u32>> {
    list.iter()
        .map(|s| {
            s.trim().parse::<u32>().map_err(|_| {
                Error::usage(format!(
                    "--{what} takes experiment numbers (e.g. 1,2,4), got `{s}`"
                ))
            })
        })
        .collect()
}

/// A data-set error about the file `path` (mtec-thermal's messages).
fn data_error(data: &ThermalData, path: &Path, e: mtec_thermal::ThermalError) -> Error {
    super::located(data, path, e)
}

/// Trains a CNN-LSTM or a BPNN on the log's training experiments through
/// [`NeuralFit`] (mtec-thermal's `Fit` on the [`ThermalData`] that [`thermal_log::load`] reads:
/// several targets, the sequence column, the extra inputs), scores it on both sets of rows
/// with mtec-thermal's metrics per target and writes the model file.
pub fn fit(opts: &FitOptions, obs: &mut dyn Observer) -> Result<FitOutcome> {
    // where the model goes is settled before any work (an input, a directory: exit 2)
    let dest = OutputGuard::new(&[&opts.data]).check(&opts.output)?;
    let nn = &opts.nn;
    let table = Table::read(&opts.data)?;
    let cols = thermal_log::resolve_columns(&table, &opts.target, &opts.sensors, nn)
        .map_err(|e| nn_error(&opts.data, e))?;
    drop(table);
    let loaded = thermal_log::load(
        &opts.data,
        &LoadSpec {
            features: &cols.features,
            targets: &cols.targets,
            sequence_by: cols.sequence_by.as_deref(),
            need_targets: true,
            strict_time: nn.kind == NnKind::CnnLstm,
            trained_interval_min: None,
        },
    )
    .map_err(|e| nn_error(&opts.data, e))?;
    let data = &loaded.data;
    let train_ids = parse_ids(&opts.train, "train")?;
    let test_ids = parse_ids(&opts.test, "test")?;
    if !test_ids.is_empty() && train_ids.is_empty() {
        return Err(Error::usage("--test needs --train"));
    }
    if let Some(id) = train_ids.iter().find(|id| test_ids.contains(id)) {
        return Err(Error::usage(format!(
            "experiment {id} is both in the training and the test set"
        )));
    }
    let held = data.experiments();
    if let Some(id) = (train_ids.iter().chain(&test_ids)).find(|id| !held.contains(&id.to_string()))
    {
        return Err(Error::Input(InputError::file(
            &opts.data,
            format!("no experiment {id} (the data holds {})", held.join(", ")),
        )));
    }
    let names = |ids: &[u32]| ids.iter().map(u32::to_string).collect::<Vec<_>>();
    let split = match train_ids.is_empty() {
        true => SplitBy::All,
        false => SplitBy::Experiments {
            train: names(&train_ids),
            test: names(&test_ids),
        },
    };
    let rows = split_rows(data, &split).map_err(|e| data_error(data, &opts.data, e))?;
    let ids = |rows: &[usize]| {
        let mut v: Vec<u32> = rows
            .iter()
            .filter_map(|&i| data.experiment[i].parse().ok())
            .collect();
        v.dedup();
        v
    };
    let train_exps = ids(&rows.train);
    let test_exps = (!rows.test.is_empty()).then(|| ids(&rows.test));
    // the sensors lead the features (rises are theirs), the other inputs follow
    let mut options = nn.clone();
    let n_sensors = match cols.n_sensors {
        0 => {
            options.rises = false;
            cols.features.len()
        }
        n => n,
    };
    let fitter = NeuralFit {
        options,
        sensors: cols.features[..n_sensors].to_vec(),
        inputs: cols.features[n_sensors..].to_vec(),
    };
    let mut monitor = crate::observer::Relay(obs);
    let (model, training) = fitter
        .fit_rows_monitored(data, &rows.train, &mut monitor)
        .map_err(|e| data_error(data, &opts.data, e))?;
    let pred = model
        .predict_targets(data)
        .map_err(|e| data_error(data, &opts.data, e))?;
    let p = model.predictors();
    let train_m = TargetMetrics::on_rows(&data.targets(), &pred, &rows.train, p);
    let test_m = test_exps
        .as_ref()
        .map(|_| TargetMetrics::on_rows(&data.targets(), &pred, &rows.test, p));
    let interval = loaded.interval_min;
    let (format, summary) = match (&model.network, &training) {
        (Network::CnnLstm(m), Training::CnnLstm(report)) => (
            m.format.clone(),
            format!(
                "CNN-LSTM ({} parameters, window {} rows = {}, {} filters, LSTM {}) on experiments {:?}: {} epochs, best {}, {:.1} s; {}",
                report.parameters,
                m.architecture.window,
                interval
                    .map(|i| format!("{} min", i * m.architecture.window as f64))
                    .unwrap_or_else(|| "? min".into()),
                m.architecture.conv_channels,
                m.architecture.lstm_hidden,
                train_exps,
                report.epochs,
                report.best_epoch,
                report.seconds,
                report.stop_reason
            ),
        ),
        (Network::Bpnn(net), Training::Bpnn(report)) => (
            mtec_comp::bpnn::FORMAT.to_string(),
            format!(
                "BPNN {}-{}-{} ({} parameters) on experiments {:?}: {} Levenberg-Marquardt iterations, best {}; {}",
                net.n_in(),
                net.n_hidden(),
                net.n_out(),
                net.param_count(),
                train_exps,
                report.epochs,
                report.best_epoch,
                report.stop_reason
            ),
        ),
        _ => unreachable!("the training report is the network's"),
    };
    let text = model.to_json(
        data,
        serde_json::json!({
            "data": opts.data.display().to_string(),
            "train_experiments": train_exps,
            "test_experiments": test_exps,
            "train_metrics": train_m,
            "test_metrics": test_m,
            "training": {"report": training},
        }),
    );
    dest.write(text.as_bytes())?;
    Ok(FitOutcome {
        output: opts.output.clone(),
        kind: nn.kind,
        format,
        train_experiments: train_exps,
        test_experiments: test_exps,
        summary,
        training,
        train_metrics: train_m,
        test_metrics: test_m,
        model_json: text,
        warnings: Vec::new(),
    })
}

/// Reads `path` as a neural model when its `format` says so (`None`: another model kind).
pub fn read_model(path: &Path) -> Result<Option<Network>> {
    let Some(format) = super::neural_format(path)? else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(path)?;
    let bad = |e: NnError| Error::Input(InputError::file(path, e.to_string()));
    Ok(Some(if format == super::CNN_LSTM_FORMAT {
        Network::CnnLstm(CnnLstm::from_json(&text).map_err(bad)?)
    } else {
        Network::Bpnn(Bpnn::from_json(&text).map_err(|e| bad(e.into()))?)
    }))
}

/// The predictions of a neural model file.
#[derive(Debug, Clone, Serialize)]
pub struct Prediction {
    pub format: String,
    pub targets: Vec<String>,
    pub n: usize,
    /// Per row, one value per target.
    pub predictions: Vec<Vec<f64>>,
    /// Per target, when the data hold the targets (mtec-thermal's [`mtec_thermal::Metrics`]).
    pub metrics: Option<Vec<TargetMetrics>>,
    /// `experiment,time_min[,<sequence_by>],pred_<t>...[,<t>,res_<t>...]`
    #[serde(skip)]
    pub csv: String,
    /// The predicted ballbar readings of a rotary model (`--setup`, `--dbb`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub readings: Option<RotaryReadings>,
}

/// A rotary model's predicted ballbar readings against the measured ones: the source's metrics
/// per experiment and every reading (`mtec_nn::rotary::reading_rows`).
#[derive(Debug, Clone, Serialize)]
pub struct RotaryReadings {
    pub metrics: Vec<ReadingComparison>,
    #[serde(skip)]
    pub rows: Vec<ReadingRow>,
    /// `experiment,time_min,mode,angle_deg,predicted_um,measured_um,residual_um,
    /// predicted_change_um,measured_change_um,change_residual_um`
    #[serde(skip)]
    pub csv: String,
}

/// The readings table: per experiment the readings (after mean and first harmonic) and their
/// change since the first measurement, RMSE, MAE, max |residual| against max |measured|.
impl fmt::Display for RotaryReadings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "ballbar readings (µm; change = since the experiment's first measurement)\n  {:<10} {:>6} {:>8} {:>8} {:>9} {:>9} {:>7}",
            "experiment", "n", "RMSE", "MAE", "max|res|", "max|meas|", "ratio"
        )?;
        for m in &self.metrics {
            for (what, r) in m.rows() {
                let what = if what == "change" { " change" } else { "" };
                writeln!(
                    f,
                    "  {:<10} {:>6} {:>8.3} {:>8.3} {:>9.3} {:>9.3} {:>6.1}%",
                    format!("{}{what}", m.experiment),
                    m.n,
                    r[0],
                    r[1],
                    r[2],
                    r[3],
                    100.0 * r[4]
                )?;
            }
        }
        Ok(())
    }
}

/// The ballbar readings of a rotary model's predictions (`pred` per row of `labels`, the five
/// motions in `TARGET_NAMES` order, one sequence per angle): every experiment of the
/// predictions that the DBB file holds.
fn rotary_readings(
    r: &super::ReadingsOptions,
    model: &Path,
    targets: &[String],
    seq_by: Option<&str>,
    data: &ThermalData,
    pred: &[Vec<f64>],
) -> Result<RotaryReadings> {
    if targets.iter().map(String::as_str).ne(TARGET_NAMES) || seq_by != Some("angle_deg") {
        return Err(Error::Input(InputError::file(
            model,
            format!(
                "predicted ballbar readings need a rotary model of the five error motions {} \
                 fitted with --sequence-by angle_deg (this one predicts {} with sequences by {})",
                TARGET_NAMES.join(","),
                targets.join(","),
                seq_by.unwrap_or("experiment")
            ),
        )));
    }
    let setup = Setup::read(&r.setup)?;
    let measured = Measurements::from_table(&Table::read(&r.dbb)?, &setup)?;
    let angle = data.sequence.as_ref().map(|(_, v)| v);
    let rows: Vec<MotionRow> = pred
        .iter()
        .enumerate()
        .map(|(i, p)| MotionRow {
            experiment: data.experiment[i].parse().unwrap_or(u32::MAX),
            time_min: data.time_min[i],
            angle_deg: angle.map_or(f64::NAN, |a| a[i]),
            motions: [p[0], p[1], p[2], p[3], p[4]],
        })
        .collect();
    let mut experiments: Vec<u32> = rows.iter().map(|r| r.experiment).collect();
    experiments.sort_unstable();
    experiments.dedup();
    let in_dbb = |e: u32| measured.items.iter().any(|m| m.experiment == i64::from(e));
    let mut metrics = Vec::new();
    let mut all = Vec::new();
    for e in experiments.into_iter().filter(|&e| in_dbb(e)) {
        let of_e: Vec<MotionRow> = rows.iter().filter(|r| r.experiment == e).copied().collect();
        let rr = reading_rows(&setup, &measured, e, &of_e).map_err(|x| nn_error(&r.dbb, x))?;
        metrics.push(reading_metrics(e, &rr));
        all.extend(rr);
    }
    if metrics.is_empty() {
        return Err(Error::Input(InputError::file(
            &r.dbb,
            "holds none of the experiments of the predictions",
        )));
    }
    let mut csv = CsvWriter::new([
        "experiment",
        "time_min",
        "mode",
        "angle_deg",
        "predicted_um",
        "measured_um",
        "residual_um",
        "predicted_change_um",
        "measured_change_um",
        "change_residual_um",
    ]);
    for x in &all {
        csv.row([
            x.experiment.to_string(),
            x.time_min.to_string(),
            x.mode.to_string(),
            x.angle_deg.to_string(),
            format!("{:.4}", x.predicted_um),
            format!("{:.4}", x.measured_um),
            format!("{:.4}", x.measured_um - x.predicted_um),
            format!("{:.4}", x.predicted_change_um),
            format!("{:.4}", x.measured_change_um),
            format!("{:.4}", x.measured_change_um - x.predicted_change_um),
        ]);
    }
    Ok(RotaryReadings {
        metrics,
        rows: all,
        csv: csv.finish(),
    })
}

/// The metrics table, when the data hold the targets, and the ballbar readings' table.
impl fmt::Display for Prediction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(m) = &self.metrics {
            write!(f, "{}", metrics_table("metrics", m))?;
        }
        if let Some(r) = &self.readings {
            write!(f, "{r}")?;
        }
        Ok(())
    }
}

/// `thermal predict` with a neural model file: predictions per row, metrics when the data hold
/// the targets, the CSV (written to `output` when given).
pub fn predict(opts: &PredictOptions, _obs: &mut dyn Observer) -> Result<Prediction> {
    // where the predictions go is settled before any work (an input, a directory: exit 2)
    let mut inputs = vec![opts.data.as_path(), opts.model.as_path()];
    if let Some(r) = &opts.readings {
        inputs.extend([r.setup.as_path(), r.dbb.as_path()]);
    }
    let dest = match &opts.output {
        Some(p) => Some(OutputGuard::new(&inputs).check(p)?),
        None => None,
    };
    let readings_dest = match opts.readings.as_ref().and_then(|r| r.out.as_ref()) {
        Some(p) => {
            let mut g = OutputGuard::new(&inputs);
            if let Some(o) = &opts.output {
                g.add_input(o);
            }
            Some(g.check(p)?)
        }
        None => None,
    };
    let network = read_model(&opts.model)?.ok_or_else(|| {
        Error::Input(InputError::file(
            &opts.model,
            "not a neural model file (`format` is not mtec.cnn-lstm/1 or mtec.bpnn/1)",
        ))
    })?;
    // a file of `neural_log` (a log of one target, split as the regression models split it)
    let of_log = match &network {
        Network::Bpnn(n) => n.provenance.get("split").is_some(),
        Network::CnnLstm(n) => n.provenance.get("split").is_some(),
    };
    let (model, trained_interval) = NeuralThermalModel::from_network(network.clone())
        .unwrap_or_else(|| (plain_model(network), None));
    let cnn_lstm = matches!(model.network, Network::CnnLstm(_));
    // a network of one target on its sensors: predicted on the log as the regression models
    if of_log && model.inputs.is_empty() && model.more_targets.is_empty() {
        if opts.readings.is_some() {
            return Err(Error::Input(InputError::file(
                &opts.model,
                "predicted ballbar readings need a rotary model of the five error motions fitted with --sequence-by angle_deg (this one predicts one target from the sensors)",
            )));
        }
        let p = predict_log(&opts.data, &model, trained_interval)?;
        if let Some(d) = &dest {
            d.write(p.csv.as_bytes())?;
        }
        return Ok(p);
    }
    let (features, targets) = (model.input_names(), model.targets());
    let seq_by = model.sequence_by.clone();
    let path = &opts.data;
    // the CNN-LSTM's window is rows of the interval it was trained on
    let loaded = thermal_log::load(
        path,
        &LoadSpec {
            features: &features,
            targets: &targets,
            sequence_by: seq_by.as_deref(),
            need_targets: false,
            strict_time: cnn_lstm,
            trained_interval_min: trained_interval,
        },
    )
    .map_err(|e| nn_error(path, e))?;
    let data = &loaded.data;
    // rises of the sensors and a model of changes: [`NeuralThermalModel::predict_targets`]
    let pred = model
        .predict_targets(data)
        .map_err(|e| data_error(data, path, e))?;
    let all: Vec<usize> = (0..data.len()).collect();
    let metrics = loaded
        .has_targets
        .then(|| TargetMetrics::on_rows(&data.targets(), &pred, &all, model.predictors()));
    let mut header = vec!["experiment".to_string(), "time_min".to_string()];
    header.extend(seq_by.iter().cloned());
    header.extend(targets.iter().map(|t| format!("pred_{t}")));
    if loaded.has_targets {
        header.extend(
            targets
                .iter()
                .flat_map(|t| [t.to_string(), format!("res_{t}")]),
        );
    }
    let measured = data.targets();
    let mut csv = CsvWriter::new(header);
    for (i, p) in pred.iter().enumerate() {
        let mut row = vec![data.experiment[i].clone(), data.time_min[i].to_string()];
        row.extend(data.sequence.iter().map(|(_, s)| s[i].to_string()));
        row.extend(p.iter().map(|p| format!("{p:.4}")));
        if loaded.has_targets {
            for (p, (_, y)) in p.iter().zip(&measured) {
                row.extend([format!("{:.4}", y[i]), format!("{:.4}", y[i] - p)]);
            }
        }
        csv.row(row);
    }
    let csv = csv.finish();
    let readings = match &opts.readings {
        Some(r) => Some(rotary_readings(
            r,
            &opts.model,
            &targets,
            seq_by.as_deref(),
            data,
            &pred,
        )?),
        None => None,
    };
    if let Some(d) = &dest {
        d.write(csv.as_bytes())?;
    }
    if let (Some(d), Some(r)) = (&readings_dest, &readings) {
        d.write(r.csv.as_bytes())?;
    }
    Ok(Prediction {
        format: "mtec.thermal-prediction/1".into(),
        targets,
        n: pred.len(),
        predictions: pred,
        metrics,
        csv,
        readings,
    })
}

/// A network file without the provenance of a thermal fit: its inputs taken as they are (no
/// rises, no sequence column), its outputs as the targets.
fn plain_model(network: Network) -> NeuralThermalModel {
    let (inputs, targets) = match &network {
        Network::Bpnn(n) => (n.input_names.clone(), n.output_names.clone()),
        Network::CnnLstm(n) => (n.feature_names.clone(), n.target_names.clone()),
    };
    NeuralThermalModel {
        network,
        sensors: inputs,
        inputs: Vec::new(),
        rises: false,
        target: targets.first().cloned().unwrap_or_default(),
        more_targets: targets.iter().skip(1).cloned().collect(),
        changes: false,
        sequence_by: None,
    }
}

/// The predictions of a network fitted on a log of one target ([`neural_log::predict_log`]):
/// `experiment,time_min,pred_<t>[,<t>,res_<t>]`.
fn predict_log(
    path: &Path,
    model: &NeuralThermalModel,
    interval: Option<f64>,
) -> Result<Prediction> {
    let (data, pred) = neural_log::predict_log(path, model, interval)?;
    let t = &model.target;
    let measured = data.target_um().ok();
    let mut header = vec![
        "experiment".to_string(),
        "time_min".into(),
        format!("pred_{t}"),
    ];
    if measured.is_some() {
        header.extend([t.clone(), format!("res_{t}")]);
    }
    let mut csv = CsvWriter::new(header);
    for (i, p) in pred.iter().enumerate() {
        let mut row = vec![
            data.experiment[i].clone(),
            data.time_min[i].to_string(),
            format!("{p:.4}"),
        ];
        if let Some(y) = measured {
            row.extend([format!("{:.4}", y[i]), format!("{:.4}", y[i] - p)]);
        }
        csv.row(row);
    }
    let targets = vec![t.clone()];
    let predictions: Vec<Vec<f64>> = pred.iter().map(|&p| vec![p]).collect();
    let all: Vec<usize> = (0..data.len()).collect();
    let metrics = measured.map(|y| {
        TargetMetrics::on_rows(&[(t.as_str(), y)], &predictions, &all, model.predictors())
    });
    Ok(Prediction {
        format: "mtec.thermal-prediction/1".into(),
        targets,
        n: pred.len(),
        predictions,
        metrics,
        csv: csv.finish(),
        readings: None,
    })
}

/// The format the CLI recognises before it has the network crate is the network's own.
#[test]
fn cnn_lstm_format_is_the_networks() {
    assert_eq!(super::CNN_LSTM_FORMAT, mtec_nn::cnn_lstm::FORMAT);
}
