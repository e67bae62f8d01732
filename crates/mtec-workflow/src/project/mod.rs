//! A project: the whole pipeline a project file asks for, with an HTML report (`mtec run
//! PROJECT.toml`, `mtec demo`, `mtec.run_project` in Python).
//!
//! Each stage runs the job of the subcommand a user would type, in-process
//! (`mtec_workflow::ops`); its result is saved in the output folder as the command prints it
//! with `--json` and turned into a report section (tables of its numbers, plots). A stage that
//! fails stops the run with that stage's message and exit code: a report never hides a failed
//! analysis.
//!
//! Project file (paths relative to the project file):
//! ```toml
//! name = "VMC acceptance 2026-11"
//! machine = "machine.toml"
//! [[iso230_2]]                 # one table per positioning run file
//! data = "x-axis.csv"
//! [lines]                      # 9-line identification
//! data = "lines.csv"
//! [sensitivity]                # EFAST of the identified (or given) error statistics
//! method = "efast"
//! [[circular]]
//! data = "circular.csv"
//! [ballbar]
//! setup = "setup.toml"
//! data = "dbb.csv"
//! temps = "temps.csv"
//! model = "rotary.json"      # optional: its predicted readings (neural build)
//! [[thermal]]
//! data = "thermal.csv"
//! target = "drift_um"
//! model = "ridge-select"
//! [map]
//! grid = "grid.csv"
//! [compensation]
//! gcode = ["part.ngc"]
//! tables = ["linuxcnc"]
//! elements = "key"             # optional: all | key | EXX,EYY (the identified kinematic model)
//! [machine_model]              # thermal models of the [[thermal]] stages + envelopes
//! data = "thermal.csv"
//! parts = [{ target = "drift_um", axis = "z" }]
//! [[replay]]                   # a recorded day compensated through the real-time path
//! state = "day-state.csv"
//! probes = "day-probes.csv"
//! ```

pub mod demo;
mod labels;
mod machine_stage;
mod pipeline;
#[cfg(feature = "neural")]
mod readings_section;
mod selective_section;
mod spec;
mod stages;
mod summary;
mod thermal_section;

pub use pipeline::Pipeline;
pub use spec::*;
pub use stages::fmt_value;

use crate::{Observer, Result};
use mtec_io::{InputError, OutputGuard};
use mtec_report::Report;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The folder a project's results go to by default: `<name>-results` beside the project file.
pub fn default_out(project_path: &Path, name: &str) -> PathBuf {
    project_path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
        .join(format!("{}-results", slug(name)))
}

fn slug(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect()
}

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The project file (TOML; docs/formats.md, "Project TOML").
    pub project: PathBuf,
    /// Output folder (`None`: `<project name>-results` beside the project file).
    pub out: Option<PathBuf>,
    /// The report's name (`None`: the project's `name`).
    pub title: Option<String>,
}

impl RunOptions {
    /// The project file's run into its default folder.
    pub fn new(project: impl Into<PathBuf>) -> Self {
        RunOptions {
            project: project.into(),
            out: None,
            title: None,
        }
    }
}

/// Where a project run put its results (`mtec run --json`).
#[derive(Debug, Clone, Serialize)]
pub struct RunOutcome {
    pub format: &'static str,
    /// The output folder.
    pub out: PathBuf,
    /// report.html.
    pub report: PathBuf,
    /// Every file written, in order.
    #[serde(skip)]
    pub outputs: Vec<String>,
}

/// Runs the project file: every stage it asks for, in-process, then report.html. A stage that
/// fails ends the run with its error, after the report is written with the failure as its last
/// section.
pub fn run(opts: &RunOptions, obs: &mut dyn Observer) -> Result<RunOutcome> {
    run_with(opts, obs, |_| Ok(()))
}

