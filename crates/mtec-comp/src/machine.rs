//! The machine's error with a state: a geometric model plus thermal models that follow the
//! machine as it warms, as one [`ErrorModel`] (`mtec.machine-error/1`).
//!
//! e(p, state) = e_geo(p) + Σ_parts w · s_part · δ_part(state, p_axis) · u_axis  (µm)
//!
//! - e_geo: any static model mtec loads (grid map, kinematic model, BPNN), or none;
//! - δ_part: a fitted thermal model (`mtec.thermal-model/1`) run on line by
//!   [`mtec_thermal::ThermalStream`]: its drift along one machine axis (u_axis), with sign s_part
//!   (+1 when the model's target is the tool's displacement relative to the workpiece along
//!   +axis, the convention of every mtec error: actual = commanded + e);
//! - w: the envelope weight. Each input (temperature, spindle speed, ambient) has the range it
//!   had in the training data; the envelope may also name guards, columns the model does not
//!   read (the shop's air for a model of the spindle speed alone), which become state inputs
//!   that fade the part like its own inputs. Inside every range w = 1. An input a distance d outside its range
//!   gives w_i = max(0, 1 − d / width), width = `fade.temperature_c` (default 2 °C) for
//!   temperature columns (`*_c`) and `fade.other_fraction` (default 10 %) of the training range
//!   for other inputs; w = min_i w_i. A faded thermal part falls back to no thermal correction,
//!   the safe value: outside the data it was fitted on, a model can predict anything, and no
//!   correction never makes the machine worse than it is. The status of every update says which
//!   input is outside, so a controller can raise a message.
//!
//! The state advances through [`ErrorModel::update_state`] (readings in
//! [`ErrorModel::state_inputs`] order, the union of the parts' inputs in file order, each
//! part's guards after its inputs in name order); before the
//! first update the thermal part is zero. Updates do not allocate: every buffer is sized when the
//! file is loaded.

use crate::chain::{ChainKinematics, Pose, PoseError};
use crate::model::{StateError, StateStatus};
use crate::ErrorModel;
use mtec_io::InputError;
use mtec_thermal::{ModelFile, ThermalStream};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The format tag of a machine error model file.
pub const MACHINE_FORMAT: &str = "mtec.machine-error/1";

/// Widest fade of a temperature input outside its training range (°C).
pub const MAX_FADE_TEMPERATURE_C: f64 = 10.0;

/// Default fade width of a temperature input outside its training range (°C).
pub const FADE_TEMPERATURE_C: f64 = 2.0;
/// Default fade width of any other input, as a fraction of its training range.
pub const FADE_OTHER_FRACTION: f64 = 0.1;

/// How fast the thermal part fades outside the training envelope (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fade {
    #[serde(default = "fade_temperature")]
    pub temperature_c: f64,
    #[serde(default = "fade_other")]
    pub other_fraction: f64,
}

fn fade_temperature() -> f64 {
    FADE_TEMPERATURE_C
}
fn fade_other() -> f64 {
    FADE_OTHER_FRACTION
}

impl Default for Fade {
    fn default() -> Self {
        Fade {
            temperature_c: FADE_TEMPERATURE_C,
            other_fraction: FADE_OTHER_FRACTION,
        }
    }
}

/// One thermal part of the file: a thermal model file and the axis its drift acts along.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalPartSpec {
    /// `x`, `y` or `z`.
    pub axis: String,
    /// The thermal model file (`mtec.thermal-model/1`), relative to this file.
    pub model: String,
    /// +1 or −1 (module docs).
    #[serde(default = "plus_one")]
    pub sign: f64,
    /// Training range [min, max] of every input of the model.
    pub envelope: BTreeMap<String, [f64; 2]>,
}

fn plus_one() -> f64 {
    1.0
}

/// The file form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineFile {
    pub format: String,
    /// The static geometric model file, relative to this file; none: thermal only.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub geometric: Option<String>,
    #[serde(default)]
    pub thermal: Vec<ThermalPartSpec>,
    #[serde(default)]
    pub fade: Fade,
}

