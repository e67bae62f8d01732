//! `mtec thermal fit|predict --model cnn-lstm|bpnn`: the neural thermal models of `mtec-nn` on
//! files. `thermal.rs` routes the two model kinds here; the regression models stay there.
//!
//! Data: the thermal log format with any number of targets and, for sequence models, a column
//! that splits each experiment into sequences — e.g. the `motions.csv` that
//! `mtec identify ballbar --temps` writes (`experiment,time_min,angle_deg,EXC_um..EBC_urad,
//! T1_c..T9_c`, one sequence per angle: `--sequence-by angle_deg`).
//!
//! Decisions where the spec is silent:
//! - Features: the sensors (`--sensors`, default every `_c` column but `ambient_c`, as for the
//!   regression models) followed by the `--features` columns (e.g. `angle_deg`, `ambient_c`).
//!   An angle column may enter as its harmonics `cos_k(col)`, `sin_k(col)` (`--angle-harmonics
//!   N`, or named one by one in `--features`); the model file stores those names and
//!   `thermal predict` computes them again from the angle column.
//! - `--rises`: the sensor features as rises over each sequence's first row; the model file
//!   records how many leading features are rises (`provenance.rises`) and predict does the same.
//! - Rows of one sequence are time steps in `time_min` order (sorted here, a repeated time is an
//!   error); the CNN-LSTM's window counts rows, so resample irregular logs first.
//! - The model file is the network's own versioned format (`mtec.cnn-lstm/1`, `mtec.bpnn/1`);
//!   the CLI adds under `provenance` the data file, `sequence_by`, the split and the metrics, and
//!   `thermal predict` reads `sequence_by` back from there.
//! - Ctrl-C during training stops after the current epoch and keeps the best epoch's weights
//!   (the file is still written); a second Ctrl-C ends the process.

use crate::error::CliError;
use mtec_io::{InputError, OutputGuard, Table};
use mtec_nn::cnn_lstm::Architecture;
use mtec_nn::metrics::{channel_metrics, ChannelMetrics};
use mtec_nn::rotary::{harmonic_feature_names, HarmonicFeature};
use mtec_nn::{
    train_bpnn_baseline, train_cnn_lstm, Activation, Bpnn, BpnnTrainConfig, CnnLstm, CnnLstmConfig,
    Experiment, NnError, Optimizer, Sequence, ThermalDataset,
};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

pub use super::neural::{NnArgs, NnKind};

/// Everything `thermal fit` passes to a neural fit.
pub struct FitRequest<'a> {
    pub kind: NnKind,
    pub data: &'a Path,
    pub target: &'a str,
    pub sensors: &'a [String],
    pub train: &'a [String],
    pub test: &'a [String],
    pub output: &'a Path,
    pub nn: &'a NnArgs,
}

/// The data of a thermal log as sequences, plus where each scored row came from.
struct Loaded {
    data: ThermalDataset,
    /// Per row, in model order: (experiment, time_min, sequence value).
    labels: Vec<(u32, f64, Option<f64>)>,
    has_targets: bool,
    /// The sampling interval of the sequences (median time step, min), when any has two rows.
    interval_min: Option<f64>,
}

/// Relative difference of a time step from the interval that is still the same interval (a
/// logger's clock jitter); a larger one changes what a window of rows spans.
const INTERVAL_TOLERANCE: f64 = 0.01;

/// Resolves `ez` or `ez_um` against the header (exact name first).
fn resolve(t: &Table, name: &str) -> Option<String> {
    if t.has(name) {
        return Some(name.to_string());
    }
    ["_um", "_urad", "_c", "_mm", "_deg"]
        .iter()
        .map(|s| format!("{name}{s}"))
        .find(|n| t.has(n))
}

fn header_error(t: &Table, msg: String) -> CliError {
    CliError::Input(InputError::at(&t.path, t.header_line, 1, msg))
}

