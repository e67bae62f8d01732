//! `mtec thermal select|fit|predict|cv`: thermal error models from temperature logs. The jobs
//! are `mtec_workflow::ops::thermal`'s (the networks': its `neural`, `neural_log`); the kinds and
//! their `--model` values come from `mtec_thermal::registry`. This module parses and prints.

#[cfg(feature = "neural")]
use super::terminal::{ctrl_c, Terminal};
use crate::choice::possible_value;
use crate::error::CliError;
use crate::help::{examples, text};
use clap::builder::PossibleValuesParser;
use mtec_thermal::model_file::SplitBy;
use mtec_workflow::ops::thermal as op;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Thermal error models: sensor selection, fitting and prediction.
#[derive(clap::Args)]
#[command(after_help = text!("thermal.format_help"))]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

#[derive(clap::Subcommand)]
enum Sub {
    #[command(about = text!("thermal.select_about"), long_about = text!("thermal.select_long"))]
    Select(SelectArgs),
    /// Fits a model and writes it as JSON (`mtec.thermal-model/1`) with train/test metrics.
    #[command(long_about = text!("thermal.fit_long"))]
    Fit(Box<FitArgs>),
    #[command(about = text!("thermal.predict_about"))]
    Predict(PredictArgs),
    #[command(about = text!("thermal.cv_about"))]
    Cv(Box<CvArgs>),
}

#[derive(clap::Args)]
#[command(after_long_help = examples!("thermal.select_examples"))]
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

/// The `--model` values: `op::model_choices()`.
fn model_values() -> PossibleValuesParser {
    PossibleValuesParser::new(op::model_choices().map(|(v, help)| possible_value(v, help)))
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
    #[arg(long, value_parser = model_values())]
    model: String,
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
    /// Validation block length, min (default: experiments, --input steps, or eight blocks).
    #[arg(long)]
    block_min: Option<f64>,
    /// auto and lag-select: most temperature sensors (auto 6, lag-select 3; --input not counted).
    #[arg(long)]
    max_sensors: Option<usize>,
    /// The heat-source column (spindle speed, rpm): heat-input and auto's heat features, and
    /// the duty-cycle steps that cut the validation blocks (used when the file has it).
    #[arg(long, default_value = "spindle_rpm")]
    input: String,
    /// exp-ambient: ΔT_up from several sensors (first principal component of their standardised
    /// rises, a weighted mean in °C). Goes with --nut-sensors, instead of --sensors.
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
#[command(after_long_help = examples!("thermal.fit_examples"))]
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
#[command(after_long_help = examples!("thermal.predict_examples"))]
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
    /// Rotary model: the ballbar setup; with --dbb, predicts and scores every mode's readings.
    #[arg(long, requires = "dbb")]
    setup: Option<PathBuf>,
    /// The measured ballbar readings (`experiment,time_min,mode,angle_deg,dl_um`).
    #[arg(long, requires = "setup")]
    dbb: Option<PathBuf>,
    /// Write the predicted and measured readings and their changes here (CSV).
    #[arg(long, requires = "dbb")]
    readings: Option<PathBuf>,
}

#[derive(clap::Args)]
#[command(after_long_help = examples!("thermal.cv_examples"))]
struct CvArgs {
    #[command(flatten)]
    common: Common,
    /// Print the per-block metrics as JSON.
    #[arg(long)]
    json: bool,
    /// Leave-one-block-out instead of forward folds (optimistic: trains on the block's future).
    #[arg(long)]
    loo: bool,
    #[command(flatten)]
    nn: super::neural::NnArgs,
}

/// Where a report goes: stdout, or stderr when the output itself streams to stdout (`-o -`).
fn say_for(output: &Path) -> Box<dyn Write> {
    if output == Path::new("-") {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    }
}

impl Common {
    fn fit_options(&self) -> mtec_thermal::FitOptions {
        mtec_thermal::FitOptions {
            sensors: self.sensors.clone(),
            k: self.k,
            lag: self.lag,
            block_min: self.block_min,
            max_sensors: self.max_sensors,
            input: self.input.clone(),
            up_sensors: self.up_sensors.clone(),
            nut_sensors: self.nut_sensors.clone(),
        }
    }
}

