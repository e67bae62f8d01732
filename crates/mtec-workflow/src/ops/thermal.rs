//! `mtec thermal select|fit|predict|cv`: thermal error models from temperature logs, on files.
//!
//! The modelling (which kinds exist, the split, the validation, the metrics, the model file) is
//! `mtec-thermal`'s ([`mtec_thermal::registry`], [`mtec_thermal::model_file`]); here the log is
//! read, the options checked, the files written and the outcome built. The neural models
//! (`cnn-lstm`, `bpnn`) are [`neural`], behind the cargo feature `neural`.

use crate::{Error, Observer, Result};
use mtec_io::{CsvWriter, InputError, OutputGuard, Table};
use mtec_thermal::auto::CandidateScore;
use mtec_thermal::features::{design, temp_features};
use mtec_thermal::guard::{model_columns, outside_envelope};
use mtec_thermal::heat_input::with_input;
use mtec_thermal::model_file::{fit_file, split_rows, worse_warning, SplitBy};
use mtec_thermal::registry::{self, KindInfo, ModelSpec};
use mtec_thermal::select::{select_sensors, SelectOptions as RidgeTraceRules, Selection};
use mtec_thermal::validate::{
    block_cv, duty_cycle_blocks, forward_cv, forward_folds, rows_of_experiments, time_blocks,
    BlockCv, ForwardCv,
};
use mtec_thermal::{Fit, Metrics, ModelFile, Predict, ThermalData, ThermalError, ThermalModel};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

mod network_options;
#[cfg(feature = "neural")]
pub mod neural;
#[cfg(feature = "neural")]
pub mod neural_log;
pub use network_options::NetworkOptions;

/// The `--model` values of the neural models (cargo feature `neural`; see [`neural`]).
pub const NEURAL_KINDS: [&str; 2] = ["cnn-lstm", "bpnn"];

/// Every `--model` value with its one line of help ("" for none): the registry's kinds
/// (`mtec_thermal::registry::KINDS`), then the neural models (refused with exit 2 by a build
/// without them).
pub fn model_choices() -> impl Iterator<Item = (&'static str, &'static str)> {
    let regression = mtec_thermal::registry::KINDS
        .iter()
        .map(|k| (k.name, k.help));
    regression.chain([
        (
            "cnn-lstm",
            "Neural (a build with `--features neural`): CNN-LSTM sequence model (several targets; --window, --sequence-by, ...)",
        ),
        (
            "bpnn",
            "Neural (a build with `--features neural`): one-hidden-layer BPNN on the current row (several targets; --hidden)",
        ),
    ])
}

/// Whether `model` names a neural model.
pub fn is_neural(model: &str) -> bool {
    NEURAL_KINDS.contains(&model)
}

// ---- reading the log ----

/// A non-temperature input column to attach: its name and whether the file must have it.
type InputColumn<'a> = Option<(&'a str, bool)>;

/// Attaches the heat-source column (e.g. `spindle_rpm`) to a log already read (a file, or the
/// Python module's arrays): required for heat-input models, otherwise when the log has it (it
/// marks the duty-cycle blocks).
fn load_table(
    t: &Table,
    target: Option<&str>,
    require: bool,
    input: InputColumn,
) -> Result<ThermalData> {
    let d = ThermalData::from_table(t, target, require)?;
    match input {
        Some((name, required)) if required || t.has(name) => {
            let v = t.f64_column(name)?;
            with_input(&d, name, &v)
                .map_err(|e| Error::Input(InputError::file(&t.path, e.to_string())))
        }
        _ => Ok(d),
    }
}

/// A model error about the data file: missing columns at the header, the rest about the file.
fn located(data: &ThermalData, path: &Path, e: ThermalError) -> Error {
    match e {
        ThermalError::MissingColumn(c) => Error::Input(data.header_error(format!(
            "missing column `{c}`; the header has: {}",
            header_list(data)
        ))),
        other => Error::Input(InputError::file(path, other.to_string())),
    }
}

fn header_list(d: &ThermalData) -> String {
    let mut h = d.sensor_names.clone();
    if d.ambient_c.is_some() {
        h.push("ambient_c".into());
    }
    if d.position_mm.is_some() {
        h.push("position_mm".into());
    }
    h.join(", ")
}

/// The registered kind `model` with the options checked against it (usage errors).
fn checked_kind(model: &str, fit: &registry::FitOptions) -> Result<&'static KindInfo> {
    let kind = registry::kind(model).ok_or_else(|| {
        let names: Vec<&str> = registry::KINDS.iter().map(|k| k.name).collect();
        Error::usage(format!(
            "no thermal model `{model}`; the models are {}, and {} with the neural models",
            names.join(", "),
            NEURAL_KINDS.join(", ")
        ))
    })?;
    fit.check(kind).map_err(Error::Usage)?;
    Ok(kind)
}

fn warn_all(obs: &mut dyn Observer, warnings: &[String]) {
    for w in warnings {
        obs.warning(w);
    }
}

fn fmt_opt(v: Option<f64>, prec: usize) -> String {
    v.map(|x| format!("{x:.prec$}"))
        .unwrap_or_else(|| "-".into())
}

// ---- select ----

