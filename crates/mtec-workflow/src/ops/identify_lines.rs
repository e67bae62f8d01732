//! The error elements of a three-axis machine from line measurements (9-line method): the
//! report, and optionally the error set, the kinematic model and the error statistics.
//! The job of `mtec identify lines`.

use crate::inputs::read_machine;
use crate::{Error, Observer, Result};
use mtec_comp::kinematic::KinematicFile;
use mtec_identify::lines::{self, Degree, LineData, LinesError, LinesReport, DEFAULT_DEGREE};
use mtec_io::{Destination, InputError, OutputGuard};
use mtec_model::ErrorSet;
use mtec_sensitivity::error_model::ErrorStatistics;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// What to identify from what, and where the results go.
#[derive(Debug, Clone)]
pub struct Options {
    /// Machine description (TOML): chain, travels, tool offset of the measurement.
    pub machine: PathBuf,
    /// Line measurements (CSV, docs/formats.md "Line measurement CSV").
    pub data: Option<PathBuf>,
    /// A built-in design (`nine-line`, `fifteen-line`): the data must contain its lines;
    /// without data, the design is analysed alone.
    pub design: Option<String>,
    /// Degree of the error functions: `auto` (cross-validated) or 2..12.
    pub degree: Degree,
    /// Where to write the identified error set (`mtec.errors/1`; `-` is stdout).
    pub output: Option<PathBuf>,
    /// Where to write the kinematic model (`mtec.kinematic-model/1`).
    pub kinematic_model: Option<PathBuf>,
    /// Where to write the error statistics (CSV element,mean,std,unit).
    pub stats: Option<PathBuf>,
}

impl Options {
    /// The data identified at the default degree, nothing written.
    pub fn new(machine: impl Into<PathBuf>, data: impl Into<PathBuf>) -> Options {
        Options {
            machine: machine.into(),
            data: Some(data.into()),
            design: None,
            degree: DEFAULT_DEGREE,
            output: None,
            kinematic_model: None,
            stats: None,
        }
    }
}

/// The result. Serialises to the report (`mtec.identify-lines/1`); the identified set and the
/// files written are kept beside it.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    #[serde(flatten)]
    pub report: LinesReport,
    /// The identified error set (what `output` holds).
    #[serde(skip)]
    pub errors: ErrorSet,
    /// The files written, in the order written (`-` for stdout).
    #[serde(skip)]
    pub written: Vec<PathBuf>,
}

/// The files the job writes, settled before any work.
struct Outputs {
    errors: Option<(PathBuf, Destination)>,
    kinematic_model: Option<(PathBuf, Destination)>,
    stats: Option<(PathBuf, Destination)>,
}

impl Outputs {
    /// Checks every output before any work: none may be an input, a directory or another of
    /// them, at most one may be stdout (`-`), and all need measurements.
    fn check(o: &Options) -> Result<Outputs> {
        let named = [
            ("-o", &o.output),
            ("--kinematic-model", &o.kinematic_model),
            ("--stats", &o.stats),
        ];
        let given: Vec<(&str, &PathBuf)> = named
            .iter()
            .filter_map(|(opt, p)| p.as_ref().map(|p| (*opt, p)))
            .collect();
        if let (Some((opt, _)), None) = (given.first(), &o.data) {
            return Err(Error::usage(format!(
                "{opt} needs measurements (--data): a design alone identifies no values"
            )));
        }
        let on_stdout: Vec<&str> = given
            .iter()
            .filter(|(_, p)| p.as_os_str() == "-")
            .map(|(opt, _)| *opt)
            .collect();
        if on_stdout.len() > 1 {
            return Err(Error::usage(format!(
                "{} all name stdout (-): at most one output can go there",
                on_stdout.join(" and ")
            )));
        }
        let mut inputs = vec![o.machine.clone()];
        inputs.extend(o.data.clone());
        let guard = OutputGuard::new(&inputs);
        // each output against the ones before it, so that two never name one file
        let mut earlier: Vec<(&str, OutputGuard)> = Vec::new();
        let mut check =
            |opt: &'static str, p: &Option<PathBuf>| -> Result<Option<(PathBuf, Destination)>> {
                let Some(p) = p else { return Ok(None) };
                let dest = guard.check(p)?;
                for (other, g) in &earlier {
                    if g.check(p).is_err() {
                        return Err(Error::Input(InputError::file(
                            p,
                            format!(
                            "{opt} names the same file as {other}: give each output its own file"
                        ),
                        )));
                    }
                }
                earlier.push((opt, OutputGuard::new(&[p])));
                Ok(Some((p.clone(), dest)))
            };
        Ok(Outputs {
            errors: check("-o", &o.output)?,
            kinematic_model: check("--kinematic-model", &o.kinematic_model)?,
            stats: check("--stats", &o.stats)?,
        })
    }
}

