//! `mtec thermal select|fit|predict|cv`: thermal error models from temperature logs.

use crate::error::CliError;
use mtec_io::{InputError, OutputGuard, Table};
use mtec_thermal::auto::{Auto, CandidateScore};
use mtec_thermal::guard::{envelope, outside_envelope};
use mtec_thermal::model::{ModelFile, Split, ThermalModel};
use mtec_thermal::select::{select_sensors, SelectOptions, Selection};
use mtec_thermal::validate::{
    block_cv, duty_cycle_blocks, forward_cv, forward_folds, rows_of_experiments, split_at_time,
    time_blocks, BlockSpec, ForwardCv,
};
use mtec_thermal::{
    features::{design, temp_features},
    heat_input::with_input,
    ExpAmbient, Fit, HeatInput, LagSelect, Metrics, Mlr, Predict, Ridge, RidgeSelect, ThermalData,
    ThermalError, MODEL_FORMAT,
};
use std::io::Write;
use std::path::{Path, PathBuf};

const FORMAT_HELP: &str = "\
Thermal log format (CSV, docs/formats.md, Thermal CSV):
  experiment,time_min,<sensor>_c...,[ambient_c],[position_mm],<target>_um
Every `_c` column except `ambient_c` is a temperature sensor. `experiment` may be absent (one
continuous record). Rows of one experiment are in time order. Other columns are ignored.";

const SELECT_EXAMPLES: &str = crate::help::examples!(
    "  # eight collinear spindle temperature sensors and the radial drift
  $ mtec simulate spindle-sensors --out t
  # VIF, ridge trace and the sensors the ridge-trace rules keep; plots in t/sel
  $ mtec thermal select --data t/thermal.csv --target radial_um --out t/sel"
);

const FIT_EXAMPLES: &str = crate::help::examples!(
    "  # Z drift along the axis at ambient 15, 20, 25 and 30 C (experiments 1 to 4)
  $ mtec simulate feed-axis-ambient --out f
  # the exp-ambient model: trained at 15, 20 and 30 C, tested at 25 C
  $ mtec thermal fit --data f/thermal.csv --target ez_um --model exp-ambient \\
      --sensors up,nut --train 1,2,4 --test 3 -o f/z.json
  # plain multiple linear regression on the same two sensors, to compare
  $ mtec thermal fit --data f/thermal.csv --target ez_um --model mlr \\
      --sensors up,nut --train 1,2,4 --test 3 -o f/z-mlr.json
  # a build with the neural models (cargo feature `neural`) also fits
  # --model bpnn --hidden 8 --features position_mm, and --model cnn-lstm"
);

const PREDICT_EXAMPLES: &str = crate::help::examples!(
    "  # a Z drift model trained at three ambient temperatures
  $ mtec simulate feed-axis-ambient --out f
  $ mtec thermal fit --data f/thermal.csv --target ez_um --model exp-ambient \\
      --sensors up,nut --train 1,2,4 --test 3 -o f/z.json
  # the prediction per row, residual where the log has ez_um, and the RMSE
  $ mtec thermal predict --model f/z.json --data f/thermal.csv -o f/pred.csv"
);

const CV_EXAMPLES: &str = crate::help::examples!(
    "  # 4 production days: temperatures, spindle speed, drift at the table centre
  $ mtec simulate production-day --out p
  # which model predicts each block's Z drift best from the blocks before it
  $ mtec thermal cv --data p/train.csv --target dz_um --model auto \\
      --input spindle_rpm"
);

/// Thermal error models: sensor selection, fitting and prediction.
#[derive(clap::Args)]
#[command(after_help = FORMAT_HELP)]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// VIF table, ridge trace, sensor elimination by the ridge-trace rules, chosen k, and the
    /// comparison of full MLR, ridge-selected and simple-correlation models. Warns when the
    /// selection collapses (its R² falls well below that of all sensors).
    ///
    /// --out DIR writes DIR/ridge_trace.csv, DIR/ridge_trace.svg and DIR/selection.json besides
    /// printing the report; without --out nothing is written; `--json` prints the selection as
    /// JSON instead.
    Select(SelectArgs),
    /// Fits a model and writes it as JSON (`mtec.thermal-model/1`) with train/test metrics.
    ///
    /// Every regression model is validated forward in time on its training rows (fit on the
    /// blocks before, score the next; blocks follow the --input steps); the model file keeps
    /// the folds, their pooled RMSE (the uncertainty `predict` reports) and the training range
    /// of every input (`predict` flags rows outside it).
    ///
    /// auto: candidate families mlr, ridge, heat-input, lagged-ridge, dynamic (temperatures,
    /// their first-order lags and lags of the spindle power, time constants fitted with the
    /// coefficients), exp-ambient when its columns exist; every choice inside each family made
    /// by forward folds of the fold's training rows (nested); a family worse than no
    /// compensation on any fold is never chosen; the simplest within one standard error of the
    /// best wins; at most --max-sensors temperature sensors (default 6) plus the --input column.
    ///
    /// Models: mlr (all or --sensors), ridge (k by forward folds, or --k), ridge-select
    /// (sensors chosen by the ridge trace), exp-ambient (δ = k·x + b with exponential
    /// saturation in the temperature rises of --sensors UP,NUT, or of the first principal
    /// components of --up-sensors A,B --nut-sensors C,D, and cubic-in-ambient coefficients, b_b
    /// and k_b kept positive; needs ambient_c and position_mm; warns when the rises stay in the
    /// exponential's linear range, where b_a and b_b cannot be told apart), lag-select (forward selection of up to
    /// --max-sensors sensors, each with a first-order lag of fitted time constant, scored by
    /// leaving out whole blocks of --block-min minutes or experiments), heat-input (drift =
    /// response to the spindle power: δ = b₀ + Σ c_m·L_τm[(n/1000)^α] + ambient sensors, n from
    /// the --input column, time constants s·τ at rest (s = 1…4: a turning spindle cools faster),
    /// α, τ bank, s, ridge k and ambient sensors chosen by leaving out blocks of the training
    /// rows). --lag adds a first-order lag of each sensor, its time constant chosen by how the
    /// model predicts forward folds of the training rows (mlr, ridge, ridge-select).
    ///
    /// Neural models (in a build with the cargo feature `neural`; any number of comma-separated
    /// --target columns; the model file is
    /// `mtec.cnn-lstm/1` or `mtec.bpnn/1`): cnn-lstm (1-D convolution over the features of each
    /// time step, max pooling, LSTM over --window steps, dense output; one sequence per
    /// experiment, or per value of --sequence-by within it) and bpnn (one hidden layer of
    /// --hidden sigmoid units on the current row, Levenberg–Marquardt). Features: the sensors,
    /// then --features columns. Training shows epoch, loss and validation loss (the tail of
    /// every training sequence), stops early when the validation loss no longer improves, and
    /// on Ctrl-C keeps the best epoch so far.
    Fit(Box<FitArgs>),
    /// Predicts the drift with a model file; metrics when the data hold the target. Also reads
    /// the neural models (`mtec.cnn-lstm/1`, `mtec.bpnn/1`): then one `pred_<target>` column per
    /// target (and `<target>,res_<target>` when the data hold it).
    Predict(PredictArgs),
    /// Forward (rolling-origin) validation: fit on every block before, score the next block,
    /// step forward. Blocks follow the duty cycle (a new block where the --input column steps),
    /// or experiments, or --block-min minutes. Each fold shows the error without compensation
    /// and is flagged when the model is worse. --loo gives leave-one-block-out instead, which
    /// trains on the future of the scored block and is optimistic.
    Cv(CvArgs),
}