/// Options of [`select`].
#[derive(Debug, Clone)]
pub struct SelectOptions {
    /// Thermal log (CSV).
    pub data: PathBuf,
    /// Target column (`radial_um` or `radial`).
    pub target: String,
    /// Candidate sensors (every `_c` column but ambient_c when empty).
    pub sensors: Vec<String>,
    /// Folder for ridge_trace.csv, ridge_trace.svg and selection.json (`None`: write nothing).
    pub out: Option<PathBuf>,
}

/// The sensor selection: the `mtec.thermal-selection/1` document (also `selection.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SelectOutcome {
    pub format: String,
    pub target: String,
    #[serde(flatten)]
    pub selection: Selection,
    /// The folder the three files went into.
    #[serde(skip)]
    pub out: Option<PathBuf>,
    /// The selection's warnings (also in `selection.warnings`).
    #[serde(skip)]
    pub warnings: Vec<String>,
}

/// VIF table, ridge trace, elimination by the ridge-trace rules and the comparison of models;
/// with `out`, writes ridge_trace.csv, ridge_trace.svg and selection.json into it.
pub fn select(opts: &SelectOptions, obs: &mut dyn Observer) -> Result<SelectOutcome> {
    // where the files go is settled before any work: a folder, and none of them the input
    let guard = OutputGuard::new(&[&opts.data]);
    if let Some(dir) = &opts.out {
        check_selection_dir(&guard, dir)?;
    }
    let mut outcome = select_table(&Table::read(&opts.data)?, &opts.target, &opts.sensors)?;
    if let Some(dir) = &opts.out {
        write_selection_files(&guard, &outcome, dir)?;
        outcome.out = Some(dir.clone());
    }
    warn_all(obs, &outcome.warnings);
    Ok(outcome)
}

/// [`select`] of a log already read (a file, or the Python module's arrays): the selection,
/// nothing written (`out` is `None`; [`write_selection`] writes its files).
pub fn select_table(table: &Table, target: &str, sensors: &[String]) -> Result<SelectOutcome> {
    let data = load_table(table, Some(target), true, None)?;
    let err = |e| located(&data, &table.path, e);
    let features = temp_features(&data, sensors).map_err(err)?;
    let names: Vec<String> = features.iter().map(|f| f.name()).collect();
    let x = design(&data, &features).map_err(err)?;
    let y = data.target_um().map_err(err)?;
    let sel = select_sensors(&x, y, &names, RidgeTraceRules::default()).map_err(err)?;
    Ok(SelectOutcome {
        format: "mtec.thermal-selection/1".into(),
        target: data.target_name().unwrap_or_default().into(),
        warnings: sel.warnings.clone(),
        selection: sel,
        out: None,
    })
}

/// Whether the folder `dir` can take ridge_trace.csv, ridge_trace.svg and selection.json, none
/// of them over one of `inputs` (a usage error otherwise): checked before any work.
pub fn check_selection_out(dir: &Path, inputs: &[&Path]) -> Result<()> {
    check_selection_dir(&OutputGuard::new(inputs), dir)
}

/// Writes ridge_trace.csv, ridge_trace.svg and selection.json of `outcome` into the folder
/// `dir` (created), none of them over one of `inputs`: what [`select`] writes with `out`.
pub fn write_selection(outcome: &SelectOutcome, dir: &Path, inputs: &[&Path]) -> Result<()> {
    let guard = OutputGuard::new(inputs);
    check_selection_dir(&guard, dir)?;
    write_selection_files(&guard, outcome, dir)
}

/// The selection's folder: a folder (or nothing yet), and none of its three files an input.
fn check_selection_dir(guard: &OutputGuard, dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::usage(format!(
            "--out {} is a file: it must be a folder (ridge_trace.csv, ridge_trace.svg and selection.json go into it)",
            dir.display()
        )));
    }
    for f in ["ridge_trace.csv", "ridge_trace.svg", "selection.json"] {
        guard.check(&dir.join(f))?;
    }
    Ok(())
}

fn write_selection_files(guard: &OutputGuard, outcome: &SelectOutcome, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let sel = &outcome.selection;
    guard.write(&dir.join("ridge_trace.csv"), sel.trace.to_csv().as_bytes())?;
    let trace = mtec_report::ridge_trace::RidgeTrace {
        sensors: &sel.trace.sensors,
        k: &sel.trace.k,
        coefficients: &sel.trace.coefficients,
    };
    let svg = mtec_report::ridge_trace::ridge_trace_svg(&trace, sel.k)
        .map_err(|e| Error::Internal(anyhow::anyhow!("plot: {e}")))?;
    guard.write(&dir.join("ridge_trace.svg"), svg.as_bytes())?;
    guard.write(
        &dir.join("selection.json"),
        serde_json::to_string_pretty(&serde_json::to_value(outcome)?)?.as_bytes(),
    )?;
    Ok(())
}