/// True when one of `opts`' outputs is standard output (`-`, which [`Destination`] writes to
/// stdout): a front prints its report on stderr then, so the two never mix.
pub fn writes_to_stdout(opts: &Options) -> bool {
    [&opts.output, &opts.kinematic_model, &opts.stats]
        .into_iter()
        .flatten()
        .any(|p| p.as_os_str() == "-")
}

/// Identifies the error elements; writes the outputs that are asked for.
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    // where the outputs go is settled before any work (an input, a directory: a usage error)
    let outputs = Outputs::check(opts)?;
    let machine = read_machine(&opts.machine)?;
    let preset = match &opts.design {
        Some(name) => Some(
            mtec_model::line_preset(name, &machine, 20, 10.0).ok_or_else(|| {
                InputError::file(
                    &opts.machine,
                    format!("the `{name}` design needs a machine with axes X, Y and Z"),
                )
            })?,
        ),
        None => None,
    };
    let data =
        match (&opts.data, &preset) {
            (Some(path), _) => {
                let d = LineData::read(path)?;
                if let Some(p) = &preset {
                    lines::check_design(&d, p).map_err(|m| {
                        InputError::file(
                            path,
                            format!("{m} (--design {})", opts.design.as_deref().unwrap_or("")),
                        )
                    })?;
                }
                d
            }
            (None, Some(p)) => LineData::from_specs(p).map_err(Error::Usage)?,
            (None, None) => return Err(Error::usage(
                "give the measurements with --data LINES.csv, or a design to analyse with --design",
            )),
        };
    let id = lines::identify_with(&machine, &data, opts.degree).map_err(|e| match e {
        LinesError::Input(i) => Error::Input(i),
        LinesError::Model(m) => Error::Input(InputError::file(&opts.machine, m.to_string())),
        other => Error::Input(InputError::file(
            opts.data.as_deref().unwrap_or(&opts.machine),
            other.to_string(),
        )),
    })?;
    // everything is made before anything is written: a machine the compensation cannot
    // evaluate (no X, Y, Z) refuses the kinematic model, and no file is left half-done
    let kinematic = match &outputs.kinematic_model {
        Some(_) => Some(
            KinematicFile::new(&machine, &id.errors)
                .map_err(|m| Error::Input(InputError::file(&opts.machine, m)))?
                .to_json()
                .map_err(|e| Error::Internal(e.into()))?,
        ),
        None => None,
    };
    let stats = outputs
        .stats
        .as_ref()
        .map(|_| ErrorStatistics::of_identified(&id.errors, &machine).to_identified_csv());
    let errors = match &outputs.errors {
        Some(_) => Some(serde_json::to_vec_pretty(&id.errors)?),
        None => None,
    };
    let mut written = Vec::new();
    for (out, bytes) in [
        (&outputs.errors, errors),
        (&outputs.kinematic_model, kinematic.map(String::into_bytes)),
        (&outputs.stats, stats.map(String::into_bytes)),
    ] {
        if let (Some((path, dest)), Some(bytes)) = (out, bytes) {
            dest.write(&bytes)?;
            written.push(path.clone());
        }
    }
    Ok(Outcome {
        report: id.report,
        errors: id.errors,
        written,
    })
}

impl Outcome {
    /// The report as the command's `--json` prints it (`mtec.identify-lines/1`).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(&self.report)?)
    }
}

/// The text report, then `Wrote FILE` for each file written.
impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.report.to_text())?;
        for p in &self.written {
            writeln!(f, "Wrote {}", p.display())?;
        }
        Ok(())
    }
}
