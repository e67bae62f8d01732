//! `mtec machine build|replay`: the machine error model with a state (`mtec.machine-error/1`).

use crate::error::CliError;
use mtec_workflow::ops::machine::{self, BuildOptions, Part, ReplayOptions};
use std::path::PathBuf;

const BUILD_HELP: &str = "\
Writes a machine error model (mtec.machine-error/1): a static geometric model plus thermal
models, each acting along one axis, that follow the machine's state (temperatures, spindle speed)
on line. Each thermal model gets its training envelope, the range [min, max] of each of its
inputs over the rows of --data it was fitted on (its file's split: --train-until, --train
experiments, or all rows); outside it the thermal part fades to no correction over --fade-c
(temperatures) or --fade-other of the range (other inputs). --data must be the file the models
were fitted on: a different number of training rows is refused. Without --data the envelope is
the training range `thermal fit` recorded in the model file (a file without one, written by an
older mtec, is refused); --guard needs --data.

--thermal AXIS=MODEL[,sign=-1]: the model's drift acts along AXIS (x, y or z); sign=-1 when its
target is the workpiece's displacement relative to the tool (mtec's convention, sign=1, is the
tool's relative to the workpiece: actual = commanded + error). --guard COL,...: further columns of
--data whose training range every thermal part must stay in although the models do not read them
(e.g. the shop's air for a model of the spindle speed alone).

Paths inside the written file are relative to it. The file is read back before it is written.";

const REPLAY_HELP: &str = "\
Compensates a recorded day through the real-time code path (the calls of mtec-rt) and says how
much of the measured error it removes. --state is the controller's log (time_min and the model's
state inputs); --probes holds the error at the tool tip measured without compensation
(time_min,[probe,]x_mm,y_mm,z_mm,ex_um,ey_um,ez_um, actual - commanded). For each probe reading
the model has received every state reading up to its time (update_state), then the correction
for the probe point is computed (correction_um); the compensated error is the measured one plus
the correction.

Prints RMS and largest error before and after (X, Y, Z and the vector), the compensation rate
1 - RMS_after/RMS_before, the reduction of the worst moment, how many readings got worse and how
many were taken with the thermal part faded (outside the training envelope). -o writes every
reading (before, correction, after, thermal weight); --json prints the summary as JSON
(mtec.machine-replay/1).";

const BUILD_EXAMPLES: &str = crate::help::examples!(
    "  # four production days of a machining centre: temperatures, spindle, drift
  $ mtec simulate production-day --out p
  # thermal models of the drift along Z and X
  $ mtec thermal fit --data p/train.csv --target dz_um --model mlr -o p/dz.json
  $ mtec thermal fit --data p/train.csv --target dx_um --model mlr -o p/dx.json
  # one model of the machine; each thermal part fades out outside its training
  # envelope, and outside the training days' air temperatures (--guard)
  $ mtec machine build --thermal z=p/dz.json --thermal x=p/dx.json \\
      --data p/train.csv --guard air_c -o p/machine.json"
);

const REPLAY_EXAMPLES: &str = crate::help::examples!(
    "  # training days, and an unseen day: the controller's log and probed errors
  $ mtec simulate production-day --out p
  $ mtec thermal fit --data p/train.csv --target dz_um --model mlr -o p/dz.json
  $ mtec machine build --thermal z=p/dz.json -o p/machine.json
  # the unseen day through the real-time path: RMS before, after, per reading
  $ mtec machine replay --model p/machine.json --state p/day-state.csv \\
      --probes p/day-probes.csv -o p/replay.csv"
);

/// The machine error model with a state.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// Build a machine error model file from a geometric model and fitted thermal models.
    #[command(long_about = BUILD_HELP)]
    Build(BuildArgs),
    /// Compensate a recorded day (state log + probe readings) through the real-time path.
    #[command(long_about = REPLAY_HELP)]
    Replay(ReplayArgs),
}

#[derive(clap::Args)]
#[command(after_long_help = BUILD_EXAMPLES)]
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
#[command(after_long_help = REPLAY_EXAMPLES)]
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
        thermal: a
            .thermal
            .iter()
            .map(|s| Part::parse(s))
            .collect::<Result<_, _>>()?,
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
    if a.json {
        // through a JSON value, as before: the keys in the order the command always printed
        let doc = serde_json::to_value(&done).map_err(|e| CliError::Internal(e.into()))?;
        println!(
            "{}",
            serde_json::to_string_pretty(&doc).map_err(|e| CliError::Internal(e.into()))?
        );
    } else {
        print!("{done}");
    }
    Ok(())
}