/// Reads the log into sequences. `targets` empty or absent columns with `need_targets = false`
/// give zero targets (prediction only). `strict_time`: a time may not repeat within a sequence
/// (the sequence model's rows are time steps; the BPNN takes rows one by one and only uses the
/// time order for its validation tail). With `strict_time` the time step must also be one
/// interval throughout (the CNN-LSTM's window counts rows, so a gap or another sampling rate
/// would change the minutes it spans): `trained_interval_min` when the model recorded it, the
/// median step of the file otherwise; the first row off it is refused.
fn load(
    path: &Path,
    feature_names: &[String],
    targets: &[String],
    sequence_by: Option<&str>,
    need_targets: bool,
    strict_time: bool,
    trained_interval_min: Option<f64>,
) -> Result<Loaded, CliError> {
    let t = Table::read(path)?;
    t.require(&["time_min"])?;
    let exp: Vec<i64> = if t.has("experiment") {
        t.i64_column("experiment")?
    } else {
        vec![1; t.rows.len()]
    };
    let time = t.f64_column("time_min")?;
    let seq_col = match sequence_by {
        Some(c) => Some(t.f64_column(c)?),
        None => None,
    };
    // a column of the file, or a harmonic `cos_k(col)` of one (the file's column wins)
    let feats: Vec<Vec<f64>> = feature_names
        .iter()
        .map(|n| match HarmonicFeature::parse(n).filter(|_| !t.has(n)) {
            Some(h) => Ok(t
                .f64_column(&h.column)?
                .into_iter()
                .map(|deg| h.value(deg))
                .collect()),
            None => t.f64_column(n),
        })
        .collect::<Result<_, InputError>>()?;
    let has_targets = !targets.is_empty() && targets.iter().all(|n| t.has(n));
    if need_targets && !has_targets {
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
            .collect::<Result<_, _>>()?
    } else {
        Vec::new()
    };
    let n_targets = targets.len().max(1);
    // experiment → sequence key → [(time, row)]
    let mut groups: BTreeMap<u32, BTreeMap<i64, Vec<(f64, usize)>>> = BTreeMap::new();
    for (i, row) in t.rows.iter().enumerate() {
        let e = u32::try_from(exp[i]).map_err(|_| {
            CliError::Input(t.error_at(row, "experiment", "experiment numbers must be 0 or more"))
        })?;
        let s = seq_col.as_ref().map_or(0, |c| (c[i] * 1e6).round() as i64);
        groups
            .entry(e)
            .or_default()
            .entry(s)
            .or_default()
            .push((time[i], i));
    }
    let mut experiments = Vec::new();
    let mut labels = Vec::new();
    // (time step, row of its later sample) of every sequence
    let mut steps: Vec<(f64, usize)> = Vec::new();
    for (e, seqs) in groups {
        let mut sequences = Vec::new();
        for (_, mut rows) in seqs {
            rows.sort_by(|a, b| a.0.total_cmp(&b.0));
            steps.extend(rows.windows(2).map(|w| (w[1].0 - w[0].0, w[1].1)));
            for w in rows.windows(2) {
                if strict_time && w[0].0 == w[1].0 {
                    return Err(CliError::Input(t.error_at(
                        &t.rows[w[1].1],
                        "time_min",
                        format!(
                            "time {} min appears twice in one sequence of experiment {e}{}",
                            w[1].0,
                            sequence_by
                                .map(|c| format!(" (same {c})"))
                                .unwrap_or_default()
                        ),
                    )));
                }
            }
            let mut features = Vec::with_capacity(rows.len());
            let mut tg = Vec::with_capacity(rows.len());
            for &(tm, i) in &rows {
                features.push(feats.iter().map(|c| c[i]).collect::<Vec<f64>>());
                tg.push(if has_targets {
                    targ.iter().map(|c| c[i]).collect()
                } else {
                    vec![0.0; n_targets]
                });
                labels.push((e, tm, seq_col.as_ref().map(|c| c[i])));
            }
            sequences.push(Sequence {
                features,
                targets: tg,
                warmup: 0,
            });
        }
        experiments.push(Experiment { id: e, sequences });
    }
    let data = ThermalDataset {
        feature_names: feature_names.to_vec(),
        target_names: if targets.is_empty() {
            vec!["none".into()]
        } else {
            targets.to_vec()
        },
        experiments,
    };
    data.validate()
        .map_err(|e| CliError::Input(InputError::file(path, e.to_string())))?;
    let interval_min = median_step(&steps);
    if strict_time {
        if let Some(expected) = trained_interval_min.or(interval_min) {
            if let Some(&(dt, row)) = steps
                .iter()
                .find(|(dt, _)| (dt - expected).abs() > INTERVAL_TOLERANCE * expected)
            {
                let why = match trained_interval_min {
                    Some(_) => {
                        format!("the model was trained on data sampled every {expected} min")
                    }
                    None => format!("the log is sampled every {expected} min (median step)"),
                };
                return Err(CliError::Input(t.error_at(
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
    Ok(Loaded {
        data,
        labels,
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

fn parse_ids(list: &[String], what: &str) -> Result<Vec<u32>, CliError> {
    list.iter()
        .map(|s| {
            s.trim().parse::<u32>().map_err(|_| {
                CliError::usage(format!(
                    "--{what} takes experiment numbers (e.g. 1,2,4), got `{s}`"
                ))
            })
        })
        .collect()
}

fn nn_error(path: &Path, e: NnError) -> CliError {
    match e {
        NnError::Data(m) | NnError::Model(m) => CliError::Input(InputError::file(path, m)),
        NnError::Config(m) => CliError::Usage(m),
        other => CliError::Internal(anyhow::anyhow!(other)),
    }
}

/// Set by the SIGINT handler while a training runs.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_sigint(_: libc::c_int) {
    // async-signal-safe: an atomic store, then the default action for a second Ctrl-C
    INTERRUPTED.store(true, Ordering::Relaxed);
    // SAFETY: restoring the default disposition is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

/// Runs `f` with Ctrl-C turned into a request to stop training.
fn with_ctrl_c<T>(f: impl FnOnce(&'static AtomicBool) -> T) -> T {
    INTERRUPTED.store(false, Ordering::Relaxed);
    let handler = on_sigint as extern "C" fn(libc::c_int);
    // SAFETY: installs a handler that only stores to an atomic and resets the disposition.
    unsafe {
        libc::signal(libc::SIGINT, handler as libc::sighandler_t);
    }
    let out = f(&INTERRUPTED);
    // SAFETY: back to the default disposition.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
    out
}

/// Metrics per channel as a small table (ratio = max|res| / range of the measured values).
fn metrics_table(what: &str, m: &[ChannelMetrics]) -> String {
    let mut s = format!(
        "{what}\n  {:<14} {:>6} {:>10} {:>10} {:>10} {:>10} {:>8}\n",
        "channel", "n", "RMSE", "MAE", "max|res|", "range", "ratio"
    );
    for c in m {
        s.push_str(&format!(
            "  {:<14} {:>6} {:>10.4} {:>10.4} {:>10.4} {:>10.4} {:>8.3}\n",
            c.channel, c.n, c.rmse, c.mae, c.max_abs_residual, c.range, c.residual_ratio
        ));
    }
    s
}

fn print_metrics(say: &mut dyn std::io::Write, what: &str, m: &[ChannelMetrics]) {
    let _ = write!(say, "{}", metrics_table(what, m));
}

/// `thermal fit --model cnn-lstm|bpnn`.
pub fn fit(r: FitRequest) -> Result<(), CliError> {
    // the CLI has no other thread yet: one candle thread is ~8x faster for these nets
    mtec_nn::threads::prefer_single_thread();
    // where the model goes is settled before any work (an input, a directory: exit 2); the
    // report goes to stderr when the model itself streams to stdout (`-o -`)
    let dest = OutputGuard::new(&[r.data]).check(r.output)?;
    let mut say = super::messages(&dest);
    let nn = r.nn;
    let table = Table::read(r.data)?;
    let mut targets = Vec::new();
    for name in r.target.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        targets.push(resolve(&table, name).ok_or_else(|| {
            header_error(
                &table,
                format!(
                    "missing target column `{name}`; the header has: {}",
                    table.header.join(", ")
                ),
            )
        })?);
    }
    if targets.is_empty() {
        return Err(CliError::usage("--target needs at least one column"));
    }
    let mut features: Vec<String> = if r.sensors.is_empty() {
        table
            .columns_with_suffix("_c")
            .into_iter()
            .filter(|c| c != "ambient_c")
            .collect()
    } else {
        r.sensors
            .iter()
            .map(|s| {
                resolve(&table, s)
                    .ok_or_else(|| header_error(&table, format!("missing sensor column `{s}`")))
            })
            .collect::<Result<_, _>>()?
    };
    let n_sensors = features.len();
    if nn.angle_harmonics == Some(0) {
        return Err(CliError::usage(
            "--angle-harmonics needs at least 1 harmonic",
        ));
    }
    if nn.angle_harmonics.is_some()
        && !nn
            .features
            .iter()
            .any(|f| resolve(&table, f).is_some_and(|name| name.ends_with("_deg")))
    {
        return Err(CliError::usage(
            "--angle-harmonics needs an angle column in degrees (name ending in `_deg`) among --features",
        ));
    }
    for f in &nn.features {
        let derived = HarmonicFeature::parse(f);
        let column = derived.as_ref().map_or(f.as_str(), |h| h.column.as_str());
        let name = resolve(&table, column)
            .ok_or_else(|| header_error(&table, format!("missing feature column `{column}`")))?;
        let names = match (derived, nn.angle_harmonics) {
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
            &table,
            "no feature columns: the file has no `_c` sensor column and no --features".into(),
        ));
    }
    let kernel = CnnLstmConfig::default().architecture.kernel;
    if r.kind == NnKind::CnnLstm && features.len() < kernel {
        return Err(header_error(
            &table,
            format!(
                "the CNN-LSTM's convolution (width {kernel}) needs at least {kernel} features; the data have {}: {} (add --features columns)",
                features.len(),
                features.join(", ")
            ),
        ));
    }
    if let Some(t) = features.iter().find(|f| targets.contains(f)) {
        return Err(CliError::usage(format!(
            "`{t}` is both a feature and a target"
        )));
    }
    let seq_by = match &nn.sequence_by {
        Some(c) => Some(resolve(&table, c).ok_or_else(|| {
            header_error(&table, format!("missing column `{c}` (--sequence-by)"))
        })?),
        None => None,
    };
    drop(table);
    let mut loaded = load(
        r.data,
        &features,
        &targets,
        seq_by.as_deref(),
        true,
        r.kind == NnKind::CnnLstm,
        None,
    )?;
    // the leading sensor features as rises (0: absolute temperatures)
    let rises = if nn.rises { n_sensors } else { 0 };
    loaded.data = loaded.data.rises(rises);
    let train_ids = parse_ids(r.train, "train")?;
    let mut test_ids = parse_ids(r.test, "test")?;
    if !test_ids.is_empty() && train_ids.is_empty() {
        return Err(CliError::usage("--test needs --train"));
    }
    let all: Vec<u32> = loaded.data.experiments.iter().map(|e| e.id).collect();
    if !train_ids.is_empty() && test_ids.is_empty() {
        test_ids = all
            .iter()
            .copied()
            .filter(|e| !train_ids.contains(e))
            .collect();
    }
    let (train, test) = if train_ids.is_empty() {
        (loaded.data.clone(), None)
    } else if test_ids.is_empty() {
        (
            loaded
                .data
                .select(&train_ids)
                .map_err(|e| nn_error(r.data, e))?,
            None,
        )
    } else {
        let (a, b) = loaded
            .data
            .split(&train_ids, &test_ids)
            .map_err(|e| nn_error(r.data, e))?;
        (a, Some(b))
    };
    let train_exps: Vec<u32> = train.experiments.iter().map(|e| e.id).collect();
    let interval = loaded.interval_min;
    let provenance = |training: serde_json::Value,
                      train_m: &[ChannelMetrics],
                      test_m: Option<&Vec<ChannelMetrics>>| {
        serde_json::json!({
            "data": r.data.display().to_string(),
            "sequence_by": seq_by,
            "rises": rises,
            "train_experiments": train_exps,
            "test_experiments": test.as_ref().map(|t| t.experiments.iter().map(|e| e.id).collect::<Vec<_>>()),
            "train_metrics": train_m,
            "test_metrics": test_m,
            "training": training,
            "sample_interval_min": interval,
        })
    };
    let text = match r.kind {
        NnKind::CnnLstm => {
            let d = CnnLstmConfig::default();
            let cfg = CnnLstmConfig {
                architecture: Architecture {
                    window: nn.window.unwrap_or(d.architecture.window),
                    conv_channels: nn.conv_channels.unwrap_or(d.architecture.conv_channels),
                    kernel: d.architecture.kernel,
                    lstm_hidden: nn.lstm_hidden.unwrap_or(d.architecture.lstm_hidden),
                },
                max_epochs: nn.epochs.unwrap_or(d.max_epochs),
                batch_size: nn.batch_size.unwrap_or(d.batch_size),
                learning_rate: nn.learning_rate.unwrap_or(d.learning_rate),
                final_learning_rate_fraction: nn
                    .final_lr_fraction
                    .unwrap_or(d.final_learning_rate_fraction),
                patience: nn.patience.unwrap_or(d.patience),
                seed: nn.seed,
                progress: !nn.quiet,
                ..d
            };
            let (mut model, report) = with_ctrl_c(|stop| {
                train_cnn_lstm(
                    &train,
                    &CnnLstmConfig {
                        stop: Some(stop),
                        ..cfg
                    },
                )
            })
            .map_err(|e| nn_error(r.data, e))?;
            let _ = writeln!(say,
                "CNN-LSTM ({} parameters, window {} rows = {}, {} filters, LSTM {}) on experiments {:?}: {} epochs, best {}, {:.1} s; {}",
                report.parameters,
                model.architecture.window,
                interval
                    .map(|i| format!("{} min", i * model.architecture.window as f64))
                    .unwrap_or_else(|| "? min".into()),
                model.architecture.conv_channels,
                model.architecture.lstm_hidden,
                train_exps,
                report.epochs,
                report.best_epoch,
                report.seconds,
                report.stop_reason
            );
            let train_m = model.evaluate(&train).map_err(|e| nn_error(r.data, e))?;
            let test_m = match &test {
                Some(t) => Some(model.evaluate(t).map_err(|e| nn_error(r.data, e))?),
                None => None,
            };
            print_metrics(&mut *say, "train", &train_m);
            if let Some(m) = &test_m {
                print_metrics(&mut *say, "test", m);
            }
            let training = serde_json::json!({"model": model.provenance, "report": report});
            model.provenance = provenance(training, &train_m, test_m.as_ref());
            model.to_json()
        }
        NnKind::Bpnn => {
            let d = BpnnTrainConfig::default();
            let cfg = BpnnTrainConfig {
                hidden: nn.hidden.unwrap_or(d.hidden),
                activation: Activation::Sigmoid,
                optimizer: Optimizer::LevenbergMarquardt,
                max_epochs: nn.epochs.unwrap_or(200),
                patience: nn.patience,
                seed: nn.seed,
                progress: !nn.quiet,
                ..d
            };
            let (mut net, report) = with_ctrl_c(|stop| {
                train_bpnn_baseline(
                    &train,
                    &BpnnTrainConfig {
                        stop: Some(stop),
                        ..cfg
                    },
                )
            })
            .map_err(|e| nn_error(r.data, e))?;
            let _ = writeln!(say,
                "BPNN {}-{}-{} ({} parameters) on experiments {:?}: {} Levenberg-Marquardt iterations, best {}; {}",
                net.n_in(),
                net.n_hidden(),
                net.n_out(),
                net.param_count(),
                train_exps,
                report.epochs,
                report.best_epoch,
                report.stop_reason
            );
            let eval = |d: &ThermalDataset| -> Result<Vec<ChannelMetrics>, CliError> {
                mtec_nn::evaluate_bpnn(&net, d).map_err(|e| nn_error(r.data, e))
            };
            let train_m = eval(&train)?;
            let test_m = match &test {
                Some(t) => Some(eval(t)?),
                None => None,
            };
            print_metrics(&mut *say, "train", &train_m);
            if let Some(m) = &test_m {
                print_metrics(&mut *say, "test", m);
            }
            let training = serde_json::json!({"model": net.provenance, "report": report});
            net.provenance = provenance(training, &train_m, test_m.as_ref());
            net.to_json()
        }
    };
    dest.write(text.as_bytes())?;
    let _ = writeln!(say, "wrote {}", r.output.display());
    Ok(())
}

/// A neural model file, by its `format`.
pub enum NnModel {
    CnnLstm(CnnLstm),
    Bpnn(Bpnn),
}

/// Reads `path` as a neural model when its `format` says so (`None`: another model kind).
pub fn read_model(path: &Path) -> Result<Option<NnModel>, CliError> {
    let Some(format) = super::neural::neural_format(path)? else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(path)?;
    let bad = |e: NnError| CliError::Input(InputError::file(path, e.to_string()));
    Ok(Some(if format == super::neural::CNN_LSTM_FORMAT {
        NnModel::CnnLstm(CnnLstm::from_json(&text).map_err(bad)?)
    } else {
        NnModel::Bpnn(Bpnn::from_json(&text).map_err(|e| bad(e.into()))?)
    }))
}

/// The format the CLI recognises before it has the network crate is the network's own.
#[test]
fn cnn_lstm_format_is_the_networks() {
    assert_eq!(super::neural::CNN_LSTM_FORMAT, mtec_nn::cnn_lstm::FORMAT);
}

/// `thermal predict` with a neural model: predictions per row (CSV or JSON), metrics when the
/// data hold the targets.
pub fn predict(
    model: NnModel,
    model_path: &Path,
    data: &Path,
    json: bool,
    output: Option<&PathBuf>,
) -> Result<(), CliError> {
    mtec_nn::threads::prefer_single_thread();
    // where the predictions go is settled before any work (an input, a directory: exit 2)
    let dest = match output {
        Some(p) => Some(OutputGuard::new(&[data, model_path]).check(p)?),
        None => None,
    };
    // with `-o -` the CSV has stdout: the JSON and the metrics go to stderr
    let mut say = match &dest {
        Some(d) => super::messages(d),
        None => Box::new(std::io::stdout()),
    };
    let (features, targets, provenance) = match &model {
        NnModel::CnnLstm(m) => (&m.feature_names, &m.target_names, &m.provenance),
        NnModel::Bpnn(m) => (&m.input_names, &m.output_names, &m.provenance),
    };
    // the sequences of the fit (a BPNN takes rows one by one; its sequences only matter for
    // where the rises start)
    let seq_by = provenance
        .get("sequence_by")
        .and_then(|v| v.as_str())
        .map(str::to_string);
    let strict = matches!(model, NnModel::CnnLstm(_));
    // the CNN-LSTM's window is rows of the interval it was trained on
    let trained_interval = provenance
        .get("sample_interval_min")
        .and_then(|v| v.as_f64());
    let mut loaded = load(
        data,
        features,
        targets,
        seq_by.as_deref(),
        false,
        strict,
        trained_interval,
    )?;
    // trained on rises of the first k features (`thermal fit --rises`): the same here
    let rises = provenance
        .get("rises")
        .and_then(|v| v.as_u64())
        .unwrap_or(0) as usize;
    loaded.data = loaded.data.rises(rises.min(features.len()));
    let pred = match &model {
        NnModel::CnnLstm(m) => m.predict(&loaded.data).map_err(|e| nn_error(data, e))?,
        NnModel::Bpnn(m) => loaded
            .data
            .rows()
            .0
            .iter()
            .map(|r| m.predict(r))
            .collect::<Result<_, _>>()
            .map_err(|e| nn_error(data, e.into()))?,
    };
    let meas = loaded.has_targets.then(|| loaded.data.rows().1);
    let metrics = meas.as_ref().map(|y| channel_metrics(targets, &pred, y));
    if json {
        let doc = serde_json::json!({
            "format": "mtec.thermal-prediction/1",
            "targets": targets,
            "n": pred.len(),
            "predictions": pred,
            "metrics": metrics,
        });
        let _ = writeln!(
            say,
            "{}",
            serde_json::to_string(&doc).map_err(|e| CliError::Internal(e.into()))?
        );
    } else if let Some(m) = &metrics {
        // the CSV may go to stdout: the metrics then go to stderr
        let table = metrics_table("metrics", m);
        match output {
            Some(_) => {
                let _ = write!(say, "{table}");
            }
            None => eprint!("{table}"),
        }
    }
    if output.is_some() || !json {
        let mut csv = String::from("experiment,time_min");
        if let Some(c) = &seq_by {
            csv.push(',');
            csv.push_str(c);
        }
        for t in targets {
            csv.push_str(&format!(",pred_{t}"));
        }
        if meas.is_some() {
            for t in targets {
                csv.push_str(&format!(",{t},res_{t}"));
            }
        }
        csv.push('\n');
        for (i, (e, tm, s)) in loaded.labels.iter().enumerate() {
            csv.push_str(&format!("{e},{tm}"));
            if let Some(s) = s {
                csv.push_str(&format!(",{s}"));
            }
            for p in &pred[i] {
                csv.push_str(&format!(",{p:.4}"));
            }
            if let Some(y) = &meas {
                for (p, v) in pred[i].iter().zip(&y[i]) {
                    csv.push_str(&format!(",{v:.4},{:.4}", v - p));
                }
            }
            csv.push('\n');
        }
        match &dest {
            Some(d) => d.write(csv.as_bytes())?,
            None => print!("{csv}"),
        }
    }
    Ok(())
}