impl fmt::Display for SelectOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sel = &self.selection;
        let target = &self.target;
        writeln!(
            f,
            "Variance inflation factors (VIF > 10: severe collinearity)"
        )?;
        for v in &sel.vif {
            writeln!(
                f,
                "  {:<16} {:>12} {}",
                v.sensor,
                v.vif
                    .map(|x| format!("{x:.1}"))
                    .unwrap_or_else(|| "inf".into()),
                if v.severe { "severe" } else { "" }
            )?;
        }
        writeln!(
            f,
            "\nRidge-trace elimination (rules: stable-small, unstable-to-zero, unstable, sign-change)"
        )?;
        for (i, s) in sel.steps.iter().enumerate() {
            writeln!(
                f,
                "  step {}: {:<17} removed {:<24} at k = {:.4}; remaining {}",
                i + 1,
                s.rule,
                s.removed.join(","),
                s.k,
                s.remaining.join(",")
            )?;
        }
        writeln!(
            f,
            "\nSelected sensors: {}   chosen k = {:.4}",
            sel.selected.join(", "),
            sel.k
        )?;
        let std_eq: Vec<String> = sel
            .selected
            .iter()
            .zip(&sel.standardised_coefficients)
            .map(|(s, b)| format!("{b:+.4}·z({s})"))
            .collect();
        writeln!(
            f,
            "Standardised equation:    z({target}) = {}",
            std_eq.join(" ")
        )?;
        let eq: Vec<String> = sel
            .selected
            .iter()
            .zip(&sel.coefficients)
            .map(|(s, b)| format!("{b:+.4}·{s}"))
            .collect();
        writeln!(
            f,
            "De-standardised equation: {target} = {:.4} {}",
            sel.intercept_um,
            eq.join(" ")
        )?;
        writeln!(f, "\nComparison")?;
        writeln!(
            f,
            "  {:<34} {:>3} {:>8} {:>10} {:>12} {:>10} {:>12}",
            "model", "n", "R²", "max|res|", "SSE", "MSE", "F"
        )?;
        for r in &sel.comparison {
            let m = &r.metrics;
            writeln!(
                f,
                "  {:<34} {:>3} {:>8} {:>10.3} {:>12.3} {:>10} {:>12}",
                r.model,
                r.sensors.len(),
                fmt_opt(m.r2, 4),
                m.max_abs_residual_um,
                m.sse_um2,
                fmt_opt(m.mse_um2, 4),
                fmt_opt(m.f_statistic, 1)
            )?;
        }
        match &self.out {
            Some(dir) => writeln!(
                f,
                "\nwrote {}/ridge_trace.csv, ridge_trace.svg, selection.json",
                dir.display()
            ),
            None => writeln!(f, "\n(nothing written: --out DIR writes ridge_trace.csv, ridge_trace.svg and selection.json)"),
        }
    }
}

// ---- fit ----

/// Options of [`fit`] (the regression models of [`mtec_thermal::registry`]).
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Thermal log (CSV).
    pub data: PathBuf,
    /// Target column (`ez_um` or `ez`).
    pub target: String,
    /// The model kind: a name of [`mtec_thermal::registry::KINDS`] (`auto`, `mlr`, ...).
    pub model: String,
    /// What the kind is fitted from (sensors, k, lags, blocks, ...).
    pub fit: registry::FitOptions,
    /// Which rows train and which test.
    pub split: SplitBy,
    /// Model file to write (JSON, `mtec.thermal-model/1`; `-`: stdout).
    pub output: PathBuf,
}

/// The fitted model file (written to `output`) and its warnings.
#[derive(Debug, Clone, Serialize)]
pub struct FitOutcome {
    pub output: PathBuf,
    /// The `mtec.thermal-model/1` document written.
    pub file: ModelFile,
    /// The fit's warnings (also in `file.warnings`).
    pub warnings: Vec<String>,
}

/// Fits a registered kind on the training rows, validates it forward, scores it and writes the
/// model file.
pub fn fit(opts: &FitOptions, obs: &mut dyn Observer) -> Result<FitOutcome> {
    let kind = checked_kind(&opts.model, &opts.fit)?;
    // where the model goes is settled before any work (an input, a directory: exit 2)
    let dest = OutputGuard::new(&[&opts.data]).check(&opts.output)?;
    let file = fit_checked(
        &Table::read(&opts.data)?,
        &opts.target,
        kind,
        &opts.fit,
        &opts.split,
    )?;
    let text = serde_json::to_string_pretty(&file)?;
    dest.write(text.as_bytes())?;
    warn_all(obs, &file.warnings);
    Ok(FitOutcome {
        output: opts.output.clone(),
        warnings: file.warnings.clone(),
        file,
    })
}

/// [`fit`] of a log already read (the Python module's arrays): the model file, not written.
pub fn fit_table(
    table: &Table,
    target: &str,
    model: &str,
    fit: &registry::FitOptions,
    split: &SplitBy,
) -> Result<ModelFile> {
    fit_checked(table, target, checked_kind(model, fit)?, fit, split)
}