/// [`run`], letting `extra` add report sections (after the stages, before the report is
/// written; `mtec demo` adds the compensation rate against the simulation's truth).
pub fn run_with(
    opts: &RunOptions,
    obs: &mut dyn Observer,
    extra: impl FnOnce(&mut Pipeline) -> Result<()>,
) -> Result<RunOutcome> {
    let project: Project = mtec_io::read_toml(&opts.project)?;
    let base = opts
        .project
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let name = if project.name.is_empty() {
        "project".to_string()
    } else {
        project.name.clone()
    };
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| default_out(&opts.project, &name));
    let title = opts.title.as_deref().unwrap_or(&name);
    let (report, outputs) =
        run_project_with(&project, &opts.project, &base, &out, title, obs, extra)?;
    Ok(RunOutcome {
        format: "mtec.run/1",
        report,
        out,
        outputs,
    })
}

/// Runs a parsed project (paths relative to `base`), letting `extra` add report sections before
/// the report is written; returns report.html and every file written.
fn run_project_with(
    project: &Project,
    project_path: &Path,
    base: &Path,
    out: &Path,
    name: &str,
    obs: &mut dyn Observer,
    extra: impl FnOnce(&mut Pipeline) -> Result<()>,
) -> Result<(PathBuf, Vec<String>)> {
    let mut inputs = vec![project_path.to_path_buf()];
    let steps = project.iso230_2.len()
        + project.lines.is_some() as usize
        + project.sensitivity.is_some() as usize
        + project.circular.len()
        + project.ballbar.is_some() as usize
        + project.thermal.len()
        + project.map.is_some() as usize
        + project.compensation.is_some() as usize
        + project.machine_model.is_some() as usize
        + project.replay.len();
    let mut p = Pipeline {
        base: base.to_path_buf(),
        out: out.to_path_buf(),
        obs,
        report: Report::new(
            format!("mtec report: {name}"),
            format!(
                "mtec {} — measure, identify, model, compensate",
                env!("CARGO_PKG_VERSION")
            ),
        ),
        outputs: vec![],
        guard: OutputGuard::default(),
        step: 0,
        steps,
        current: String::new(),
        summary: Default::default(),
        tolerances: project.tolerances.clone(),
    };
    // every file the project names is an input that no output may overwrite
    let check = |f: &Path, what: &str| -> std::result::Result<PathBuf, InputError> {
        let f = if f.is_absolute() {
            f.to_path_buf()
        } else {
            base.join(f)
        };
        if !f.is_file() {
            return Err(InputError::file(
                project_path,
                format!("{what} `{}` does not exist", f.display()),
            ));
        }
        Ok(f)
    };
    let machine = project
        .machine
        .as_ref()
        .map(|m| check(m, "machine"))
        .transpose()?;
    for st in &project.iso230_2 {
        inputs.push(check(&st.data, "iso230_2 data")?);
    }
    for st in &project.circular {
        inputs.push(check(&st.data, "circular data")?);
    }
    if let Some(l) = &project.lines {
        inputs.push(check(&l.data, "lines data")?);
        if machine.is_none() {
            return Err(InputError::file(project_path, "[lines] needs `machine`").into());
        }
    }
    if let Some(b) = &project.ballbar {
        inputs.push(check(&b.setup, "ballbar setup")?);
        inputs.push(check(&b.data, "ballbar data")?);
        if let Some(t) = &b.temps {
            inputs.push(check(t, "ballbar temps")?);
        }
        if let Some(m) = &b.model {
            inputs.push(check(m, "ballbar model")?);
            if b.temps.is_none() {
                return Err(InputError::file(
                    project_path,
                    "[ballbar] model needs `temps`: the model predicts from the temperatures",
                )
                .into());
            }
        }
    }
    for t in &project.thermal {
        inputs.push(check(&t.data, "thermal data")?);
    }
    if let Some(m) = &project.map {
        inputs.push(check(&m.grid, "map grid")?);
    }
    if let Some(c) = &project.compensation {
        for g in &c.gcode {
            inputs.push(check(g, "gcode")?);
        }
    }
    if let Some(m) = &project.machine_model {
        inputs.push(check(&m.data, "machine_model data")?);
        if let Some(g) = &m.geometric {
            inputs.push(check(g, "machine_model geometric")?);
        }
        for part in &m.parts {
            let n = project
                .thermal
                .iter()
                .filter(|t| t.target == part.target)
                .count();
            if n != 1 {
                return Err(InputError::file(
                    project_path,
                    format!(
                        "[machine_model] part `{}`: {n} [[thermal]] stages have this target, it needs exactly one",
                        part.target
                    ),
                )
                .into());
            }
        }
    }
    for r in &project.replay {
        inputs.push(check(&r.state, "replay state")?);
        inputs.push(check(&r.probes, "replay probes")?);
        match &r.model {
            Some(m) => inputs.push(check(m, "replay model")?),
            None if project.machine_model.is_none() => {
                return Err(InputError::file(
                    project_path,
                    "[[replay]] needs `model` or a [machine_model] stage",
                )
                .into())
            }
            None => {}
        }
    }
    inputs.extend(machine.clone());
    p.guard = OutputGuard::new(&inputs);
    std::fs::create_dir_all(out)?;

    // a stage that fails ends the run: the report is still written, with the failure as its
    // last section, and the run exits with the stage's error (a report never hides it)
    let ran = (|| -> Result<()> {
        stages::machine_section(&mut p, machine.as_deref())?;
        for st in &project.iso230_2 {
            stages::iso230_2(&mut p, &st.data)?;
        }
        let mut identified: Option<PathBuf> = None;
        if let (Some(l), Some(m)) = (&project.lines, &machine) {
            identified = Some(stages::lines(&mut p, m, l)?);
        }
        if let (Some(st), Some(m)) = (&project.sensitivity, &machine) {
            stages::sensitivity(&mut p, m, st, identified.as_deref())?;
        }
        for st in &project.circular {
            stages::circular(&mut p, &st.data)?;
        }
        if let Some(b) = &project.ballbar {
            stages::ballbar(&mut p, b)?;
        }
        let mut thermal_models = Vec::new();
        for t in &project.thermal {
            thermal_models.push((t.target.clone(), stages::thermal(&mut p, t)?));
        }
        let mut map: Option<PathBuf> = None;
        if let Some(m) = &project.map {
            map = Some(stages::map(&mut p, m)?);
        }
        if let Some(c) = &project.compensation {
            stages::compensation(
                &mut p,
                c,
                map.as_deref(),
                machine.as_deref(),
                identified.as_deref(),
            )?;
        }
        let mut machine_model: Option<PathBuf> = None;
        if let Some(m) = &project.machine_model {
            machine_model = Some(machine_stage::build(
                &mut p,
                m,
                &thermal_models,
                map.as_deref(),
            )?);
        }
        for r in &project.replay {
            machine_stage::replay(&mut p, r, machine_model.as_deref())?;
        }
        extra(&mut p)
    })();
    if let Err(e) = &ran {
        let stage = p.current.clone();
        let sec = p.report.section(format!("FAILED: {stage}"));
        sec.note(format!(
            "This stage failed, so the run stopped here and the stages after it did not run: {e}"
        ));
    } else if !p.current.is_empty() {
        p.summary.completed.push(std::mem::take(&mut p.current));
    }
    // the summary, read first: the verdict, the files, every stage's key figures
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    for f in &inputs {
        // a file several stages read is listed once
        if !files.iter().any(|(_, g)| g == f) {
            let shown = f.strip_prefix(base).unwrap_or(f).display().to_string();
            files.push((shown, f.clone()));
        }
    }
    let failed = ran
        .as_ref()
        .err()
        .map(|e| (p.current.clone(), e.to_string()));
    let not_run = if failed.is_some() {
        p.steps.saturating_sub(p.step)
    } else {
        0
    };
    let summary = p.summary.section(
        name,
        &files,
        failed.as_ref().map(|(s, e)| (s.as_str(), e.clone())),
        not_run,
    );
    p.report.insert_first(summary);
    let html = p.report.to_html();
    let report = p.save("report.html", &html)?;
    if ran.is_err() {
        p.obs.progress(&format!(
            "report, with the failed stage as its last section: {}",
            report.display()
        ));
    }
    ran?;
    Ok((report, p.outputs))
}
