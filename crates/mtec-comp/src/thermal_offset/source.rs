//! The thermal part of one axis, loaded for an offset update: from a machine error model file
//! (`mtec.machine-error/1`, which carries each part's axis, sign and training envelope), or from
//! a bare thermal model file (`mtec.thermal-model/1`) with the envelope taken from its training
//! log.

use super::OffsetError;
use crate::machine::{Fade, MachineFile, ThermalPartSpec, MACHINE_FORMAT};
use crate::table::Axis;
use crate::MachineErrorModel;
use mtec_io::{InputError, Table};
use mtec_thermal::Feature;
use mtec_thermal::{ModelFile, ThermalModel, MODEL_FORMAT};
use std::collections::BTreeMap;
use std::path::Path;

/// What the model's state needs from the log before "now".
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum History {
    /// The drift depends on the current readings only (temperatures as regressors).
    None,
    /// First-order lags: their state forgets its start as e^(−t/τ); `slowest_tau_min` is the
    /// largest τ of the model (at rest, for heat-input's switched lags).
    Lags { slowest_tau_min: f64 },
    /// Temperature rises from the first reading (exp-ambient): the first row must be the machine
    /// at rest, whatever the length of the log.
    FromStart,
}

impl History {
    /// The stricter of two requirements.
    fn and(self, other: History) -> History {
        match (self, other) {
            (History::FromStart, _) | (_, History::FromStart) => History::FromStart,
            (History::Lags { slowest_tau_min: a }, History::Lags { slowest_tau_min: b }) => {
                History::Lags {
                    slowest_tau_min: a.max(b),
                }
            }
            (l @ History::Lags { .. }, History::None) | (History::None, l) => l,
        }
    }

    /// The requirement of one fitted model (read from its public fields).
    pub fn of(model: &ThermalModel) -> History {
        let lags = |taus: Vec<f64>| match taus
            .into_iter()
            .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))))
        {
            Some(t) => History::Lags { slowest_tau_min: t },
            None => History::None,
        };
        match model {
            ThermalModel::Linear(m) => lags(
                m.features
                    .iter()
                    .filter_map(|f| match f {
                        Feature::Lag { tau_min, .. } => Some(*tau_min),
                        // the heat-input filter runs at tau_min while the input is on and
                        // rest_tau_min while it is off: the slower one bounds the history
                        Feature::HeatLag {
                            tau_min,
                            rest_tau_min,
                            ..
                        } => Some(tau_min.max(*rest_tau_min)),
                        _ => None,
                    })
                    .collect(),
            ),
            ThermalModel::HeatInput(m) => {
                let rest = m.rest_tau_factor.max(1.0);
                let mut taus: Vec<f64> = m.taus_min.iter().map(|t| t * rest).collect();
                taus.extend(m.ambient_lag_min);
                lags(taus)
            }
            ThermalModel::ExpAmbient(_) => History::FromStart,
        }
    }
}

/// Options of [`OffsetModel::load`].
#[derive(Debug, Clone, Copy)]
pub struct LoadOptions<'a> {
    /// The axis whose offset is updated.
    pub axis: Axis,
    /// For a bare thermal model: +1 when its target is the tool's displacement relative to the
    /// workpiece along +axis (mtec's error convention), −1 for the opposite. `None`: +1.
    pub sign: Option<f64>,
    /// For a bare thermal model: its training log, whose range of every input is the envelope.
    pub training: Option<&'a Path>,
}

/// The thermal drift of one axis as a stateful model, with what its state needs from the log.
pub struct OffsetModel {
    pub(super) machine: MachineErrorModel,
    pub(super) axis: Axis,
    pub(super) history: History,
    /// Whether the drift depends on the axis position (exp-ambient's k·x).
    pub(super) position_dependent: bool,
    pub(super) source: String,
}

