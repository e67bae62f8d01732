//! `mtec run PROJECT.toml`: the whole pipeline a project file asks for, with an HTML report.
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
//! [[thermal]]
//! data = "thermal.csv"
//! target = "drift_um"
//! model = "ridge-select"
//! [map]
//! grid = "grid.csv"
//! [compensation]
//! gcode = ["part.ngc"]
//! tables = ["linuxcnc"]
//! [machine_model]              # thermal models of the [[thermal]] stages + envelopes
//! data = "thermal.csv"
//! parts = [{ target = "drift_um", axis = "z" }]
//! [[replay]]                   # a recorded day compensated through the real-time path
//! state = "day-state.csv"
//! probes = "day-probes.csv"
//! ```

use crate::error::CliError;
use mtec_io::{InputError, OutputGuard};
use mtec_report::Report;
use serde::Deserialize;
use std::path::{Path, PathBuf};

const LONG: &str = "\
Run the whole pipeline of a project file and write report.html.

The project file (TOML; docs/formats.md, \"Project TOML\") names the machine and the
measurement files, and which analyses, models and compensation outputs to produce; paths in it
are relative to it. Each stage runs the job of the subcommand a user would type and keeps its
JSON result in the output folder; a stage that fails stops the run with its message and exit
code. `mtec demo` writes a complete project to start from.";

const EXAMPLES: &str = crate::help::examples!(
    "  # positioning runs of an axis and a spindle's thermal log
  $ mtec simulate iso230-2 --out p
  $ mtec simulate spindle-sensors --out t
  # a project: ISO 230-2 of the runs, a thermal model of the radial drift
  $ printf '%s\\n' 'name = \"X axis and spindle\"' \\
      '[[iso230_2]]' 'data = \"p/iso230-2.csv\"' \\
      '[[thermal]]' 'data = \"t/thermal.csv\"' 'target = \"radial_um\"' \\
      'model = \"ridge-select\"' > project.toml
  $ mtec run project.toml --out results"
);

/// Arguments of `mtec run`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Run the whole pipeline of a project file and write an HTML report",
    long_about = LONG,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// Project file (TOML).
    pub project: PathBuf,
    /// Output folder (default: <project name>-results beside the project file).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long)]
    pub quiet: bool,
    /// Print a JSON summary (the stages and their output files) on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Project {
    #[serde(default)]
    pub name: String,
    pub machine: Option<PathBuf>,
    #[serde(default)]
    pub iso230_2: Vec<DataStage>,
    pub lines: Option<LinesStage>,
    pub sensitivity: Option<SensitivityStage>,
    #[serde(default)]
    pub circular: Vec<DataStage>,
    pub ballbar: Option<BallbarStage>,
    #[serde(default)]
    pub thermal: Vec<ThermalStage>,
    pub map: Option<MapStage>,
    pub compensation: Option<CompensationStage>,
    pub machine_model: Option<MachineModelStage>,
    #[serde(default)]
    pub replay: Vec<ReplayStage>,
}

/// `[machine_model]`: `mtec machine build` over the models of the [[thermal]] stages.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineModelStage {
    /// The data the thermal models were fitted on (their envelopes come from it).
    pub data: PathBuf,
    pub parts: Vec<MachinePart>,
    /// Static geometric model file; default: the [map] stage's map, if any.
    pub geometric: Option<PathBuf>,
    /// Columns of `data` that guard every thermal part (`machine build --guard`).
    #[serde(default)]
    pub guard: Vec<String>,
    pub fade_c: Option<f64>,
}

/// One thermal part: the [[thermal]] stage with this target, along `axis`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachinePart {
    pub target: String,
    pub axis: String,
    #[serde(default = "plus_one")]
    pub sign: f64,
}

fn plus_one() -> f64 {
    1.0
}