fn fit_checked(
    table: &Table,
    target: &str,
    kind: &KindInfo,
    fit: &registry::FitOptions,
    split: &SplitBy,
) -> Result<ModelFile> {
    let input = Some((fit.input.as_str(), kind.requires_input));
    let data = load_table(table, Some(target), true, input)?;
    let err = |e| located(&data, &table.path, e);
    if let SplitBy::Experiments { train, test } = split {
        if train.is_empty() && !test.is_empty() {
            return Err(Error::usage("--test needs --train"));
        }
    }
    let rows = split_rows(&data, split).map_err(err)?;
    if rows.train.is_empty() {
        return Err(Error::usage("the training selection holds no rows"));
    }
    let spec = ModelSpec::from_options(kind.name, fit, &data).map_err(err)?;
    fit_file(&spec, &data, rows, &fit.blocks()).map_err(err)
}

/// One line of metrics as `thermal fit` prints them.
fn metrics_line(f: &mut fmt::Formatter<'_>, name: &str, m: &Metrics) -> fmt::Result {
    writeln!(
        f,
        "{name:<6} n={:<6} RMSE {:.3} um  MAE {:.3} um  max|res| {:.3} um  R² {}  compensation {}",
        m.n,
        m.rmse_um,
        m.mae_um,
        m.max_abs_residual_um,
        fmt_opt(m.r2, 4),
        m.compensation_rate
            .map(|c| format!("{:.1} %", 100.0 * c))
            .unwrap_or_else(|| "-".into())
    )
}

fn write_candidates(f: &mut fmt::Formatter<'_>, candidates: &[CandidateScore]) -> fmt::Result {
    writeln!(
        f,
        "auto: forward score of every candidate (mean fold RMSE ± standard error; pooled; worst fold vs no compensation)"
    )?;
    for c in candidates {
        match &c.forward {
            Some(fw) => {
                let folds: Vec<String> = fw
                    .folds
                    .iter()
                    .map(|x| format!("{:.2}/{:.2}", x.metrics.rmse_um, x.uncompensated_rmse_um))
                    .collect();
                // one fold has no standard error (the rule then takes the best mean)
                let se = if fw.folds.len() >= 2 {
                    format!("{:<6.3}", fw.rmse_std_error_um)
                } else {
                    format!("{:<6}", "n/a")
                };
                writeln!(
                    f,
                    "  {:<13} {:>7.3} ± {se} pooled {:>7.3} um  folds (model/none) {}{}{}",
                    c.family,
                    fw.mean_rmse_um(),
                    fw.pooled_rmse_um,
                    folds.join(" "),
                    if c.worse_than_uncompensated.is_empty() {
                        ""
                    } else {
                        "  worse than none: never chosen"
                    },
                    if c.chosen { "  <- chosen" } else { "" }
                )?;
            }
            None => writeln!(
                f,
                "  {:<13} not fitted: {}",
                c.family,
                c.error.as_deref().unwrap_or("")
            )?,
        }
    }
    // auto offers the heat-input families only with a heat-input column: say why they are absent
    if !candidates.iter().any(|c| c.family == "heat-input") {
        writeln!(
            f,
            "  heat-input, dynamic: not candidates: the log has no heat-input column (--input, default spindle_rpm)"
        )?;
    }
    Ok(())
}

/// The `thermal fit` report.
impl fmt::Display for FitOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = &self.file;
        if let ThermalModel::ExpAmbient(m) = &file.model {
            writeln!(f,
                "exp-ambient: δ = k·x + b, b = b_a(1 − exp(−ΔT_up/b_b)), k = k_a(1 − exp(−ΔT_nut/k_b)); b_a, ln b_b, k_a, ln k_b polynomials of degree {} in u = (T_a − 20 °C)/10 °C (coefficient ± standard uncertainty, ascending powers)",
                m.degree
            )?;
            for (name, group) in [("ΔT_up", &m.up_group), ("ΔT_nut", &m.nut_group)] {
                if !group.is_empty() {
                    let terms: Vec<String> = group
                        .iter()
                        .map(|g| format!("{:.4}·Δ{}", g.weight, g.sensor))
                        .collect();
                    writeln!(
                        f,
                        "  {name} = {} (first principal component)",
                        terms.join(" + ")
                    )?;
                }
            }
            for (name, c, sd) in [
                ("b_a [um]", &m.b_a, &m.b_a_sd),
                ("ln b_b [C]", &m.ln_b_b, &m.ln_b_b_sd),
                ("k_a [um/mm]", &m.k_a, &m.k_a_sd),
                ("ln k_b [C]", &m.ln_k_b, &m.ln_k_b_sd),
            ] {
                let terms: Vec<String> = c
                    .iter()
                    .zip(sd)
                    .map(|(c, s)| format!("{c:.5} ± {s:.5}"))
                    .collect();
                writeln!(f, "  {name:<12} {}", terms.join(", "))?;
            }
            if !m.held_at_cap.is_empty() {
                writeln!(f,
                    "  held at the linear-limit cap (100 × the largest training rise, not fitted; ± 0 means held): {}",
                    m.held_at_cap.join(", ")
                )?;
            }
            for l in &m.identifiability {
                writeln!(f,
                    "  at {} °C: b_b = {:.4} °C (max ΔT_up {:.2} °C), k_b = {:.4} °C (max ΔT_nut {:.2} °C)",
                    l.ambient_c, l.b_b_c, l.max_dt_up_c, l.k_b_c, l.max_dt_nut_c
                )?;
            }
        }
        if !file.candidates.is_empty() {
            write_candidates(f, &file.candidates)?;
        }
        if let ThermalModel::Linear(m) = &file.model {
            let names: Vec<String> = m.features.iter().map(|f| f.name()).collect();
            writeln!(f, "features: {}", names.join(", "))?;
        }
        metrics_line(f, "train", &file.train_metrics)?;
        if let Some(v) = &file.validation {
            writeln!(
                f,
                "forward validation on the training rows: {} folds, pooled RMSE {:.3} um (the uncertainty predict reports), mean {:.3} ± {:.3} um",
                v.folds.len(),
                v.pooled_rmse_um,
                v.mean_rmse_um(),
                v.rmse_std_error_um
            )?;
        }
        if let Some(m) = &file.test_metrics {
            metrics_line(f, "test", m)?;
        }
        writeln!(f, "wrote {}", self.output.display())
    }
}