impl OffsetModel {
    /// Loads `path` (module docs): only the thermal parts acting along `opts.axis` are kept (a
    /// geometric part is not an offset and is ignored).
    pub fn load(path: &Path, opts: LoadOptions) -> Result<OffsetModel, OffsetError> {
        let text = mtec_io::read_text(path)?;
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
        let format = value.get("format").and_then(|f| f.as_str()).unwrap_or("");
        let dir = path.parent().unwrap_or(Path::new("."));
        let (specs, fade) = match format {
            MACHINE_FORMAT => {
                if opts.sign.is_some() || opts.training.is_some() {
                    return Err(OffsetError::Usage(
                        "--sign and --training go with a bare thermal model file; a machine \
                         error model file gives each thermal part's sign and envelope"
                            .into(),
                    ));
                }
                let file: MachineFile =
                    serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
                let specs: Vec<(ThermalPartSpec, ModelFile)> = file
                    .thermal
                    .into_iter()
                    .filter(|s| Axis::parse(&s.axis) == Some(opts.axis))
                    .map(|s| Ok((s.clone(), read_model(&dir.join(&s.model))?)))
                    .collect::<Result<_, InputError>>()?;
                if specs.is_empty() {
                    return Err(InputError::file(
                        path,
                        format!(
                            "no thermal part acts along {}: the file's `thermal` entries name other axes (or none)",
                            opts.axis.letter()
                        ),
                    )
                    .into());
                }
                (specs, file.fade)
            }
            MODEL_FORMAT => {
                let model = read_model(path)?;
                let training = opts.training.ok_or_else(|| {
                    InputError::file(
                        path,
                        "a bare thermal model carries no training envelope: give --training \
                         T.csv (the log it was fitted on), or a machine error model file \
                         (mtec.machine-error/1) that names the model, its axis, sign and envelope",
                    )
                })?;
                let sign = opts.sign.unwrap_or(1.0);
                let stream = model
                    .model
                    .stream()
                    .map_err(|e| InputError::file(path, e.to_string()))?;
                let envelope = envelope_of(training, stream.inputs())?;
                let spec = ThermalPartSpec {
                    axis: opts.axis.letter().to_string(),
                    model: path.display().to_string(),
                    sign,
                    envelope,
                };
                (vec![(spec, model)], Fade::default())
            }
            other => {
                let at = text.find("\"format\"").map(|o| mtec_io::line_col(&text, o));
                let msg = format!(
                    "`format` is `{other}`: thermal-offset reads a machine error model \
                     ({MACHINE_FORMAT}) or a thermal model ({MODEL_FORMAT})"
                );
                return Err(match at {
                    Some((l, c)) => InputError::at(path, l, c, msg),
                    None => InputError::file(path, msg),
                }
                .into());
            }
        };
        let history = specs
            .iter()
            .fold(History::None, |h, (_, m)| h.and(History::of(&m.model)));
        let mut parts = Vec::new();
        for (spec, m) in &specs {
            let stream = m.model.stream().map_err(|e| {
                InputError::file(&dir.join(&spec.model), format!("cannot run on line: {e}"))
            })?;
            parts.push((spec, stream));
        }
        let position_dependent = parts.iter().any(|(_, s)| s.needs_position());
        let source = format!("{}", path.display());
        let machine = MachineErrorModel::new(None, parts, fade, source.clone())
            .map_err(|m| InputError::file(path, m))?;
        Ok(OffsetModel {
            machine,
            axis: opts.axis,
            history,
            position_dependent,
            source,
        })
    }

    /// The readings the model takes (columns of the temperature log), in order.
    pub fn inputs(&self) -> &[String] {
        use crate::ErrorModel;
        self.machine.state_inputs()
    }

    /// What the state needs from the log.
    pub fn history(&self) -> History {
        self.history
    }

    /// Whether the drift depends on the axis position (exp-ambient: e = k·x + b).
    pub fn position_dependent(&self) -> bool {
        self.position_dependent
    }

    /// The axis whose offset is updated.
    pub fn axis(&self) -> Axis {
        self.axis
    }

    /// The model file, for provenance lines.
    pub fn source(&self) -> &str {
        &self.source
    }
}

fn read_model(path: &Path) -> Result<ModelFile, InputError> {
    let text = mtec_io::read_text(path)?;
    let m: ModelFile = serde_json::from_str(&text).map_err(|e| mtec_io::json_error(path, &e))?;
    m.check_format()
        .map_err(|e| InputError::file(path, e.to_string()))?;
    Ok(m)
}

/// [min, max] of every input over the training log.
fn envelope_of(
    training: &Path,
    inputs: &[String],
) -> Result<BTreeMap<String, [f64; 2]>, InputError> {
    let t = Table::read(training)?;
    let mut out = BTreeMap::new();
    for name in inputs {
        let v = t.f64_column(name)?;
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        out.insert(name.clone(), [lo, hi]);
    }
    Ok(out)
}
