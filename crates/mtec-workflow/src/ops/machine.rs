//! `machine build` and `machine replay`: the machine error model with a state
//! (`mtec.machine-error/1`), and a recorded day compensated through the real-time code path.

use crate::{Error, Observer, Result};
use mtec_comp::machine::{Fade, MachineFile, FADE_OTHER_FRACTION, FADE_TEMPERATURE_C};
use mtec_comp::machine_build::{self, BuildRequest, PartRequest};
use mtec_comp::replay::{self, ReplaySummary};
use mtec_comp::{Compensator, CorrectionOptions};
use mtec_io::{OutputGuard, Table};
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

/// A thermal part of the machine model: a fitted thermal model whose drift acts along one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// `x`, `y` or `z`.
    pub axis: String,
    /// The thermal model file (`mtec.thermal-model/1`).
    pub model: PathBuf,
    /// 1 when the model's target is the tool's displacement relative to the workpiece (mtec's
    /// convention), -1 when it is the workpiece's relative to the tool.
    pub sign: f64,
}

impl Part {
    /// Parses every `--thermal` value; the first malformed one is the error.
    pub fn parse_all(values: &[String]) -> Result<Vec<Part>> {
        values.iter().map(|s| Part::parse(s)).collect()
    }

    /// Parses `AXIS=MODEL.json[,sign=-1]` (the command line's `--thermal`).
    pub fn parse(s: &str) -> Result<Part> {
        let bad = |why: &str| {
            Error::usage(format!(
                "--thermal `{s}`: {why}; expected AXIS=MODEL.json[,sign=-1], e.g. z=dz.json"
            ))
        };
        let (axis, rest) = s.split_once('=').ok_or_else(|| bad("no `=`"))?;
        let axis = axis.trim().to_lowercase();
        if !["x", "y", "z"].contains(&axis.as_str()) {
            return Err(bad("the axis is x, y or z"));
        }
        let mut it = rest.split(',');
        let model = PathBuf::from(it.next().unwrap_or_default().trim());
        if model.as_os_str().is_empty() {
            return Err(bad("no model file"));
        }
        let mut sign = 1.0;
        for opt in it {
            match opt.trim().split_once('=') {
                Some(("sign", "1" | "+1")) => sign = 1.0,
                Some(("sign", "-1")) => sign = -1.0,
                _ => return Err(bad(&format!("`{opt}` is not sign=1 or sign=-1"))),
            }
        }
        Ok(Part { axis, model, sign })
    }
}

/// Options of [`build`].
#[derive(Debug, Clone)]
pub struct BuildOptions {
    /// Static geometric model (map, kinematic model, BPNN).
    pub geometric: Option<PathBuf>,
    /// The thermal parts.
    pub thermal: Vec<Part>,
    /// The data the thermal models were fitted on (CSV); `None`: the training ranges the model
    /// files recorded.
    pub data: Option<PathBuf>,
    /// Columns of `data` whose training range guards every thermal part.
    pub guard: Vec<String>,
    /// Fade width of temperature inputs outside their range (°C).
    pub fade_c: f64,
    /// Fade width of other inputs, as a fraction of their training range.
    pub fade_other: f64,
    /// The machine file to write (`-`: stdout).
    pub output: PathBuf,
}

impl BuildOptions {
    /// A machine file at `output` of `geometric` and `thermal`, envelopes from the model files,
    /// default fades.
    pub fn new(geometric: Option<PathBuf>, thermal: Vec<Part>, output: impl Into<PathBuf>) -> Self {
        BuildOptions {
            geometric,
            thermal,
            data: None,
            guard: Vec::new(),
            fade_c: FADE_TEMPERATURE_C,
            fade_other: FADE_OTHER_FRACTION,
            output: output.into(),
        }
    }
}

/// What [`build`] wrote.
#[derive(Debug, Clone, Serialize)]
pub struct BuildOutcome {
    /// The machine file as written (paths relative to it; thermal parts with their envelopes).
    pub file: MachineFile,
    pub output: PathBuf,
}

impl fmt::Display for BuildOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(g) = &self.file.geometric {
            writeln!(f, "geometric: {g}")?;
        }
        for p in &self.file.thermal {
            let ranges: Vec<String> = p
                .envelope
                .iter()
                .map(|(k, [lo, hi])| format!("{k} [{lo}, {hi}]"))
                .collect();
            writeln!(
                f,
                "thermal {} (sign {:+}): {}; envelope {}",
                p.axis,
                p.sign,
                p.model,
                ranges.join(", ")
            )?;
        }
        writeln!(f, "wrote {}", self.output.display())
    }
}