impl FitArgs {
    fn options(&self) -> op::FitOptions {
        op::FitOptions {
            data: self.common.data.clone(),
            target: self.common.target.clone(),
            model: self.common.model.clone(),
            fit: self.common.fit_options(),
            split: SplitBy::from_options(self.train_until, self.train.clone(), self.test.clone()),
            output: self.output.clone(),
        }
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    match &args.cmd {
        Sub::Fit(a) => a.nn.refuse_unused(&a.common.model)?,
        Sub::Cv(a) => a.nn.refuse_unused(&a.common.model)?,
        _ => {}
    }
    match args.cmd {
        Sub::Select(a) => select(a),
        Sub::Fit(a) if op::is_neural(&a.common.model) || !a.nn.with_networks.is_empty() => {
            fit_neural(*a)
        }
        Sub::Fit(a) => fit(*a),
        Sub::Predict(a) => predict(a),
        Sub::Cv(a) => cv(*a),
    }
}

fn select(a: SelectArgs) -> Result<(), CliError> {
    let opts = op::SelectOptions {
        data: a.data,
        target: a.target,
        sensors: a.sensors,
        out: a.out,
    };
    let mut obs = mtec_workflow::Collect::default();
    let outcome = op::select(&opts, &mut obs)?;
    super::report(&outcome, a.json, mtec_workflow::pretty_json)?;
    print_warnings(&obs);
    Ok(())
}

fn fit(a: FitArgs) -> Result<(), CliError> {
    let opts = a.options();
    let mut obs = mtec_workflow::Collect::default();
    let outcome = op::fit(&opts, &mut obs)?;
    let mut say = say_for(&opts.output);
    // the report, its warnings, then where the model went
    let report = outcome.to_string();
    let (body, wrote) = report
        .trim_end()
        .rsplit_once('\n')
        .unwrap_or(("", report.trim_end()));
    if !body.is_empty() {
        let _ = writeln!(say, "{body}");
    }
    let _ = say.flush();
    print_warnings(&obs);
    let _ = writeln!(say, "{wrote}");
    Ok(())
}

/// `--model cnn-lstm|bpnn` in a build without the neural models.
#[cfg(not(feature = "neural"))]
fn fit_neural(a: FitArgs) -> Result<(), CliError> {
    let with = ["", " --with-networks"][usize::from(!a.nn.with_networks.is_empty())];
    let what = format!("`thermal fit --model {}{with}`", a.common.model);
    Err(mtec_workflow::neural_unavailable(&what))
}

/// `--model cnn-lstm|bpnn`, or `auto --with-networks` (the networks' options as bpnn's).
#[cfg(feature = "neural")]
fn fit_neural(a: FitArgs) -> Result<(), CliError> {
    let (opts, nn) = (a.options(), a.nn.fit_options(&a.common.model));
    let mut term = Terminal::new(a.nn.quiet);
    let with = &a.nn.with_networks;
    let outcome = ctrl_c::during(|| op::neural::fit_thermal(&opts, &nn, with, &mut term));
    term.done();
    let _ = write!(say_for(&opts.output), "{}", outcome?);
    Ok(())
}

fn predict(a: PredictArgs) -> Result<(), CliError> {
    #[cfg(feature = "neural")]
    super::neural::single_candle_thread();
    let opts = op::PredictOptions {
        model: a.model,
        data: a.data,
        history: a.history,
        output: a.output,
        readings: op::ReadingsOptions::given(a.setup, a.dbb, a.readings),
    };
    let mut obs = mtec_workflow::Collect::default();
    let outcome = op::predict(&opts, &mut obs)?;
    print_warnings(&obs);
    for n in outcome.notes() {
        eprintln!("note: {n}");
    }
    // the JSON or the metrics table: beside a CSV on stdout (`-o -`, no -o) the table is on stderr
    let mut say: Box<dyn Write> = match &opts.output {
        Some(p) => say_for(p),
        None if a.json => Box::new(std::io::stdout()),
        None => Box::new(std::io::stderr()),
    };
    let text = match a.json {
        true => serde_json::to_value(&outcome)?.to_string() + "\n",
        false => outcome.to_string(),
    };
    let _ = write!(say, "{text}");
    if opts.output.is_none() && !a.json {
        print!("{}", outcome.csv());
    }
    Ok(())
}

fn cv(a: CvArgs) -> Result<(), CliError> {
    let opts = op::CvOptions {
        data: a.common.data.clone(),
        target: a.common.target.clone(),
        model: a.common.model.clone(),
        fit: a.common.fit_options(),
        loo: a.loo,
    };
    let mut obs = mtec_workflow::Collect::default();
    #[cfg(feature = "neural")]
    let outcome = op::neural_log::cv(&opts, &a.nn.fit_options(&opts.model), &mut obs)?;
    #[cfg(not(feature = "neural"))]
    let outcome = op::cv(&opts, &mut obs)?;
    if let op::CvOutcome::LeaveOneBlockOut(o) = &outcome {
        eprintln!("note: {}", o.note);
    }
    super::report(&outcome, a.json, mtec_workflow::pretty_json)?;
    print_warnings(&obs);
    Ok(())
}

fn print_warnings(obs: &mtec_workflow::Collect) {
    for w in &obs.warnings {
        eprintln!("warning: {w}");
    }
}
