//! `mtec identify ballbar`: rotary-axis error motions from ballbar readings in five modes.

use crate::error::CliError;
use mtec_identify::ballbar::{
    identify, time_key, BallbarError, Identification, Measurements, Setup, TemperatureLog,
};
use mtec_io::{InputError, OutputGuard, Table};
use mtec_report::rotary::{rotary_figures, MotionSample};
use std::path::{Path, PathBuf};

pub const LONG_ABOUT: &str = "\
Identifies the error motions EXC, EYC, EZC (um) and EAC, EBC (urad) of a rotary C axis from
double-ball-bar readings taken in five installation modes, at every measured angle, for every
experiment and time (static errors at t = 0, thermal errors later). ECC (rotation about the axis)
is not observable with bars in planes through the axis.

Method: each mode signal has its mean and first harmonic removed (this removes the set-up
eccentricity, the location errors of the axis and drifts of the tool side, and also any true
constant or once-per-revolution error motion); then, per angle, the 5x5 system of the first-order
bar-length model  L0*dL = (r_w - r_t).dr  is solved by SVD. A mode set that cannot separate the
five motions at some angle is refused with the combination it cannot see.

Setup TOML: five [[mode]] tables
  [[mode]]
  id = 1
  workpiece_ball_mm = [0, 0, 100]   # ball on the table, coordinates at C = 0
  tool_ball_mm = [500, 0, 100]      # ball in the spindle, fixed while C turns

Data CSV: experiment,time_min,mode,angle_deg,dl_um   (one full, evenly spaced revolution per
experiment, time and mode; dl_um = reading minus nominal length). Temperatures CSV (optional):
experiment,time_min,<sensor>_c,... joined to the output by experiment and time.

Outputs (in --out DIR, default <data>-ballbar/ beside the data):
  motions.csv        experiment,time_min,angle_deg,EXC_um,EYC_um,EZC_um,EAC_urad,EBC_urad[,<sensor>_c...]
  conditioning.json  rank, singular values and condition number per angle, worst angle, and
                     the motion combinations (harmonics >= 2) that the set-up-error removal
                     makes invisible over a revolution (reported as zero in motions.csv)
  polar_<EXC..EBC>.svg, time_<EXC..EBC>.svg   polar plots against C and change with time
With --json the same content is printed as one JSON object (files only if --out is given).";

const EXAMPLES: &str = crate::help::examples!(
    "  # ballbar on a C axis in 5 installations, 4 speeds x 4 h, with temperatures
  $ mtec simulate dbb-rotary --out d --seed 1
  # EXC, EYC, EZC, EAC, EBC per angle and time; conditioning, plots in d/id
  $ mtec identify ballbar --setup d/setup.toml --data d/dbb.csv \\
      --temps d/temps.csv --out d/id"
);

const MOTION_COLUMNS: [&str; 5] = ["EXC_um", "EYC_um", "EZC_um", "EAC_urad", "EBC_urad"];