#[derive(clap::Args)]
#[command(after_long_help = SELECT_EXAMPLES)]
struct SelectArgs {
    /// Thermal log (CSV).
    #[arg(long)]
    data: PathBuf,
    /// Target column (`radial_um` or `radial`).
    #[arg(long)]
    target: String,
    /// Candidate sensors (default: every `_c` column but ambient_c).
    #[arg(long, value_delimiter = ',')]
    sensors: Vec<String>,
    /// Folder for ridge_trace.csv, ridge_trace.svg, selection.json (default: write nothing).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print the selection as JSON (`mtec.thermal-selection/1`) on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, clap::ValueEnum, PartialEq)]
enum ModelKind {
    /// Chooses the family by nested forward validation (see `fit --help`).
    Auto,
    Mlr,
    Ridge,
    RidgeSelect,
    ExpAmbient,
    LagSelect,
    HeatInput,
    /// Neural (a build with `--features neural`): CNN-LSTM sequence model (several targets;
    /// --window, --sequence-by, ...).
    CnnLstm,
    /// Neural (a build with `--features neural`): one-hidden-layer BPNN on the current row
    /// (several targets; --hidden).
    Bpnn,
}

impl ModelKind {
    fn neural(self) -> Option<super::neural::NnKind> {
        match self {
            ModelKind::CnnLstm => Some(super::neural::NnKind::CnnLstm),
            ModelKind::Bpnn => Some(super::neural::NnKind::Bpnn),
            _ => None,
        }
    }
}

#[derive(clap::Args)]
struct Common {
    /// Thermal log (CSV).
    #[arg(long)]
    data: PathBuf,
    /// Target column (`ez_um` or `ez`); cnn-lstm and bpnn take several, comma-separated.
    #[arg(long)]
    target: String,
    /// Model family.
    #[arg(long, value_enum)]
    model: ModelKind,
    /// Sensors to use (exp-ambient: exactly two, the upper bearing then the nut).
    #[arg(long, value_delimiter = ',')]
    sensors: Vec<String>,
    /// Ridge parameter k (correlation form); default: where the ridge trace stabilises.
    #[arg(long)]
    k: Option<f64>,
    /// Add a first-order lag feature per sensor, its time constant chosen by forward folds of the
    /// training rows (blocks as --input/--block-min; not by the training fit).
    #[arg(long)]
    lag: bool,
    /// Validation block length in minutes (default: experiments, or the steps of the --input
    /// column, or eight equal blocks).
    #[arg(long)]
    block_min: Option<f64>,
    /// auto and lag-select: largest number of temperature sensors (default: auto 6,
    /// lag-select 3); the --input column does not count.
    #[arg(long)]
    max_sensors: Option<usize>,
    /// The heat-source column (spindle speed, rpm): heat-input and auto's heat features, and
    /// the duty-cycle steps that cut the validation blocks (used when the file has it).
    #[arg(long, default_value = "spindle_rpm")]
    input: String,
    /// exp-ambient: ΔT_up from several sensors — the first principal component of their
    /// (standardised) rises, as a weighted mean in °C. Goes with --nut-sensors, instead of
    /// --sensors.
    #[arg(
        long,
        value_delimiter = ',',
        requires = "nut_sensors",
        conflicts_with = "sensors"
    )]
    up_sensors: Vec<String>,
    /// exp-ambient: ΔT_nut from several sensors (like --up-sensors).
    #[arg(
        long,
        value_delimiter = ',',
        requires = "up_sensors",
        conflicts_with = "sensors"
    )]
    nut_sensors: Vec<String>,
}