/// Builds the machine file, reads it back, and writes it. The output is checked (not an input)
/// before any model is read.
pub fn build(opts: &BuildOptions, _obs: &mut dyn Observer) -> Result<BuildOutcome> {
    if opts.thermal.is_empty() && opts.geometric.is_none() {
        return Err(Error::usage(
            "give --geometric, --thermal or both: the machine model sums them",
        ));
    }
    if !opts.guard.is_empty() && opts.thermal.is_empty() {
        return Err(Error::usage("--guard goes with --thermal"));
    }
    let parts: Vec<PartRequest> = opts
        .thermal
        .iter()
        .map(|p| PartRequest {
            axis: p.axis.clone(),
            model: p.model.clone(),
            sign: p.sign,
            guards: opts.guard.clone(),
        })
        .collect();
    let mut inputs: Vec<PathBuf> = parts.iter().map(|p| p.model.clone()).collect();
    inputs.extend(opts.geometric.clone());
    inputs.extend(opts.data.clone());
    let dest = OutputGuard::new(&inputs).check(&opts.output)?;
    let data = opts.data.as_deref().map(Table::read).transpose()?;
    let file = machine_build::build(&BuildRequest {
        geometric: opts.geometric.as_deref(),
        parts: &parts,
        data: data.as_ref(),
        fade: Fade {
            temperature_c: opts.fade_c,
            other_fraction: opts.fade_other,
        },
        output: &opts.output,
    })?;
    dest.write(machine_build::to_json(&file).as_bytes())?;
    Ok(BuildOutcome {
        file,
        output: opts.output.clone(),
    })
}

/// Options of [`replay`].
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Any model file mtec reads (a machine error model to follow a state).
    pub model: PathBuf,
    /// The controller's state log (CSV: time_min and the model's state inputs).
    pub state: PathBuf,
    /// Probe readings (CSV: time_min,[probe,]x_mm,y_mm,z_mm,ex_um,ey_um,ez_um; um).
    pub probes: PathBuf,
    /// Every compensated reading as CSV (`None`: not written).
    pub output: Option<PathBuf>,
}

/// What [`replay`] found: serialises to `mtec.machine-replay/1`, the command's `--json`.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayOutcome {
    /// RMS and largest error before and after, readings made worse, faded readings.
    #[serde(flatten)]
    pub summary: ReplaySummary,
    /// `mtec.machine-replay/1`.
    pub format: &'static str,
    /// The model as the compensator describes it.
    pub model: String,
    /// The model's state inputs (columns of the state log it reads).
    pub state_inputs: Vec<String>,
    /// The CSV of every reading, when written (not part of the JSON summary).
    #[serde(skip)]
    pub output: Option<PathBuf>,
    /// Every probe reading, compensated (the rows of the CSV; not part of the JSON summary).
    #[serde(skip)]
    pub samples: Vec<replay::ReplaySample>,
}

impl fmt::Display for ReplayOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.summary;
        writeln!(f, "{}", self.model)?;
        writeln!(
            f,
            "{} probe readings, {} state readings",
            s.readings, s.state_rows
        )?;
        writeln!(
            f,
            "  {:<7} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}",
            "", "RMS before", "RMS after", "max before", "max after", "comp. rate", "worst"
        )?;
        for (name, r) in [("X", &s.x), ("Y", &s.y), ("Z", &s.z), ("vector", &s.vector)] {
            writeln!(
                f,
                "  {name:<7} {:>9.3} um {:>9.3} um {:>9.3} um {:>9.3} um {:>10.1} % {:>10.1} %",
                r.rms_before_um,
                r.rms_after_um,
                r.max_before_um,
                r.max_after_um,
                100.0 * r.compensation_rate,
                100.0 * r.worst_reduction
            )?;
        }
        writeln!(
            f,
            "  readings made worse: {} (largest |e| increase {:.3} um); taken with the thermal part faded: {} (smallest weight {:.3})",
            s.worse, s.largest_worsening_um.max(0.0), s.faded, s.min_thermal_weight
        )?;
        if let Some(o) = &self.output {
            writeln!(f, "wrote {}", o.display())?;
        }
        Ok(())
    }
}

/// Compensates the recorded day through the real-time code path (`mtec_comp::replay`) and
/// writes every reading when asked. The output is checked (not an input) before any reading.
pub fn replay(opts: &ReplayOptions, _obs: &mut dyn Observer) -> Result<ReplayOutcome> {
    let dest = match &opts.output {
        Some(p) => Some(OutputGuard::new(&[&opts.model, &opts.state, &opts.probes]).check(p)?),
        None => None,
    };
    let model = mtec_comp::load_error_model(&opts.model)?;
    let mut comp = Compensator::new(model, CorrectionOptions::default());
    let state = Table::read(&opts.state)?;
    let probes = Table::read(&opts.probes)?;
    let (samples, summary) = replay::replay(&mut comp, &state, &probes)?;
    let provenance = format!(
        "{}; state {}; probes {}",
        comp.describe(),
        opts.state.display(),
        opts.probes.display()
    );
    if let Some(d) = &dest {
        d.write(replay::to_csv(&samples, &provenance).as_bytes())?;
    }
    Ok(ReplayOutcome {
        summary,
        format: "mtec.machine-replay/1",
        model: comp.describe(),
        state_inputs: comp.state_inputs().to_vec(),
        output: opts.output.clone(),
        samples,
    })
}