/// A loaded thermal part.
struct ThermalPart {
    axis: usize,
    sign: f64,
    stream: ThermalStream,
    /// For each input of the stream, its index in the machine's inputs.
    map: Vec<usize>,
    /// The stream's readings, gathered each update.
    scratch: Vec<f64>,
    /// Drift now (µm) when it does not depend on the position.
    drift_um: f64,
}

/// The machine error model (module docs).
pub struct MachineErrorModel {
    geometric: Option<Box<dyn ErrorModel>>,
    parts: Vec<ThermalPart>,
    inputs: Vec<String>,
    /// Training range of each input (intersection over the parts that read it).
    envelope: Vec<[f64; 2]>,
    /// Fade width of each input (module docs).
    width: Vec<f64>,
    weight: f64,
    source: String,
}

fn axis_index(name: &str) -> Option<usize> {
    match name {
        "x" | "X" => Some(0),
        "y" | "Y" => Some(1),
        "z" | "Z" => Some(2),
        _ => None,
    }
}

/// Reads a model file of any format (`crate::load::load_error_model`).
pub type ModelLoader = dyn Fn(&Path) -> Result<Box<dyn ErrorModel>, InputError>;

impl MachineErrorModel {
    /// Reads a `mtec.machine-error/1` file and the model files it names, each through `load_model`
    /// (`crate::load::load_error_model`, which reads any model format, this one included: the
    /// loader is passed in so that this module does not depend on the registry of formats).
    pub fn load(path: &Path, load_model: &ModelLoader) -> Result<MachineErrorModel, InputError> {
        let text = mtec_io::read_text(path)?;
        let file: MachineFile =
            serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
        let at = |needle: &str, msg: String| match text.find(needle) {
            Some(off) => {
                let (l, c) = mtec_io::line_col(&text, off);
                InputError::at(path, l, c, msg)
            }
            None => InputError::file(path, msg),
        };
        if file.format != MACHINE_FORMAT {
            return Err(at(
                "\"format\"",
                format!("`format` is `{}`, expected `{MACHINE_FORMAT}`", file.format),
            ));
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let geometric = match &file.geometric {
            Some(g) => {
                let m = load_model(&dir.join(g))?;
                if !m.state_inputs().is_empty() {
                    return Err(at(
                        "\"geometric\"",
                        "the geometric part must be a static model, not another machine model"
                            .into(),
                    ));
                }
                Some(m)
            }
            None => None,
        };
        let mut parts = Vec::new();
        for spec in &file.thermal {
            let mpath = dir.join(&spec.model);
            let mtext = mtec_io::read_text(&mpath)?;
            let mf: ModelFile =
                serde_json::from_str(&mtext).map_err(|e| mtec_io::json_error(&mpath, &e))?;
            mf.check_format()
                .map_err(|e| InputError::file(&mpath, e.to_string()))?;
            let stream = mf
                .model
                .stream()
                .map_err(|e| InputError::file(&mpath, e.to_string()))?;
            parts.push((spec, stream));
        }
        let source = format!("machine error model {}", path.display());
        MachineErrorModel::new(geometric, parts, file.fade, source).map_err(|m| {
            let needle = m
                .split('`')
                .nth(1)
                .map(|s| format!("\"{s}\""))
                .unwrap_or_default();
            at(&needle, m)
        })
    }

    /// Builds the model from its parts; messages name the offending field in backquotes.
    pub fn new(
        geometric: Option<Box<dyn ErrorModel>>,
        parts: Vec<(&ThermalPartSpec, ThermalStream)>,
        fade: Fade,
        source: String,
    ) -> Result<MachineErrorModel, String> {
        // a wider fade would keep the thermal part applied far outside its training range,
        // which the envelope guard is there to stop
        let within = |v: f64, max: f64| v > 0.0 && v <= max;
        if !(within(fade.temperature_c, MAX_FADE_TEMPERATURE_C) && within(fade.other_fraction, 1.0))
        {
            return Err(format!(
                "the fade widths (--fade-c {:e}, --fade-other {:e}) must be in (0, {MAX_FADE_TEMPERATURE_C}] °C and (0, 1] of the training range",
                fade.temperature_c, fade.other_fraction
            ));
        }
        let mut inputs: Vec<String> = Vec::new();
        let mut envelope: Vec<[f64; 2]> = Vec::new();
        let mut loaded = Vec::new();
        for (spec, stream) in parts {
            let axis = axis_index(&spec.axis).ok_or_else(|| {
                format!("`{}`: the axis of a thermal part is x, y or z", spec.axis)
            })?;
            if !(spec.sign == 1.0 || spec.sign == -1.0) {
                return Err(format!("`sign` is {}, it must be 1 or -1", spec.sign));
            }
            // a reading shared by two parts must be inside both ranges
            let mut add = |name: &String, [lo, hi]: [f64; 2]| -> Result<usize, String> {
                if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                    return Err(format!(
                        "`{name}`: the envelope [{lo}, {hi}] is not a range"
                    ));
                }
                Ok(match inputs.iter().position(|s| s == name) {
                    Some(j) => {
                        envelope[j] = [envelope[j][0].max(lo), envelope[j][1].min(hi)];
                        if envelope[j][0] > envelope[j][1] {
                            return Err(format!(
                                "`{name}`: the thermal parts' training ranges do not overlap"
                            ));
                        }
                        j
                    }
                    None => {
                        inputs.push(name.clone());
                        envelope.push([lo, hi]);
                        inputs.len() - 1
                    }
                })
            };
            let mut map = Vec::new();
            for name in stream.inputs() {
                let Some(&range) = spec.envelope.get(name) else {
                    return Err(format!(
                        "`envelope` of `{}` has no training range for input `{name}`: every \
                         input needs one (mtec machine build computes them from the training data)",
                        spec.model
                    ));
                };
                map.push(add(name, range)?);
            }
            // guards: envelope columns the model does not read still fade it (module docs)
            for (name, &range) in &spec.envelope {
                if !stream.inputs().contains(name) {
                    add(name, range)?;
                }
            }
            let n = map.len();
            loaded.push(ThermalPart {
                axis,
                sign: spec.sign,
                stream,
                map,
                scratch: vec![0.0; n],
                drift_um: 0.0,
            });
        }
        let width = inputs
            .iter()
            .zip(&envelope)
            .map(|(name, [lo, hi])| {
                if name.ends_with("_c") {
                    fade.temperature_c
                } else {
                    // a range of zero width (a constant input) fades over 10 % of its value
                    (fade.other_fraction * (hi - lo))
                        .max(fade.other_fraction * hi.abs().max(lo.abs()))
                        .max(1e-9)
                }
            })
            .collect();
        Ok(MachineErrorModel {
            geometric,
            parts: loaded,
            inputs,
            envelope,
            width,
            weight: 1.0,
            source,
        })
    }