// ---- predict ----

/// Options of [`predict`].
#[derive(Debug, Clone)]
pub struct PredictOptions {
    /// Model file (JSON: `mtec.thermal-model/1`, or with the feature `neural` also
    /// `mtec.cnn-lstm/1`, `mtec.bpnn/1`).
    pub model: PathBuf,
    /// Thermal log (CSV) with the model's sensors.
    pub data: PathBuf,
    /// The log before `data` (same columns): the model's filters run through it first.
    pub history: Option<PathBuf>,
    /// Where the predictions go (CSV; `-`: stdout). `None`: the CSV is only in the outcome
    /// ([`PredictOutcome::csv`]).
    pub output: Option<PathBuf>,
    /// A rotary model's predicted ballbar readings (neural models of the five error motions).
    pub readings: Option<ReadingsOptions>,
}

/// Where the ballbar readings of a rotary model's predictions come from and go
/// (`thermal predict --setup --dbb [--readings]`).
#[derive(Debug, Clone)]
pub struct ReadingsOptions {
    /// The ballbar setup (TOML, the modes).
    pub setup: PathBuf,
    /// The ballbar readings (`experiment,time_min,mode,angle_deg,dl_um`).
    pub dbb: PathBuf,
    /// Where the predicted and measured readings go (CSV); `None`: only in the outcome.
    pub out: Option<PathBuf>,
}

impl ReadingsOptions {
    /// The readings asked for when both the setup and the DBB file are given.
    pub fn given(
        setup: Option<PathBuf>,
        dbb: Option<PathBuf>,
        out: Option<PathBuf>,
    ) -> Option<ReadingsOptions> {
        Some(ReadingsOptions {
            setup: setup?,
            dbb: dbb?,
            out,
        })
    }
}

/// The predictions of a regression model file.
#[derive(Debug, Clone, Serialize)]
pub struct Prediction {
    pub format: String,
    pub target: String,
    pub n: usize,
    /// Predicted drift per row of the data, µm.
    pub predictions: Vec<f64>,
    /// The model's forward-validation pooled RMSE, µm (`None`: the file has no validation).
    pub uncertainty_um: Option<f64>,
    /// Rows with an input outside the training range.
    pub rows_outside_training_range: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rmse_um: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mae_um: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_abs_residual_um: Option<f64>,
    /// Against the target, when the data hold it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub metrics: Option<Metrics>,
    /// Per row: the inputs outside the training range, `;`-separated (empty: none).
    #[serde(skip)]
    pub outside_training_range: Vec<String>,
    /// `experiment,time_min,predicted_um[,measured_um,residual_um][,uncertainty_um],outside_training_range`
    #[serde(skip)]
    pub csv: String,
    /// What the user should know that is not a warning (filters started in equilibrium, no
    /// uncertainty).
    #[serde(skip)]
    pub notes: Vec<String>,
    #[serde(skip)]
    pub warnings: Vec<String>,
}

/// The predictions of a model file of any kind.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum PredictOutcome {
    /// Boxed: the metrics make it the large variant.
    Regression(Box<Prediction>),
    #[cfg(feature = "neural")]
    Neural(neural::Prediction),
}

impl PredictOutcome {
    /// The predicted drift of `target` (`ch1` or `ch1_um`) per row, µm; `None` when the model
    /// does not predict it.
    pub fn predictions_of(&self, target: &str) -> Option<Vec<f64>> {
        let column = mtec_thermal::data::target_column(target);
        match self {
            PredictOutcome::Regression(p) => (mtec_thermal::data::target_column(&p.target)
                == column)
                .then(|| p.predictions.clone()),
            #[cfg(feature = "neural")]
            PredictOutcome::Neural(p) => {
                let j = p
                    .targets
                    .iter()
                    .position(|t| mtec_thermal::data::target_column(t) == column)?;
                p.predictions
                    .iter()
                    .map(|row| row.get(j).copied())
                    .collect()
            }
        }
    }

    /// The prediction CSV (also written to `output` when given).
    pub fn csv(&self) -> &str {
        match self {
            PredictOutcome::Regression(p) => &p.csv,
            #[cfg(feature = "neural")]
            PredictOutcome::Neural(p) => &p.csv,
        }
    }
    /// Notes for the user (not warnings).
    pub fn notes(&self) -> &[String] {
        match self {
            PredictOutcome::Regression(p) => &p.notes,
            #[cfg(feature = "neural")]
            PredictOutcome::Neural(_) => &[],
        }
    }
}