#[derive(clap::Args)]
#[command(after_long_help = FIT_EXAMPLES)]
struct FitArgs {
    #[command(flatten)]
    common: Common,
    /// Train on rows with time_min ≤ MIN, test on the rest.
    #[arg(long, conflicts_with_all = ["train", "test"])]
    train_until: Option<f64>,
    /// Experiments to train on (comma-separated).
    #[arg(long, value_delimiter = ',')]
    train: Vec<String>,
    /// Experiments to test on (comma-separated).
    #[arg(long, value_delimiter = ',')]
    test: Vec<String>,
    /// Model file to write (JSON).
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    #[command(flatten)]
    nn: super::neural::NnArgs,
}

#[derive(clap::Args)]
#[command(after_long_help = PREDICT_EXAMPLES)]
struct PredictArgs {
    /// Model file (JSON, `mtec.thermal-model/1`).
    #[arg(long)]
    model: PathBuf,
    /// Thermal log (CSV) with the model's sensors.
    #[arg(long)]
    data: PathBuf,
    /// The log before --data (same columns): run the model's filters through it first, so a
    /// --data that starts mid-record starts from the machine's real thermal state. Without it,
    /// the filters start in equilibrium with the first row of --data (stated on stderr).
    #[arg(long)]
    history: Option<PathBuf>,
    /// Print `{rmse_um, mae_um, max_abs_residual_um, n, predictions, metrics}` as JSON.
    #[arg(long)]
    json: bool,
    /// Write `experiment,time_min,predicted_um[,measured_um,residual_um]` here (default stdout).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
}

#[derive(clap::Args)]
#[command(after_long_help = CV_EXAMPLES)]
struct CvArgs {
    #[command(flatten)]
    common: Common,
    /// Print the per-block metrics as JSON.
    #[arg(long)]
    json: bool,
    /// Leave-one-block-out instead of forward folds (optimistic: trains on the future of the
    /// block it scores).
    #[arg(long)]
    loo: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    match args.cmd {
        Sub::Select(a) => select(a),
        Sub::Fit(a) => match a.common.model.neural() {
            Some(kind) => fit_neural(kind, *a),
            None => fit(*a),
        },
        Sub::Predict(a) => predict_any(a),
        Sub::Cv(a) if a.common.model.neural().is_some() => Err(CliError::usage(
            "thermal cv runs the regression models; for cnn-lstm and bpnn use thermal fit --train ... --test ...",
        )),
        Sub::Cv(a) => cv(a),
    }
}

/// `thermal predict`: a neural model file goes to `thermal_nn`, any other to [`predict`].
#[cfg(feature = "neural")]
fn predict_any(a: PredictArgs) -> Result<(), CliError> {
    match super::thermal_nn::read_model(&a.model)? {
        Some(m) => super::thermal_nn::predict(m, &a.model, &a.data, a.json, a.output.as_ref()),
        None => predict(a),
    }
}

/// `thermal predict` without the neural models: their model files are refused (exit 2).
#[cfg(not(feature = "neural"))]
fn predict_any(a: PredictArgs) -> Result<(), CliError> {
    match super::neural::neural_format(&a.model)? {
        Some(format) => Err(super::neural::unavailable(&format!(
            "`thermal predict` with a {format} model ({})",
            a.model.display()
        ))),
        None => predict(a),
    }
}

/// `--model cnn-lstm|bpnn` in a build without the neural models.
#[cfg(not(feature = "neural"))]
fn fit_neural(kind: super::neural::NnKind, _a: FitArgs) -> Result<(), CliError> {
    Err(super::neural::unavailable(match kind {
        super::neural::NnKind::CnnLstm => "`thermal fit --model cnn-lstm`",
        super::neural::NnKind::Bpnn => "`thermal fit --model bpnn`",
    }))
}

/// `--model cnn-lstm|bpnn`: the options the neural fit does not take are refused here.
#[cfg(feature = "neural")]
fn fit_neural(kind: super::neural::NnKind, a: FitArgs) -> Result<(), CliError> {
    let c = &a.common;
    if c.k.is_some() || c.lag || c.block_min.is_some() || a.train_until.is_some() {
        return Err(CliError::usage(
            "--k, --lag, --block-min and --train-until go with the regression models; the neural models split by --train/--test experiments",
        ));
    }
    super::thermal_nn::fit(super::thermal_nn::FitRequest {
        kind,
        data: &c.data,
        target: &c.target,
        sensors: &c.sensors,
        train: &a.train,
        test: &a.test,
        output: &a.output,
        nn: &a.nn,
    })
}

fn load(path: &Path, target: Option<&str>, require: bool) -> Result<ThermalData, CliError> {
    load_with_input(path, target, require, None)
}

/// A non-temperature input column to attach: its name and whether the file must have it.
type InputColumn<'a> = Option<(&'a str, bool)>;

/// Reads the log and attaches the heat-source column (e.g. `spindle_rpm`): required for
/// heat-input models, otherwise when the file has it (it marks the duty-cycle blocks).
fn load_with_input(
    path: &Path,
    target: Option<&str>,
    require: bool,
    input: InputColumn,
) -> Result<ThermalData, CliError> {
    let t = Table::read(path)?;
    let d = ThermalData::from_table(&t, target, require)?;
    match input {
        Some((name, required)) if required || t.has(name) => {
            let v = t.f64_column(name)?;
            with_input(&d, name, &v)
                .map_err(|e| CliError::Input(InputError::file(path, e.to_string())))
        }
        _ => Ok(d),
    }
}

fn input_of(c: &Common) -> InputColumn<'_> {
    Some((c.input.as_str(), c.model == ModelKind::HeatInput))
}