    /// Training range [min, max] of each input, in [`ErrorModel::state_inputs`] order.
    pub fn envelope(&self) -> &[[f64; 2]] {
        &self.envelope
    }

    /// Thermal drift now along X, Y, Z (µm, before the envelope weight) at `p_mm`.
    pub fn thermal_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        let mut e = [0.0; 3];
        for part in &self.parts {
            let d = if part.stream.needs_position() {
                part.stream.predict_um(p_mm[part.axis])
            } else {
                part.drift_um
            };
            e[part.axis] += part.sign * d;
        }
        e
    }

    /// The envelope weight now (module docs).
    pub fn thermal_weight(&self) -> f64 {
        self.weight
    }
}

impl ErrorModel for MachineErrorModel {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        let mut e = match &self.geometric {
            Some(g) => g.error_um(p_mm),
            None => [0.0; 3],
        };
        if self.weight > 0.0 {
            let t = self.thermal_um(p_mm);
            for k in 0..3 {
                e[k] += self.weight * t[k];
            }
        }
        e
    }

    /// The geometric part's batch (a grid map's fast one) plus the thermal drift per point: the
    /// same arithmetic as [`ErrorModel::error_um`], point by point.
    fn eval_batch(&self, points: &[[f64; 3]], out: &mut [[f64; 3]]) {
        assert_eq!(
            points.len(),
            out.len(),
            "eval_batch: as many outputs as points"
        );
        match &self.geometric {
            Some(g) => g.eval_batch(points, out),
            None => out.fill([0.0; 3]),
        }
        if self.weight > 0.0 {
            for (e, p) in out.iter_mut().zip(points) {
                let t = self.thermal_um(*p);
                for k in 0..3 {
                    e[k] += self.weight * t[k];
                }
            }
        }
    }

    /// The geometric part's error at the pose plus the thermal drift, turned into the
    /// workpiece frame: a drift d along the machine axes moves the tool like a command change
    /// of d, so it reaches the workpiece frame through the chain's linear Jacobian J(θ)·d
    /// ([`ChainKinematics::linear_jacobian`]; the identity without rotary axes).
    fn pose_error(&self, pose: &Pose) -> PoseError {
        let mut e = match &self.geometric {
            Some(g) => g.pose_error(pose),
            None => PoseError {
                position_um: [0.0; 3],
                orientation_urad: None,
            },
        };
        if self.weight > 0.0 && !self.parts.is_empty() {
            let t = self.thermal_um(pose.linear_mm);
            let t = match self.kinematics().filter(|k| k.has_rotary()) {
                Some(k) => (k.linear_jacobian(pose.rotary_deg) * Vector3::from(t)).into(),
                None => t,
            };
            for (e, t) in e.position_um.iter_mut().zip(t) {
                *e += self.weight * t;
            }
        }
        e
    }

    fn kinematics(&self) -> Option<&ChainKinematics> {
        self.geometric.as_ref().and_then(|g| g.kinematics())
    }

    fn domain_mm(&self) -> Option<[[f64; 2]; 3]> {
        self.geometric.as_ref().and_then(|g| g.domain_mm())
    }

    fn describe(&self) -> String {
        let geo = self
            .geometric
            .as_ref()
            .map_or("no geometric part".to_string(), |g| g.describe());
        format!(
            "{} ({geo}; {} thermal part(s))",
            self.source,
            self.parts.len()
        )
    }

    fn state_inputs(&self) -> &[String] {
        &self.inputs
    }

    fn update_state(&mut self, readings: &[f64], dt_s: f64) -> Result<StateStatus, StateError> {
        if readings.len() != self.inputs.len() {
            return Err(StateError::Count {
                given: readings.len(),
                expected: self.inputs.len(),
            });
        }
        if let Some(index) = readings.iter().position(|v| !v.is_finite()) {
            return Err(StateError::NotFinite { index });
        }
        if !(dt_s >= 0.0 && dt_s.is_finite()) {
            return Err(StateError::TimeStep);
        }
        for part in &mut self.parts {
            for (s, &j) in part.scratch.iter_mut().zip(&part.map) {
                *s = readings[j];
            }
            // counts, finiteness and dt were checked above: the stream cannot refuse
            if part.stream.step(&part.scratch, dt_s / 60.0).is_ok() && !part.stream.needs_position()
            {
                part.drift_um = part.stream.predict_um(0.0);
            }
        }
        // w = min_i max(0, 1 − d_i / width_i)  (module docs)
        let mut status = StateStatus::default();
        let mut worst = 0.0;
        for (j, (&v, &[lo, hi])) in readings.iter().zip(&self.envelope).enumerate() {
            let d = (lo - v).max(v - hi);
            if d > 0.0 {
                let w = (1.0 - d / self.width[j]).max(0.0);
                if status.outside.is_none() || d / self.width[j] > worst {
                    worst = d / self.width[j];
                    status.outside = Some(j);
                }
                status.thermal_weight = status.thermal_weight.min(w);
            }
        }
        self.weight = status.thermal_weight;
        Ok(status)
    }
}
