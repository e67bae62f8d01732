//! Rotary-axis error motions (EXC, EYC, EZC, EAC, EBC) from ballbar readings in five
//! installation modes, with the temperatures joined in; optionally `motions.csv`,
//! `conditioning.json` and the polar/time plots. The job of `mtec identify ballbar`.

use crate::{Error, Observer, Result};
use mtec_identify::ballbar::motions_file::{motion_records, motions_csv, MotionRecord};
use mtec_identify::ballbar::{
    identify, BallbarError, ConditioningReport, Measurements, Setup, TemperatureLog,
};
use mtec_io::{InputError, OutputGuard, Table};
use mtec_report::rotary::{rotary_figures, MotionSample};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// The motions table the job writes into [`Options::out`].
pub const MOTIONS_FILE: &str = "motions.csv";
/// The conditioning report the job writes into [`Options::out`].
pub const CONDITIONING_FILE: &str = "conditioning.json";
/// The plots' series: the five observable motions.
const MOTION_COLUMNS: [&str; 5] = ["EXC_um", "EYC_um", "EZC_um", "EAC_urad", "EBC_urad"];

/// What to identify from what, and where the results go.
#[derive(Debug, Clone)]
pub struct Options {
    /// Setup TOML with the five `[[mode]]` tables.
    pub setup: PathBuf,
    /// Ballbar readings (CSV experiment,time_min,mode,angle_deg,dl_um).
    pub data: PathBuf,
    /// Temperatures (CSV experiment,time_min,<sensor>_c,...), joined by experiment and time.
    pub temps: Option<PathBuf>,
    /// Folder for `motions.csv`, `conditioning.json` and the plots; `None` writes nothing
    /// (the command's default folder is [`default_out`]).
    pub out: Option<PathBuf>,
}

/// The folder the command writes into without `--out`: `<data stem>-ballbar` beside the data.
pub fn default_out(data: &Path) -> PathBuf {
    let stem = data
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "dbb".into());
    data.with_file_name(format!("{stem}-ballbar"))
}

/// The output folder of a run: `out`, else [`default_out`] for a text report, else (JSON on
/// stdout alone) none.
pub fn out_folder(out: Option<PathBuf>, data: &Path, json: bool) -> Option<PathBuf> {
    match (out, json) {
        (Some(d), _) => Some(d),
        (None, false) => Some(default_out(data)),
        (None, true) => None,
    }
}

/// The result: `mtec.ballbar-identification/1` (docs/formats.md).
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// `mtec.ballbar-identification/1`.
    pub format: String,
    /// Conditioning of the mode set (`mtec.ballbar-conditioning/1`).
    pub conditioning: ConditioningReport,
    /// The motions per experiment, time and angle, with their temperatures.
    pub motions: Vec<MotionRecord>,
    /// Measurements (experiment, time) identified.
    #[serde(skip)]
    pub measurements: usize,
    /// The folder written, if any.
    #[serde(skip)]
    pub out: Option<PathBuf>,
}

impl Outcome {
    /// The outcome as the one-line JSON the command prints (keys sorted).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_value(self)?.to_string())
    }
}

/// Identifies the motions; writes the files into `opts.out` when given.
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    let mut inputs = vec![opts.setup.clone(), opts.data.clone()];
    inputs.extend(opts.temps.clone());
    let guard = OutputGuard::new(&inputs);
    if let Some(dir) = &opts.out {
        guard.check(&dir.join(MOTIONS_FILE))?;
        guard.check(&dir.join(CONDITIONING_FILE))?;
    }
    let setup = Setup::read(&opts.setup)?;
    let table = Table::read(&opts.data)?;
    let data = Measurements::from_table(&table, &setup)?;
    let temps = opts
        .temps
        .as_deref()
        .map(TemperatureLog::read)
        .transpose()?;
    if let (Some(t), Some(path)) = (&temps, &opts.temps) {
        for m in &data.items {
            if t.at(m.experiment, m.time_min).is_none() {
                return Err(InputError::line(
                    &opts.data,
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
            Error::Input(InputError::file(&opts.setup, e.to_string()))
        }
        BallbarError::Signal(_) => Error::Input(InputError::file(&opts.data, e.to_string())),
    })?;
    if let Some(dir) = &opts.out {
        let csv = motions_csv(&result, temps.as_ref());
        let conditioning = serde_json::to_string_pretty(&result.conditioning)?;
        guard.write(&dir.join(MOTIONS_FILE), csv.as_bytes())?;
        guard.write(&dir.join(CONDITIONING_FILE), conditioning.as_bytes())?;
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
    Ok(Outcome {
        format: "mtec.ballbar-identification/1".into(),
        motions: motion_records(&result, temps.as_ref()),
        conditioning: result.conditioning,
        measurements: data.items.len(),
        out: opts.out.clone(),
    })
}

/// The summary the command prints: angles, rank, worst conditioning, what stays invisible.
impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = &self.conditioning;
        writeln!(
            f,
            "identified {} angles in {} measurements; rank {} of 5, worst condition number {:.2} at C = {} deg (noise gain {:.2} per um)",
            self.motions.len(),
            self.measurements,
            c.rank,
            c.worst_condition_number,
            c.worst_angle_deg,
            c.worst_noise_gain
        )?;
        for u in &c.revolution.unobservable {
            writeln!(
                f,
                "note: invisible once the set-up error is removed (reported as zero): {u}"
            )?;
        }
        if let Some(dir) = &self.out {
            writeln!(
                f,
                "wrote {}/motions.csv, conditioning.json and the polar/time plots",
                dir.display()
            )?;
        }
        Ok(())
    }
}