/// `[[replay]]`: `mtec machine replay` of a recorded day.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplayStage {
    #[serde(default)]
    pub name: String,
    pub state: PathBuf,
    pub probes: PathBuf,
    /// Model file; default: the [machine_model] stage's.
    pub model: Option<PathBuf>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataStage {
    pub data: PathBuf,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinesStage {
    pub data: PathBuf,
    pub degree: Option<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensitivityStage {
    /// Error statistics CSV; default: derived from the identified error set.
    pub stats: Option<PathBuf>,
    #[serde(default = "default_method")]
    pub method: String,
    pub samples: Option<usize>,
}

fn default_method() -> String {
    "efast".into()
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BallbarStage {
    pub setup: PathBuf,
    pub data: PathBuf,
    pub temps: Option<PathBuf>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalStage {
    pub data: PathBuf,
    pub target: String,
    #[serde(default = "default_thermal_model")]
    pub model: String,
    pub train: Option<String>,
    pub test: Option<String>,
    pub train_until_min: Option<f64>,
    /// Add a fitted first-order lag of each sensor (`thermal fit --lag`).
    #[serde(default)]
    pub lag: bool,
    /// Sensors to use (`--sensors`); default: all.
    pub sensors: Option<Vec<String>>,
    /// heat-input: the heat-source column (`--input`).
    pub input: Option<String>,
}

fn default_thermal_model() -> String {
    "ridge-select".into()
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapStage {
    pub grid: PathBuf,
    /// Points to evaluate the map at (CSV with x_mm, y_mm, z_mm; extra columns are ignored).
    pub check: Option<PathBuf>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CompensationStage {
    #[serde(default)]
    pub gcode: Vec<PathBuf>,
    #[serde(default)]
    pub tables: Vec<String>,
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// The pipeline state shared by the stages.
pub struct Pipeline {
    pub base: PathBuf,
    pub out: PathBuf,
    pub quiet: bool,
    pub report: Report,
    pub outputs: Vec<String>,
    guard: OutputGuard,
    step: usize,
    steps: usize,
    /// The stage running now (its progress line).
    current: String,
}

impl Pipeline {
    pub fn path_of(&self, p: &Path) -> PathBuf {
        self.path(p)
    }
    pub fn progress_of(&mut self, what: &str) {
        self.progress(what)
    }
    fn path(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base.join(p)
        }
    }

    fn progress(&mut self, what: &str) {
        self.step += 1;
        self.current = what.to_string();
        if !self.quiet {
            eprintln!("[{}/{}] {what}", self.step, self.steps);
        }
    }

    fn save(&mut self, name: &str, text: &str) -> Result<PathBuf, CliError> {
        let p = self.out.join(name);
        self.guard.write(&p, text.as_bytes())?;
        self.outputs.push(s(&p));
        Ok(p)
    }

    /// Saves a job's JSON result (`text`, as its command prints it with `--json`) in the output
    /// folder and returns it parsed.
    pub fn json_result(&mut self, file: &str, text: &str) -> Result<serde_json::Value, CliError> {
        self.save(file, text)?;
        Ok(serde_json::from_str(text)?)
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let project: Project = mtec_io::read_toml(&args.project)?;
    let base = args
        .project
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let name = if project.name.is_empty() {
        "project".to_string()
    } else {
        project.name.clone()
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| base.join(format!("{}-results", slug(&name))));
    let report_path = run_project(&project, &args.project, &base, &out, args.quiet, &name)?;
    if args.json {
        println!(
            "{}",
            serde_json::json!({ "format": "mtec.run/1", "report": s(&report_path), "out": s(&out) })
        );
    } else if !args.quiet {
        println!("report: {}", report_path.display());
    }
    Ok(())
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

/// Runs a parsed project; returns the path of report.html.
pub fn run_project(
    project: &Project,
    project_path: &Path,
    base: &Path,
    out: &Path,
    quiet: bool,
    name: &str,
) -> Result<PathBuf, CliError> {
    run_project_with(project, project_path, base, out, quiet, name, |_| Ok(()))
}

/// Runs a parsed project, letting `extra` add report sections before the report is written.
pub fn run_project_with(
    project: &Project,
    project_path: &Path,
    base: &Path,
    out: &Path,
    quiet: bool,
    name: &str,
    extra: impl FnOnce(&mut Pipeline) -> Result<(), CliError>,
) -> Result<PathBuf, CliError> {
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
        quiet,
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
    };
    // every file the project names is an input that no output may overwrite
    let check = |f: &Path, what: &str| -> Result<PathBuf, InputError> {
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
    let ran = (|| -> Result<(), CliError> {
        crate::cmd::pipeline::machine_section(&mut p, machine.as_deref())?;
        for st in &project.iso230_2 {
            crate::cmd::pipeline::iso230_2(&mut p, &st.data)?;
        }
        let mut identified: Option<PathBuf> = None;
        if let (Some(l), Some(m)) = (&project.lines, &machine) {
            identified = Some(crate::cmd::pipeline::lines(&mut p, m, l)?);
        }
        if let (Some(st), Some(m)) = (&project.sensitivity, &machine) {
            crate::cmd::pipeline::sensitivity(&mut p, m, st, identified.as_deref())?;
        }
        for st in &project.circular {
            crate::cmd::pipeline::circular(&mut p, &st.data)?;
        }
        if let Some(b) = &project.ballbar {
            crate::cmd::pipeline::ballbar(&mut p, b)?;
        }
        let mut thermal_models = Vec::new();
        for t in &project.thermal {
            thermal_models.push((t.target.clone(), crate::cmd::pipeline::thermal(&mut p, t)?));
        }
        let mut map: Option<PathBuf> = None;
        if let Some(m) = &project.map {
            map = Some(crate::cmd::pipeline::map(&mut p, m)?);
        }
        if let Some(c) = &project.compensation {
            crate::cmd::pipeline::compensation(
                &mut p,
                c,
                map.as_deref(),
                machine.as_deref(),
                identified.as_deref(),
            )?;
        }
        let mut machine_model: Option<PathBuf> = None;
        if let Some(m) = &project.machine_model {
            machine_model = Some(crate::cmd::machine_stage::build(
                &mut p,
                m,
                &thermal_models,
                map.as_deref(),
            )?);
        }
        for r in &project.replay {
            crate::cmd::machine_stage::replay(&mut p, r, machine_model.as_deref())?;
        }
        extra(&mut p)
    })();
    if let Err(e) = &ran {
        let stage = p.current.clone();
        let sec = p.report.section(format!("FAILED: {stage}"));
        sec.note(format!(
            "This stage failed, so the run stopped here and the stages after it did not run: {e}"
        ));
    }
    let html = p.report.to_html();
    let report = p.save("report.html", &html)?;
    if ran.is_err() {
        eprintln!(
            "report, with the failed stage as its last section: {}",
            report.display()
        );
    }
    ran?;
    Ok(report)
}