/// The report beside the CSV: the neural models' metrics table (the regression models have
/// none: their metrics are in the JSON).
impl fmt::Display for PredictOutcome {
    #[cfg_attr(not(feature = "neural"), allow(unused_variables))]
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PredictOutcome::Regression(_) => Ok(()),
            #[cfg(feature = "neural")]
            PredictOutcome::Neural(p) => write!(f, "{p}"),
        }
    }
}

/// The neural format `path` declares (`mtec.cnn-lstm/1`, `mtec.bpnn/1`), or `None` for any
/// other model file.
pub fn neural_format(path: &Path) -> Result<Option<&'static str>> {
    let v: serde_json::Value = mtec_io::read_json(path)?;
    Ok(match v.get("format").and_then(|f| f.as_str()) {
        Some(CNN_LSTM_FORMAT) => Some(CNN_LSTM_FORMAT),
        Some(f) if f == mtec_comp::bpnn::FORMAT => Some(mtec_comp::bpnn::FORMAT),
        _ => None,
    })
}

/// The model file of a CNN-LSTM (`mtec_nn::cnn_lstm::FORMAT`; a test checks they agree).
pub const CNN_LSTM_FORMAT: &str = "mtec.cnn-lstm/1";

/// Predicts with a model file: the drift per row, metrics when the data hold the target, and
/// the CSV (written to `output` when given). A neural model file goes to [`neural::predict`].
pub fn predict(opts: &PredictOptions, obs: &mut dyn Observer) -> Result<PredictOutcome> {
    if let Some(format) = neural_format(&opts.model)? {
        #[cfg(feature = "neural")]
        {
            let _ = format;
            return neural::predict(opts, obs).map(PredictOutcome::Neural);
        }
        #[cfg(not(feature = "neural"))]
        return Err(crate::neural_unavailable(&format!(
            "`thermal predict` with a {format} model ({})",
            opts.model.display()
        )));
    }
    predict_regression(opts, obs).map(|p| PredictOutcome::Regression(Box::new(p)))
}

fn predict_regression(opts: &PredictOptions, obs: &mut dyn Observer) -> Result<Prediction> {
    if opts.readings.is_some() {
        return Err(Error::usage(
            "--setup/--dbb (predicted ballbar readings) go with a rotary model of the five error \
             motions (cnn-lstm or bpnn, fitted on `identify ballbar --temps` motions)",
        ));
    }
    // where the predictions go is settled before any work (an input, a directory: exit 2)
    let dest = match &opts.output {
        Some(p) => {
            let mut g = OutputGuard::new(&[&opts.data, &opts.model]);
            if let Some(h) = &opts.history {
                g.add_input(h);
            }
            Some(g.check(p)?)
        }
        None => None,
    };
    let file = read_model(&opts.model)?;
    let data = Table::read(&opts.data)?;
    let history = match &opts.history {
        Some(h) => Some(Table::read(h)?),
        None => None,
    };
    let p = predict_table(&file, &data, history.as_ref())?;
    if let Some(d) = &dest {
        d.write(p.csv.as_bytes())?;
    }
    warn_all(obs, &p.warnings);
    Ok(p)
}

/// A regression model file (`mtec.thermal-model/1`), its format checked.
pub fn read_model(path: &Path) -> Result<ModelFile> {
    let file: ModelFile = mtec_io::read_json(path)?;
    file.check_format()
        .map_err(|e| Error::Input(InputError::file(path, e.to_string())))?;
    Ok(file)
}