/// Arguments of `mtec identify ballbar`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Rotary-axis error motions from ballbar readings in five modes",
    long_about = LONG_ABOUT,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// Setup TOML with the five [[mode]] tables.
    #[arg(long)]
    pub setup: PathBuf,
    /// Ballbar readings: experiment,time_min,mode,angle_deg,dl_um.
    #[arg(long)]
    pub data: PathBuf,
    /// Temperatures: experiment,time_min,<sensor>_c,... (joined by experiment and time).
    #[arg(long)]
    pub temps: Option<PathBuf>,
    /// Output folder (default: <data stem>-ballbar beside the data file).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let setup = Setup::read(&args.setup)?;
    let table = Table::read(&args.data)?;
    let data = Measurements::from_table(&table, &setup)?;
    let temps = args
        .temps
        .as_deref()
        .map(TemperatureLog::read)
        .transpose()?;
    if let (Some(t), Some(path)) = (&temps, &args.temps) {
        for m in &data.items {
            if t.at(m.experiment, m.time_min).is_none() {
                return Err(InputError::line(
                    &args.data,
                    m.first_line,
                    format!(
                        "no temperatures for experiment {} at {} min in {}",
                        m.experiment,
                        m.time_min,
                        path.display()
                    ),
                )
                .into());
            }
        }
    }
    let result = identify(&setup, &data).map_err(|e| match e {
        BallbarError::RankDeficient { .. } | BallbarError::Geometry(_) => {
            CliError::Input(InputError::file(&args.setup, e.to_string()))
        }
        BallbarError::Signal(_) => CliError::Input(InputError::file(&args.data, e.to_string())),
    })?;
    let csv = motions_csv(&result, temps.as_ref());
    let conditioning = serde_json::to_string_pretty(&result.conditioning)
        .map_err(|e| CliError::Internal(e.into()))?;

    let mut inputs = vec![args.setup.clone(), args.data.clone()];
    inputs.extend(args.temps.clone());
    let guard = OutputGuard::new(&inputs);
    let out_dir = match (&args.out, args.json) {
        (Some(d), _) => Some(d.clone()),
        (None, false) => Some(default_out(&args.data)),
        (None, true) => None,
    };
    if let Some(dir) = &out_dir {
        guard.write(&dir.join("motions.csv"), csv.as_bytes())?;
        guard.write(&dir.join("conditioning.json"), conditioning.as_bytes())?;
        let samples: Vec<MotionSample> = result
            .rows
            .iter()
            .map(|r| MotionSample {
                experiment: r.experiment,
                time_min: r.time_min,
                angle_deg: r.angle_deg,
                values: r.motions.observable().to_vec(),
            })
            .collect();
        for f in rotary_figures(&samples, &MOTION_COLUMNS) {
            guard.write(&dir.join(&f.name), f.svg.as_bytes())?;
        }
    }
    if args.json {
        let rows: Vec<serde_json::Value> = result
            .rows
            .iter()
            .map(|r| {
                let mut o = serde_json::json!({
                    "experiment": r.experiment,
                    "time_min": r.time_min,
                    "angle_deg": r.angle_deg,
                    "EXC_um": r.motions.exc_um,
                    "EYC_um": r.motions.eyc_um,
                    "EZC_um": r.motions.ezc_um,
                    "EAC_urad": r.motions.eac_urad,
                    "EBC_urad": r.motions.ebc_urad,
                });
                if let Some(t) = &temps {
                    let v = &t.rows[&(r.experiment, time_key(r.time_min))];
                    for (n, x) in t.sensor_names.iter().zip(v) {
                        o[n] = serde_json::json!(x);
                    }
                }
                o
            })
            .collect();
        let doc = serde_json::json!({
            "format": "mtec.ballbar-identification/1",
            "conditioning": result.conditioning,
            "motions": rows,
        });
        println!("{doc}");
    } else {
        let c = &result.conditioning;
        println!(
            "identified {} angles in {} measurements; rank {} of 5, worst condition number {:.2} at C = {} deg (noise gain {:.2} per um)",
            result.rows.len(),
            data.items.len(),
            c.rank,
            c.worst_condition_number,
            c.worst_angle_deg,
            c.worst_noise_gain
        );
        for u in &c.revolution.unobservable {
            println!("note: invisible once the set-up error is removed (reported as zero): {u}");
        }
        if let Some(dir) = &out_dir {
            println!(
                "wrote {}/motions.csv, conditioning.json and the polar/time plots",
                dir.display()
            );
        }
    }
    Ok(())
}

fn default_out(data: &Path) -> PathBuf {
    let stem = data
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "dbb".into());
    data.with_file_name(format!("{stem}-ballbar"))
}

fn motions_csv(result: &Identification, temps: Option<&TemperatureLog>) -> String {
    let mut s =
        String::from("experiment,time_min,angle_deg,EXC_um,EYC_um,EZC_um,EAC_urad,EBC_urad");
    if let Some(t) = temps {
        for n in &t.sensor_names {
            s.push(',');
            s.push_str(n);
        }
    }
    s.push('\n');
    for r in &result.rows {
        let m = &r.motions;
        s.push_str(&format!(
            "{},{},{},{:.4},{:.4},{:.4},{:.3},{:.3}",
            r.experiment,
            r.time_min,
            r.angle_deg,
            m.exc_um,
            m.eyc_um,
            m.ezc_um,
            m.eac_urad,
            m.ebc_urad
        ));
        if let Some(t) = temps {
            for v in &t.rows[&(r.experiment, time_key(r.time_min))] {
                s.push_str(&format!(",{v}"));
            }
        }
        s.push('\n');
    }
    s
}
