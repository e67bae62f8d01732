//! The project file (TOML, docs/formats.md "Project TOML"): which stages to run on which files.

use serde::Deserialize;
use std::path::PathBuf;

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
    /// Limits the summary judges the results against (none: reported, not judged).
    #[serde(default)]
    pub tolerances: Tolerances,
}

/// `[tolerances]`: acceptance limits on magnitudes, in the unit their names end in. Every one
/// is optional; a figure without a limit is reported and not judged.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerances {
    /// ISO 230-2 axis values A, E, R, B and M.
    #[serde(default)]
    pub iso230_2: Iso230_2Tolerances,
    /// ISO 230-4 circular deviation G(b) and circular hysteresis H.
    #[serde(default)]
    pub circular: CircularTolerances,
    /// RMS of the thermal drift left after the model (measured − predicted), per [[thermal]].
    pub thermal_residual_rms_um: Option<f64>,
    /// RMS difference of the volumetric map from the check measurements.
    pub map_check_rms_um: Option<f64>,
    /// RMS of the volumetric error left after compensation (the demo's virtual machine).
    pub volumetric_after_rms_um: Option<f64>,
}

#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Iso230_2Tolerances {
    pub a_um: Option<f64>,
    pub e_um: Option<f64>,
    pub r_um: Option<f64>,
    pub b_um: Option<f64>,
    pub m_um: Option<f64>,
}

#[derive(Debug, Default, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircularTolerances {
    pub g_um: Option<f64>,
    pub h_um: Option<f64>,
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
    /// A rotary thermal model (`thermal fit --model cnn-lstm|bpnn` on the identified motions,
    /// `--sequence-by angle_deg`): the report adds its predicted ballbar readings.
    pub model: Option<PathBuf>,
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
    /// The elements of the identified kinematic model the programs and tables compensate:
    /// `all` (default), `key` (ranked by EFAST) or a list `EXX,EYY` (`compensate --elements`).
    pub elements: Option<String>,
}