/// [`predict`] of a regression model on logs already read (the Python module's arrays): the
/// prediction with its CSV, nothing written. `history` is the log before `data`.
pub fn predict_table(
    file: &ModelFile,
    data: &Table,
    history: Option<&Table>,
) -> Result<Prediction> {
    let data_path = &data.path;
    // a non-temperature column the model reads (the heat input) must be in the data
    let input_name = model_columns(&file.model)
        .into_iter()
        .find(|c| !c.ends_with("_c") && c != "position_mm");
    let input = input_name.as_deref().map(|n| (n, true));
    let data = load_table(data, Some(&file.target), false, input)?;
    let mut notes = Vec::new();
    let (pred, outside) = match history {
        Some(h) => {
            let hist = load_table(h, None, false, input)?;
            let all = hist
                .followed_by(&data)
                .map_err(|e| Error::Input(InputError::file(&h.path, e.to_string())))?;
            let p = file
                .model
                .predict(&all)
                .map_err(|e| located(&all, data_path, e))?;
            let o = outside_envelope(&file.envelope, &all);
            (p[hist.len()..].to_vec(), o[hist.len()..].to_vec())
        }
        None => {
            if file.model.has_state() {
                let t0 = data.time_min.first().copied().unwrap_or(0.0);
                notes.push(format!(
                    "the model's filters start in equilibrium with the first row of {} (time_min {t0}){}; pass the log before it with --history FILE if the machine was not at rest and settled then",
                    data_path.display(),
                    if t0 > 0.0 { ", which starts mid-record" } else { "" }
                ));
            }
            let p = file
                .model
                .predict(&data)
                .map_err(|e| located(&data, data_path, e))?;
            (p, outside_envelope(&file.envelope, &data))
        }
    };
    let uncertainty = file.validation.as_ref().map(|v| v.pooled_rmse_um);
    let n_out = outside.iter().filter(|o| !o.is_empty()).count();
    let mut warnings = Vec::new();
    if n_out > 0 {
        let mut cols: Vec<&String> = outside.iter().flatten().collect();
        cols.sort();
        cols.dedup();
        let first = outside.iter().position(|o| !o.is_empty()).unwrap_or(0);
        warnings.push(format!(
            "{n_out} of {} rows have inputs outside the training range ({}; first at line {}): the model extrapolates there and its uncertainty does not hold",
            outside.len(),
            cols.iter().map(|c| c.as_str()).collect::<Vec<_>>().join(", "),
            data.lines.get(first).copied().unwrap_or(0)
        ));
    }
    if uncertainty.is_none() {
        notes.push("the model file has no forward validation, so the predictions carry no uncertainty (refit with this mtec)".into());
    }
    let y = data.target_um().ok();
    let metrics = y.map(|y| Metrics::new(y, &pred, file.model.predictors()));
    let mut header = vec!["experiment", "time_min", "predicted_um"];
    if y.is_some() {
        header.extend(["measured_um", "residual_um"]);
    }
    if uncertainty.is_some() {
        header.push("uncertainty_um");
    }
    header.push("outside_training_range");
    let mut csv = CsvWriter::new(header);
    for i in 0..pred.len() {
        let mut row = vec![
            data.experiment[i].to_string(),
            data.time_min[i].to_string(),
            format!("{:.4}", pred[i]),
        ];
        if let Some(y) = y {
            row.extend([format!("{:.4}", y[i]), format!("{:.4}", y[i] - pred[i])]);
        }
        if let Some(u) = uncertainty {
            row.push(format!("{u:.4}"));
        }
        row.push(outside[i].join(";"));
        csv.row(row);
    }
    let csv = csv.finish();
    Ok(Prediction {
        format: "mtec.thermal-prediction/1".into(),
        target: file.target.clone(),
        n: pred.len(),
        uncertainty_um: uncertainty,
        rows_outside_training_range: n_out,
        rmse_um: metrics.as_ref().map(|m| m.rmse_um),
        mae_um: metrics.as_ref().map(|m| m.mae_um),
        max_abs_residual_um: metrics.as_ref().map(|m| m.max_abs_residual_um),
        metrics,
        predictions: pred,
        outside_training_range: outside.iter().map(|o| o.join(";")).collect(),
        csv,
        notes,
        warnings,
    })
}

// ---- cv ----

/// Options of [`cv`].
#[derive(Debug, Clone)]
pub struct CvOptions {
    /// Thermal log (CSV).
    pub data: PathBuf,
    /// Target column.
    pub target: String,
    /// The model kind (a name of [`mtec_thermal::registry::KINDS`]).
    pub model: String,
    /// What the kind is fitted from.
    pub fit: registry::FitOptions,
    /// Leave-one-block-out instead of forward folds (optimistic).
    pub loo: bool,
}

/// Forward validation: `mtec.thermal-cv/2`.
#[derive(Debug, Clone, Serialize)]
pub struct ForwardOutcome {
    pub format: String,
    pub protocol: String,
    #[serde(flatten)]
    pub cv: ForwardCv,
    /// 1-based folds where the model is worse than no compensation.
    pub folds_worse_than_uncompensated: Vec<usize>,
    #[serde(skip)]
    pub warnings: Vec<String>,
}

/// Leave-one-block-out: `mtec.thermal-cv/1`.
#[derive(Debug, Clone, Serialize)]
pub struct BlockOutcome {
    pub format: String,
    pub protocol: String,
    #[serde(flatten)]
    pub cv: BlockCv,
    /// Why the score is optimistic.
    #[serde(skip)]
    pub note: String,
}

/// The validation [`cv`] ran.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum CvOutcome {
    Forward(ForwardOutcome),
    LeaveOneBlockOut(BlockOutcome),
}

/// Forward (rolling-origin) validation of a registered kind over the whole log, or
/// leave-one-block-out with `loo`. A network (`bpnn`, `cnn-lstm`, cargo feature `neural`) is
/// validated the same way with its default options ([`neural_log::cv`] takes others).
pub fn cv(opts: &CvOptions, obs: &mut dyn Observer) -> Result<CvOutcome> {
    if is_neural(&opts.model) {
        #[cfg(feature = "neural")]
        {
            let kind = mtec_nn::thermal_log::NnKind::from_name(&opts.model).expect("a network");
            let nn = mtec_nn::thermal_log::NnFitOptions::new(kind);
            return neural_log::cv(opts, &nn, obs);
        }
        #[cfg(not(feature = "neural"))]
        return Err(crate::neural_unavailable(&format!(
            "`thermal cv --model {}`",
            opts.model
        )));
    }
    let kind = checked_kind(&opts.model, &opts.fit)?;
    let outcome = cv_checked(&Table::read(&opts.data)?, kind, opts)?;
    if let CvOutcome::Forward(o) = &outcome {
        warn_all(obs, &o.warnings);
    }
    Ok(outcome)
}