/// The validation blocks the options ask for.
fn block_spec(c: &Common) -> BlockSpec {
    BlockSpec {
        block_min: c.block_min,
        input: Some(c.input.clone()),
    }
}

/// The auto fitter; exp-ambient is a candidate when the data has its columns and --sensors
/// names its two sensors.
fn auto_fitter(c: &Common, data: &ThermalData) -> Auto {
    let exp = data.ambient_c.is_some() && data.position_mm.is_some() && c.sensors.len() == 2;
    Auto {
        sensors: c.sensors.clone(),
        input: c.input.clone(),
        max_sensors: c
            .max_sensors
            .unwrap_or(mtec_thermal::auto::DEFAULT_MAX_SENSORS),
        block_min: c.block_min,
        exp_ambient: exp.then(|| ExpAmbient {
            up_sensor: c.sensors[0].clone(),
            nut_sensor: c.sensors[1].clone(),
            ..Default::default()
        }),
    }
}

/// Forward validation of the options' fitter on the training rows (`None`: fewer than two
/// blocks), and the warnings it gives.
fn validate_forward(
    c: &Common,
    data: &ThermalData,
    train: &[usize],
) -> (Option<ForwardCv>, Vec<String>) {
    let folds = forward_folds(&duty_cycle_blocks(data, train, &block_spec(c)));
    if folds.is_empty() {
        return (None, vec!["no forward validation: the training rows hold fewer than two blocks, so the model carries no uncertainty (use a longer record, experiments, or --block-min)".into()]);
    }
    match forward_cv(&CvFitter(c), data, &folds) {
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

fn print_candidates(say: &mut dyn Write, candidates: &[CandidateScore]) {
    let _ = writeln!(
        say,
        "auto: forward score of every candidate (mean fold RMSE ± standard error; pooled; worst fold vs no compensation)"
    );
    for c in candidates {
        match &c.forward {
            Some(f) => {
                let folds: Vec<String> = f
                    .folds
                    .iter()
                    .map(|x| format!("{:.2}/{:.2}", x.metrics.rmse_um, x.uncompensated_rmse_um))
                    .collect();
                let _ = writeln!(
                    say,
                    "  {:<13} {:>7.3} ± {:<6.3} pooled {:>7.3} um  folds (model/none) {}{}{}",
                    c.family,
                    f.mean_rmse_um(),
                    f.rmse_std_error_um,
                    f.pooled_rmse_um,
                    folds.join(" "),
                    if c.worse_than_uncompensated.is_empty() {
                        ""
                    } else {
                        "  worse than none: never chosen"
                    },
                    if c.chosen { "  <- chosen" } else { "" }
                );
            }
            None => {
                let _ = writeln!(
                    say,
                    "  {:<13} not fitted: {}",
                    c.family,
                    c.error.as_deref().unwrap_or("")
                );
            }
        }
    }
}

/// A model error about the data file: missing columns at the header, the rest about the file.
fn located(data: &ThermalData, path: &Path, e: ThermalError) -> CliError {
    match e {
        ThermalError::MissingColumn(c) => CliError::Input(data.header_error(format!(
            "missing column `{c}`; the header has: {}",
            header_list(data)
        ))),
        other => CliError::Input(InputError::file(path, other.to_string())),
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

fn select(a: SelectArgs) -> Result<(), CliError> {
    // where the files go is settled before any work: a folder, and none of them the input
    if let Some(dir) = &a.out {
        if dir.exists() && !dir.is_dir() {
            return Err(CliError::usage(format!(
                "--out {} is a file: it must be a folder (ridge_trace.csv, ridge_trace.svg and selection.json go into it)",
                dir.display()
            )));
        }
        let guard = OutputGuard::new(&[&a.data]);
        for f in ["ridge_trace.csv", "ridge_trace.svg", "selection.json"] {
            guard.check(&dir.join(f))?;
        }
    }
    let data = load(&a.data, Some(&a.target), true)?;
    let err = |e| located(&data, &a.data, e);
    let features = temp_features(&data, &a.sensors).map_err(err)?;
    let names: Vec<String> = features.iter().map(|f| f.name()).collect();
    let x = design(&data, &features).map_err(err)?;
    let y = data.target_um().map_err(err)?;
    let sel = select_sensors(&x, y, &names, SelectOptions::default()).map_err(err)?;
    let mut doc = serde_json::to_value(&sel).map_err(|e| CliError::Internal(e.into()))?;
    doc["format"] = "mtec.thermal-selection/1".into();
    doc["target"] = data.target_name().unwrap_or_default().into();
    let out_dir = a.out.clone();
    if let Some(dir) = &out_dir {
        std::fs::create_dir_all(dir)?;
        let guard = OutputGuard::new(&[&a.data]);
        guard.write(&dir.join("ridge_trace.csv"), sel.trace.to_csv().as_bytes())?;
        let svg = mtec_thermal::plot::ridge_trace_svg(&sel.trace, sel.k)
            .map_err(|e| CliError::Internal(anyhow::anyhow!("plot: {e}")))?;
        guard.write(&dir.join("ridge_trace.svg"), svg.as_bytes())?;
        guard.write(
            &dir.join("selection.json"),
            serde_json::to_string_pretty(&doc)
                .map_err(|e| CliError::Internal(e.into()))?
                .as_bytes(),
        )?;
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&doc).map_err(|e| CliError::Internal(e.into()))?
        );
    } else {
        print_selection(&sel, data.target_name().unwrap_or_default());
        match out_dir {
            Some(dir) => println!(
                "\nwrote {}/ridge_trace.csv, ridge_trace.svg, selection.json",
                dir.display()
            ),
            None => println!("\n(nothing written: --out DIR writes ridge_trace.csv, ridge_trace.svg and selection.json)"),
        }
    }
    for w in &sel.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}

fn fmt_opt(v: Option<f64>, prec: usize) -> String {
    v.map(|x| format!("{x:.prec$}"))
        .unwrap_or_else(|| "-".into())
}

fn print_selection(sel: &Selection, target: &str) {
    println!("Variance inflation factors (VIF > 10: severe collinearity)");
    for v in &sel.vif {
        println!(
            "  {:<16} {:>12} {}",
            v.sensor,
            v.vif
                .map(|x| format!("{x:.1}"))
                .unwrap_or_else(|| "inf".into()),
            if v.severe { "severe" } else { "" }
        );
    }
    println!(
        "\nRidge-trace elimination (rules: stable-small, unstable-to-zero, unstable, sign-change)"
    );
    for (i, s) in sel.steps.iter().enumerate() {
        println!(
            "  step {}: {:<17} removed {:<24} at k = {:.4}; remaining {}",
            i + 1,
            s.rule,
            s.removed.join(","),
            s.k,
            s.remaining.join(",")
        );
    }
    println!(
        "\nSelected sensors: {}   chosen k = {:.4}",
        sel.selected.join(", "),
        sel.k
    );
    let std_eq: Vec<String> = sel
        .selected
        .iter()
        .zip(&sel.standardised_coefficients)
        .map(|(s, b)| format!("{b:+.4}·z({s})"))
        .collect();
    println!(
        "Standardised equation:    z({target}) = {}",
        std_eq.join(" ")
    );
    let eq: Vec<String> = sel
        .selected
        .iter()
        .zip(&sel.coefficients)
        .map(|(s, b)| format!("{b:+.4}·{s}"))
        .collect();
    println!(
        "De-standardised equation: {target} = {:.4} {}",
        sel.intercept_um,
        eq.join(" ")
    );
    println!("\nComparison");
    println!(
        "  {:<34} {:>3} {:>8} {:>10} {:>12} {:>10} {:>12}",
        "model", "n", "R²", "max|res|", "SSE", "MSE", "F"
    );
    for r in &sel.comparison {
        let m = &r.metrics;
        println!(
            "  {:<34} {:>3} {:>8} {:>10.3} {:>12.3} {:>10} {:>12}",
            r.model,
            r.sensors.len(),
            fmt_opt(m.r2, 4),
            m.max_abs_residual_um,
            m.sse_um2,
            fmt_opt(m.mse_um2, 4),
            fmt_opt(m.f_statistic, 1)
        );
    }
}

fn fit_model(c: &Common, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError> {
    Ok(match c.model {
        ModelKind::Auto => auto_fitter(c, data).fit_rows(data, rows)?,
        ModelKind::Mlr => ThermalModel::Linear(
            Mlr {
                sensors: c.sensors.clone(),
                lag: c.lag,
                blocks: block_spec(c),
            }
            .fit_rows(data, rows)?,
        ),
        ModelKind::Ridge => ThermalModel::Linear(
            Ridge {
                sensors: c.sensors.clone(),
                k: c.k,
                lag: c.lag,
                blocks: block_spec(c),
            }
            .fit_rows(data, rows)?,
        ),
        ModelKind::RidgeSelect => ThermalModel::Linear(
            RidgeSelect {
                sensors: c.sensors.clone(),
                options: SelectOptions::default(),
                lag: c.lag,
            }
            .fit_rows(data, rows)?,
        ),
        ModelKind::LagSelect => ThermalModel::Linear(
            LagSelect {
                sensors: c.sensors.clone(),
                max_sensors: c.max_sensors.unwrap_or(3),
                block_min: c.block_min,
                input: Some(c.input.clone()),
            }
            .fit_rows(data, rows)?,
        ),
        ModelKind::HeatInput => ThermalModel::HeatInput(
            HeatInput {
                input: c.input.clone(),
                block_min: c.block_min,
                ..Default::default()
            }
            .fit_rows(data, rows)?,
        ),
        ModelKind::ExpAmbient if !c.up_sensors.is_empty() => ThermalModel::ExpAmbient(Box::new(
            ExpAmbient {
                up_sensors: c.up_sensors.clone(),
                nut_sensors: c.nut_sensors.clone(),
                ..Default::default()
            }
            .fit_rows(data, rows)?,
        )),
        ModelKind::CnnLstm | ModelKind::Bpnn => {
            return Err(ThermalError::Invalid(
                "the neural models are fitted by `thermal fit --model cnn-lstm|bpnn`".into(),
            ))
        }
        ModelKind::ExpAmbient => {
            let [up, nut] = c.sensors.as_slice() else {
                return Err(ThermalError::Invalid(
                    "exp-ambient needs --sensors UP,NUT: the upper-bearing sensor, then the ball-screw-nut sensor (or --up-sensors A,B --nut-sensors C,D for sensor groups)".into(),
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

fn check_common(c: &Common) -> Result<(), CliError> {
    if let Some(b) = c.block_min {
        if !(b > 0.0 && b.is_finite()) {
            return Err(CliError::usage(
                "--block-min must be a number of minutes > 0",
            ));
        }
    }
    if c.max_sensors == Some(0) {
        return Err(CliError::usage("--max-sensors must be at least 1"));
    }
    if c.max_sensors.is_some() && !matches!(c.model, ModelKind::Auto | ModelKind::LagSelect) {
        return Err(CliError::usage(
            "--max-sensors goes with --model auto or lag-select",
        ));
    }
    if c.model == ModelKind::Auto && (c.lag || !c.up_sensors.is_empty()) {
        return Err(CliError::usage(
            "--model auto chooses lags itself (no --lag) and takes exp-ambient as a candidate only from --sensors UP,NUT",
        ));
    }
    if c.model != ModelKind::ExpAmbient && !c.up_sensors.is_empty() {
        return Err(CliError::usage(
            "--up-sensors and --nut-sensors go with --model exp-ambient",
        ));
    }
    if c.model == ModelKind::ExpAmbient && c.lag {
        return Err(CliError::usage(
            "--lag applies to the linear models, not exp-ambient",
        ));
    }
    if let Some(k) = c.k {
        if !(k >= 0.0 && k.is_finite()) || c.model != ModelKind::Ridge {
            return Err(CliError::usage(
                "--k must be a number ≥ 0 and goes with --model ridge",
            ));
        }
    }
    Ok(())
}

fn metrics_on(
    model: &ThermalModel,
    data: &ThermalData,
    rows: &[usize],
    pred: &[f64],
) -> Result<Metrics, ThermalError> {
    let y = data.target_um()?;
    let yt: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
    let pt: Vec<f64> = rows.iter().map(|&i| pred[i]).collect();
    Ok(Metrics::new(&yt, &pt, model.predictors()))
}

fn fit(a: FitArgs) -> Result<(), CliError> {
    check_common(&a.common)?;
    // where the model goes is settled before any work (an input, a directory: exit 2)
    let dest = OutputGuard::new(&[&a.common.data]).check(&a.output)?;
    // the report goes to stderr when the model itself streams to stdout (`-o -`)
    let mut say = super::messages(&dest);
    let data = load_with_input(
        &a.common.data,
        Some(&a.common.target),
        true,
        input_of(&a.common),
    )?;
    let err = |e| located(&data, &a.common.data, e);
    let all: Vec<usize> = (0..data.len()).collect();
    let (train, test, split) = if let Some(t) = a.train_until {
        let (tr, te) = split_at_time(&data, t);
        let s = Split {
            train_until_min: Some(t),
            ..Default::default()
        };
        (tr, te, s)
    } else if !a.train.is_empty() {
        let tr = rows_of_experiments(&data, &a.train).map_err(err)?;
        let te = if a.test.is_empty() {
            all.iter().copied().filter(|i| !tr.contains(i)).collect()
        } else {
            rows_of_experiments(&data, &a.test).map_err(err)?
        };
        let test_exps = if a.test.is_empty() {
            data.experiments()
                .into_iter()
                .filter(|e| !a.train.contains(e))
                .collect()
        } else {
            a.test.clone()
        };
        let s = Split {
            train_experiments: a.train.clone(),
            test_experiments: test_exps,
            ..Default::default()
        };
        (tr, te, s)
    } else if !a.test.is_empty() {
        return Err(CliError::usage("--test needs --train"));
    } else {
        (all, Vec::new(), Split::default())
    };
    if train.is_empty() {
        return Err(CliError::usage("the training selection holds no rows"));
    }
    let (model, candidates, validation, mut warnings) = if a.common.model == ModelKind::Auto {
        let f = auto_fitter(&a.common, &data)
            .fit_auto(&data, &train)
            .map_err(err)?;
        (f.model, f.candidates, Some(f.validation), Vec::new())
    } else {
        let model = fit_model(&a.common, &data, &train).map_err(err)?;
        let (v, w) = validate_forward(&a.common, &data, &train);
        (model, Vec::new(), v, w)
    };
    warnings.splice(0..0, model.warnings());
    warnings.extend(validation.as_ref().and_then(worse_warning));
    let pred = model.predict(&data).map_err(err)?;
    let train_metrics = metrics_on(&model, &data, &train, &pred).map_err(err)?;
    let test_metrics = if test.is_empty() {
        None
    } else {
        Some(metrics_on(&model, &data, &test, &pred).map_err(err)?)
    };
    let mut split = split;
    if split.train_experiments.is_empty() && split.train_until_min.is_none() {
        split.train_experiments = data.experiments();
    }
    split.train_rows = train.len();
    split.test_rows = test.len();
    let file = ModelFile {
        format: MODEL_FORMAT.into(),
        target: data.target_name().unwrap_or_default().to_string(),
        envelope: envelope(&model, &data, &train),
        model,
        split,
        train_metrics,
        test_metrics,
        validation,
        candidates,
        warnings,
    };
    let text = serde_json::to_string_pretty(&file).map_err(|e| CliError::Internal(e.into()))?;
    dest.write(text.as_bytes())?;
    let show = |say: &mut dyn std::io::Write, name: &str, m: &Metrics| {
        let _ = writeln!(
            say,
            "{name:<6} n={:<6} RMSE {:.3} um  MAE {:.3} um  max|res| {:.3} um  R² {}  compensation {}",
            m.n,
            m.rmse_um,
            m.mae_um,
            m.max_abs_residual_um,
            fmt_opt(m.r2, 4),
            m.compensation_rate.map(|c| format!("{:.1} %", 100.0 * c)).unwrap_or_else(|| "-".into())
        );
    };
    if let ThermalModel::ExpAmbient(m) = &file.model {
        let _ = writeln!(say,
            "exp-ambient: δ = k·x + b, b = b_a(1 − exp(−ΔT_up/b_b)), k = k_a(1 − exp(−ΔT_nut/k_b)); b_a, ln b_b, k_a, ln k_b polynomials of degree {} in u = (T_a − 20 °C)/10 °C (coefficient ± standard uncertainty, ascending powers)",
            m.degree
        );
        for (name, group) in [("ΔT_up", &m.up_group), ("ΔT_nut", &m.nut_group)] {
            if !group.is_empty() {
                let terms: Vec<String> = group
                    .iter()
                    .map(|g| format!("{:.4}·Δ{}", g.weight, g.sensor))
                    .collect();
                let _ = writeln!(
                    say,
                    "  {name} = {} (first principal component)",
                    terms.join(" + ")
                );
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
            let _ = writeln!(say, "  {name:<12} {}", terms.join(", "));
        }
        if !m.held_at_cap.is_empty() {
            let _ = writeln!(say,
                "  held at the linear-limit cap (100 × the largest training rise, not fitted; ± 0 means held): {}",
                m.held_at_cap.join(", ")
            );
        }
        for l in &m.identifiability {
            let _ = writeln!(say,
                "  at {} °C: b_b = {:.4} °C (max ΔT_up {:.2} °C), k_b = {:.4} °C (max ΔT_nut {:.2} °C)",
                l.ambient_c, l.b_b_c, l.max_dt_up_c, l.k_b_c, l.max_dt_nut_c
            );
        }
    }
    if !file.candidates.is_empty() {
        print_candidates(&mut *say, &file.candidates);
    }
    if let ThermalModel::Linear(m) = &file.model {
        let names: Vec<String> = m.features.iter().map(|f| f.name()).collect();
        let _ = writeln!(say, "features: {}", names.join(", "));
    }
    show(&mut say, "train", &file.train_metrics);
    if let Some(v) = &file.validation {
        let _ = writeln!(
            say,
            "forward validation on the training rows: {} folds, pooled RMSE {:.3} um (the uncertainty predict reports), mean {:.3} ± {:.3} um",
            v.folds.len(),
            v.pooled_rmse_um,
            v.mean_rmse_um(),
            v.rmse_std_error_um
        );
    }
    if let Some(m) = &file.test_metrics {
        show(&mut say, "test", m);
    }
    for w in &file.warnings {
        eprintln!("warning: {w}");
    }
    let _ = writeln!(say, "wrote {}", a.output.display());
    Ok(())
}

fn predict(a: PredictArgs) -> Result<(), CliError> {
    // where the predictions go is settled before any work (an input, a directory: exit 2)
    let dest = match &a.output {
        Some(p) => {
            let mut g = OutputGuard::new(&[&a.data, &a.model]);
            if let Some(h) = &a.history {
                g.add_input(h);
            }
            Some(g.check(p)?)
        }
        None => None,
    };
    let file: ModelFile = mtec_io::read_json(&a.model)?;
    file.check_format()
        .map_err(|e| CliError::Input(InputError::file(&a.model, e.to_string())))?;
    // a non-temperature column the model reads (the heat input) must be in the data
    let input_name = mtec_thermal::guard::model_columns(&file.model)
        .into_iter()
        .find(|c| !c.ends_with("_c") && c != "position_mm");
    let input = input_name.as_deref().map(|n| (n, true));
    let data = load_with_input(&a.data, Some(&file.target), false, input)?;
    let (pred, outside) = match &a.history {
        Some(h) => {
            let hist = load_with_input(h, None, false, input)?;
            let all = hist
                .followed_by(&data)
                .map_err(|e| CliError::Input(InputError::file(h, e.to_string())))?;
            let p = file
                .model
                .predict(&all)
                .map_err(|e| located(&all, &a.data, e))?;
            let o = outside_envelope(&file.envelope, &all);
            (p[hist.len()..].to_vec(), o[hist.len()..].to_vec())
        }
        None => {
            if file.model.has_state() {
                let t0 = data.time_min.first().copied().unwrap_or(0.0);
                eprintln!(
                    "note: the model's filters start in equilibrium with the first row of {} (time_min {t0}){}; pass the log before it with --history FILE if the machine was not at rest and settled then",
                    a.data.display(),
                    if t0 > 0.0 { ", which starts mid-record" } else { "" }
                );
            }
            let p = file
                .model
                .predict(&data)
                .map_err(|e| located(&data, &a.data, e))?;
            (p, outside_envelope(&file.envelope, &data))
        }
    };
    let uncertainty = file.validation.as_ref().map(|v| v.pooled_rmse_um);
    let n_out = outside.iter().filter(|o| !o.is_empty()).count();
    if n_out > 0 {
        let mut cols: Vec<&String> = outside.iter().flatten().collect();
        cols.sort();
        cols.dedup();
        let first = outside.iter().position(|o| !o.is_empty()).unwrap_or(0);
        eprintln!(
            "warning: {n_out} of {} rows have inputs outside the training range ({}; first at line {}): the model extrapolates there and its uncertainty does not hold",
            outside.len(),
            cols.iter().map(|c| c.as_str()).collect::<Vec<_>>().join(", "),
            data.lines.get(first).copied().unwrap_or(0)
        );
    }
    if uncertainty.is_none() {
        eprintln!("note: the model file has no forward validation, so the predictions carry no uncertainty (refit with this mtec)");
    }
    let metrics = match data.target_um() {
        Ok(y) => Some(Metrics::new(y, &pred, file.model.predictors())),
        Err(_) => None,
    };
    if a.json {
        let mut doc = serde_json::json!({
            "format": "mtec.thermal-prediction/1",
            "target": file.target,
            "n": pred.len(),
            "predictions": pred,
            "uncertainty_um": uncertainty,
            "rows_outside_training_range": n_out,
        });
        if let Some(m) = &metrics {
            doc["rmse_um"] = m.rmse_um.into();
            doc["mae_um"] = m.mae_um.into();
            doc["max_abs_residual_um"] = m.max_abs_residual_um.into();
            doc["metrics"] = serde_json::to_value(m).map_err(|e| CliError::Internal(e.into()))?;
        }
        // with `-o -` the CSV has stdout and the JSON summary goes to stderr
        let mut say = match &dest {
            Some(d) => super::messages(d),
            None => Box::new(std::io::stdout()),
        };
        let _ = writeln!(
            say,
            "{}",
            serde_json::to_string(&doc).map_err(|e| CliError::Internal(e.into()))?
        );
    }
    if a.output.is_some() || !a.json {
        let y = data.target_um().ok();
        let mut csv = String::from("experiment,time_min,predicted_um");
        if y.is_some() {
            csv.push_str(",measured_um,residual_um");
        }
        if uncertainty.is_some() {
            csv.push_str(",uncertainty_um");
        }
        csv.push_str(",outside_training_range\n");
        for i in 0..pred.len() {
            csv.push_str(&format!(
                "{},{},{:.4}",
                data.experiment[i], data.time_min[i], pred[i]
            ));
            if let Some(y) = y {
                csv.push_str(&format!(",{:.4},{:.4}", y[i], y[i] - pred[i]));
            }
            if let Some(u) = uncertainty {
                csv.push_str(&format!(",{u:.4}"));
            }
            csv.push_str(&format!(",{}\n", outside[i].join(";")));
        }
        match &dest {
            Some(d) => d.write(csv.as_bytes())?,
            None => print!("{csv}"),
        }
    }
    Ok(())
}

struct CvFitter<'a>(&'a Common);

impl Fit for CvFitter<'_> {
    type Model = ThermalModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError> {
        fit_model(self.0, data, rows)
    }
}

fn cv(a: CvArgs) -> Result<(), CliError> {
    check_common(&a.common)?;
    let data = load_with_input(
        &a.common.data,
        Some(&a.common.target),
        true,
        input_of(&a.common),
    )?;
    let err = |e| located(&data, &a.common.data, e);
    let all: Vec<usize> = (0..data.len()).collect();
    if !a.loo {
        let folds = forward_folds(&duty_cycle_blocks(&data, &all, &block_spec(&a.common)));
        if folds.is_empty() {
            return Err(CliError::usage("forward validation needs at least two blocks (experiments, steps of the --input column, or --block-min shorter than the record)"));
        }
        let res = forward_cv(&CvFitter(&a.common), &data, &folds).map_err(err)?;
        if a.json {
            let mut doc = serde_json::to_value(&res).map_err(|e| CliError::Internal(e.into()))?;
            doc["format"] = "mtec.thermal-cv/2".into();
            doc["protocol"] = "forward".into();
            doc["folds_worse_than_uncompensated"] =
                serde_json::to_value(res.folds_worse_than_uncompensated())
                    .map_err(|e| CliError::Internal(e.into()))?;
            println!(
                "{}",
                serde_json::to_string_pretty(&doc).map_err(|e| CliError::Internal(e.into()))?
            );
        } else {
            println!("forward validation: fit on every block before, score the next block");
            for (i, f) in res.folds.iter().enumerate() {
                println!(
                    "fold {:<3} train {:.0}–{:.0} min, score {:.0}–{:.0} min  n={:<6} RMSE {:.3} um  max|res| {:.3} um  uncompensated {:.3} um{}",
                    i + 1,
                    f.train_from_min,
                    f.train_to_min,
                    f.test_from_min,
                    f.test_to_min,
                    f.metrics.n,
                    f.metrics.rmse_um,
                    f.metrics.max_abs_residual_um,
                    f.uncompensated_rmse_um,
                    if f.worse_than_uncompensated() { "  WORSE THAN NO COMPENSATION" } else { "" }
                );
            }
            println!(
                "pooled RMSE {:.3} um, max|res| {:.3} um; mean fold RMSE {:.3} ± {:.3} um",
                res.pooled_rmse_um,
                res.pooled_max_abs_um,
                res.mean_rmse_um(),
                res.rmse_std_error_um
            );
        }
        if let Some(w) = worse_warning(&res) {
            eprintln!("warning: {w}");
        }
        return Ok(());
    }
    let blocks: Vec<Vec<usize>> = match a.common.block_min {
        Some(b) if b > 0.0 => time_blocks(&data, b),
        Some(_) => return Err(CliError::usage("--block-min must be > 0")),
        None => data
            .experiments()
            .iter()
            .map(|e| rows_of_experiments(&data, std::slice::from_ref(e)))
            .collect::<Result<_, _>>()
            .map_err(err)?,
    };
    if blocks.len() < 2 {
        return Err(CliError::usage("leave-one-block-out needs at least two blocks (experiments, or --block-min shorter than the record)"));
    }
    let res = block_cv(&CvFitter(&a.common), &data, &blocks).map_err(err)?;
    eprintln!("note: leave-one-block-out trains on the future of every block it scores: optimistic for a model that must predict forward (the default forward validation is the honest score)");
    if a.json {
        let mut doc = serde_json::to_value(&res).map_err(|e| CliError::Internal(e.into()))?;
        doc["format"] = "mtec.thermal-cv/1".into();
        doc["protocol"] = "leave-one-block-out (optimistic)".into();
        println!(
            "{}",
            serde_json::to_string_pretty(&doc).map_err(|e| CliError::Internal(e.into()))?
        );
    } else {
        for (i, m) in res.per_block.iter().enumerate() {
            println!(
                "block {:<3} n={:<6} RMSE {:.3} um  max|res| {:.3} um",
                i + 1,
                m.n,
                m.rmse_um,
                m.max_abs_residual_um
            );
        }
        println!(
            "pooled RMSE {:.3} um, max|res| {:.3} um (leave-one-block-out: optimistic)",
            res.pooled_rmse_um, res.pooled_max_abs_um
        );
    }
    Ok(())
}
