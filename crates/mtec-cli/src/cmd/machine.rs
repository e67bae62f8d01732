//! `mtec machine build|replay`: the machine error model with a state (`mtec.machine-error/1`).

use crate::error::CliError;
use crate::help::{examples, text};
use mtec_workflow::ops::machine::{self, BuildOptions, Part, ReplayOptions};
use std::path::PathBuf;

/// The machine error model with a state.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// Build a machine error model file from a geometric model and fitted thermal models.
    #[command(long_about = text!("machine.build_help"))]
    Build(BuildArgs),
    /// Compensate a recorded day (state log + probe readings) through the real-time path.
    #[command(long_about = text!("machine.replay_help"))]
    Replay(ReplayArgs),
}

#[derive(clap::Args)]
#[command(after_long_help = examples!("machine.build_examples"))]
struct BuildArgs {
    /// Static geometric model (map, kinematic model, BPNN).
    #[arg(long, value_name = "MAP.json")]
    geometric: Option<PathBuf>,
    /// A thermal part: AXIS=MODEL.json[,sign=-1] (repeat for several).
    #[arg(long, value_name = "AXIS=MODEL.json[,sign=-1]")]
    thermal: Vec<String>,
    /// The data the thermal models were fitted on (CSV).
    #[arg(long, value_name = "TRAIN.csv")]
    data: Option<PathBuf>,
    /// Columns of --data that guard every thermal part (comma-separated).
    #[arg(long, value_delimiter = ',')]
    guard: Vec<String>,
    /// Fade width of temperature inputs outside their range (°C).
    #[arg(long, default_value_t = mtec_comp::machine::FADE_TEMPERATURE_C)]
    fade_c: f64,
    /// Fade width of other inputs, as a fraction of their training range.
    #[arg(long, default_value_t = mtec_comp::machine::FADE_OTHER_FRACTION)]
    fade_other: f64,
    /// The machine file to write.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
}

#[derive(clap::Args)]
#[command(after_long_help = examples!("machine.replay_examples"))]
struct ReplayArgs {
    /// Model file (any; a machine error model to follow a state).
    #[arg(long)]
    model: PathBuf,
    /// The controller's state log (CSV: time_min and the model's state inputs).
    #[arg(long, value_name = "STATE.csv")]
    state: PathBuf,
    /// Probe readings (CSV: time_min,[probe,]x_mm,y_mm,z_mm,ex_um,ey_um,ez_um).
    #[arg(long, value_name = "PROBES.csv")]
    probes: PathBuf,
    /// Write every compensated reading here (CSV).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    match args.cmd {
        Sub::Build(a) => build(a),
        Sub::Replay(a) => replay_day(a),
    }
}

fn build(a: BuildArgs) -> Result<(), CliError> {
    let opts = BuildOptions {
        thermal: Part::parse_all(&a.thermal)?,
        geometric: a.geometric,
        data: a.data,
        guard: a.guard,
        fade_c: a.fade_c,
        fade_other: a.fade_other,
        output: a.output,
    };
    let done = machine::build(&opts, &mut crate::observer::Stderr::default())?;
    // the summary goes to stdout unless the model itself does (-o -)
    if opts.output.as_os_str() == "-" {
        eprint!("{done}");
        Ok(())
    } else {
        super::emit(&done.to_string())
    }
}

fn replay_day(a: ReplayArgs) -> Result<(), CliError> {
    let opts = ReplayOptions {
        model: a.model,
        state: a.state,
        probes: a.probes,
        output: a.output,
    };
    let done = machine::replay(&opts, &mut crate::observer::Stderr::default())?;
    // through a JSON value, as before: the keys in the order the command always printed
    super::report(&done, a.json, mtec_workflow::pretty_json)
}