/// [`cv`] of a log already read (the Python module's arrays) with a registered kind (the
/// networks need the CLI's `neural` build): the validation, its warnings in the outcome.
pub fn cv_table(
    table: &Table,
    target: &str,
    model: &str,
    fit: &registry::FitOptions,
    loo: bool,
) -> Result<CvOutcome> {
    let kind = checked_kind(model, fit)?;
    let opts = CvOptions {
        data: table.path.clone(),
        target: target.into(),
        model: model.into(),
        fit: fit.clone(),
        loo,
    };
    cv_checked(table, kind, &opts)
}

fn cv_checked(table: &Table, kind: &KindInfo, opts: &CvOptions) -> Result<CvOutcome> {
    let input = Some((opts.fit.input.as_str(), kind.requires_input));
    let data = load_table(table, Some(&opts.target), true, input)?;
    let spec = ModelSpec::from_options(kind.name, &opts.fit, &data)
        .map_err(|e| located(&data, &table.path, e))?;
    validate_cv(&spec, &data, opts)
}

/// [`cv`] of the fitter `fitter` (a registered kind's spec, or a network) on `data`: the
/// forward folds or, with `opts.loo`, the blocks left out one by one.
fn validate_cv<F: Fit>(fitter: &F, data: &ThermalData, opts: &CvOptions) -> Result<CvOutcome> {
    let err = |e| located(data, &opts.data, e);
    let all: Vec<usize> = (0..data.len()).collect();
    if !opts.loo {
        let folds = forward_folds(&duty_cycle_blocks(data, &all, &opts.fit.blocks()));
        if folds.is_empty() {
            return Err(Error::usage("forward validation needs at least two blocks (experiments, steps of the --input column, or --block-min shorter than the record)"));
        }
        let res = forward_cv(fitter, data, &folds).map_err(err)?;
        let warnings: Vec<String> = worse_warning(&res).into_iter().collect();
        return Ok(CvOutcome::Forward(ForwardOutcome {
            format: "mtec.thermal-cv/2".into(),
            protocol: "forward".into(),
            folds_worse_than_uncompensated: res.folds_worse_than_uncompensated(),
            cv: res,
            warnings,
        }));
    }
    let blocks: Vec<Vec<usize>> = match opts.fit.block_min {
        Some(b) if b > 0.0 => time_blocks(data, b),
        Some(_) => return Err(Error::usage("--block-min must be > 0")),
        None => data
            .experiments()
            .iter()
            .map(|e| rows_of_experiments(data, std::slice::from_ref(e)))
            .collect::<std::result::Result<_, _>>()
            .map_err(err)?,
    };
    if blocks.len() < 2 {
        return Err(Error::usage("leave-one-block-out needs at least two blocks (experiments, or --block-min shorter than the record)"));
    }
    let res = block_cv(fitter, data, &blocks).map_err(err)?;
    Ok(CvOutcome::LeaveOneBlockOut(BlockOutcome {
        format: "mtec.thermal-cv/1".into(),
        protocol: "leave-one-block-out (optimistic)".into(),
        cv: res,
        note: "leave-one-block-out trains on the future of every block it scores: optimistic for a model that must predict forward (the default forward validation is the honest score)".into(),
    }))
}

impl fmt::Display for CvOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CvOutcome::Forward(o) => {
                let res = &o.cv;
                writeln!(
                    f,
                    "forward validation: fit on every block before, score the next block"
                )?;
                for (i, s) in res.folds.iter().enumerate() {
                    writeln!(
                        f,
                        "fold {:<3} train {:.0}–{:.0} min, score {:.0}–{:.0} min  n={:<6} RMSE {:.3} um  max|res| {:.3} um  uncompensated {:.3} um{}",
                        i + 1,
                        s.train_from_min,
                        s.train_to_min,
                        s.test_from_min,
                        s.test_to_min,
                        s.metrics.n,
                        s.metrics.rmse_um,
                        s.metrics.max_abs_residual_um,
                        s.uncompensated_rmse_um,
                        if s.worse_than_uncompensated() { "  WORSE THAN NO COMPENSATION" } else { "" }
                    )?;
                }
                writeln!(
                    f,
                    "pooled RMSE {:.3} um, max|res| {:.3} um; mean fold RMSE {:.3} ± {:.3} um",
                    res.pooled_rmse_um,
                    res.pooled_max_abs_um,
                    res.mean_rmse_um(),
                    res.rmse_std_error_um
                )
            }
            CvOutcome::LeaveOneBlockOut(o) => {
                for (i, m) in o.cv.per_block.iter().enumerate() {
                    writeln!(
                        f,
                        "block {:<3} n={:<6} RMSE {:.3} um  max|res| {:.3} um",
                        i + 1,
                        m.n,
                        m.rmse_um,
                        m.max_abs_residual_um
                    )?;
                }
                writeln!(
                    f,
                    "pooled RMSE {:.3} um, max|res| {:.3} um (leave-one-block-out: optimistic)",
                    o.cv.pooled_rmse_um, o.cv.pooled_max_abs_um
                )
            }
        }
    }
}
