//! A kinematic error model as a compensable [`ErrorModel`]: a machine and its identified error
//! set (JSON `{"format": "mtec.kinematic-model/1", "machine": {...}, "errors": {...}}`), evaluated
//! at the commanded pose of every axis: the chain must have X, Y and Z and may have any of the
//! rotary axes A, B, C, on the workpiece side (tables: `WCXYFZT`, `WCAYFXZT`) or the tool side
//! (heads). See [`crate::pose`] for the conventions.

use crate::chain::{ChainKinematics, Pose, PoseError};
use crate::ErrorModel;
use mtec_model::{Axis, ErrorSet, Formalism, Machine, MachineSpec, Order, VolumetricModel};
use serde::{Deserialize, Serialize};

/// The format tag of a kinematic model file.
pub const KINEMATIC_FORMAT: &str = "mtec.kinematic-model/1";

/// The file form.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct KinematicFile {
    pub format: String,
    pub machine: MachineSpec,
    pub errors: ErrorSet,
}

impl KinematicFile {
    /// The file of a machine and its (identified) error set: what `identify lines
    /// --kinematic-model` and `mtec run` write, and `compensate` and mtec-rt read. Refused here,
    /// before anything is written, when the pair would not load as a [`KinematicModel`] (a chain
    /// without X, Y and Z, an invalid error set), so no unloadable model file is ever written.
    pub fn new(machine: &Machine, errors: &ErrorSet) -> Result<KinematicFile, String> {
        KinematicModel::new(machine, errors, "")?;
        Ok(KinematicFile {
            format: KINEMATIC_FORMAT.to_string(),
            machine: machine.to_spec(),
            errors: errors.clone(),
        })
    }

    /// The JSON text of the file (pretty-printed, as the other mtec model files).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }
}

/// A kinematic error model: a chain with X, Y, Z and any rotary axes.
#[derive(Debug, Clone)]
pub struct KinematicModel {
    model: VolumetricModel,
    kinematics: ChainKinematics,
    source: String,
}

impl KinematicModel {
    /// Builds the model; the machine must have X, Y and Z (see [`ChainKinematics::new`]).
    pub fn new(
        machine: &Machine,
        errors: &ErrorSet,
        source: impl Into<String>,
    ) -> Result<Self, String> {
        let kinematics = ChainKinematics::new(machine)?;
        errors.validate().map_err(|e| e.to_string())?;
        Ok(KinematicModel {
            model: VolumetricModel::new(machine, errors),
            kinematics,
            source: source.into(),
        })
    }

    /// From the file form.
    pub fn from_file(f: KinematicFile, source: impl Into<String>) -> Result<Self, String> {
        let machine = Machine::from_spec(f.machine).map_err(|e| e.to_string())?;
        KinematicModel::new(&machine, &f.errors, source)
    }

    /// The compiled chain with its errors.
    pub fn volumetric(&self) -> &VolumetricModel {
        &self.model
    }
}

impl ErrorModel for KinematicModel {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        self.pose_error(&Pose::linear(p_mm)).position_um
    }
    /// A chain without rotary axes takes the first-order HTM model (the identification side's
    /// model; it differs from the exact one by about ε²·L, 0.01 µm for errors of 100 µrad over
    /// a metre); a chain with rotary axes the exact HTM product.
    fn pose_error(&self, pose: &Pose) -> PoseError {
        let q = self.kinematics.pose_vector(pose);
        let q = &q[..self.kinematics.n_axes()];
        let order = if self.kinematics.has_rotary() {
            Order::Exact
        } else {
            Order::FirstOrder
        };
        let v = self.model.error(q, Formalism::Htm, order);
        PoseError {
            position_um: v.position_um,
            orientation_urad: Some(v.orientation_urad),
        }
    }
    fn kinematics(&self) -> Option<&ChainKinematics> {
        Some(&self.kinematics)
    }
    /// The travels of X, Y and Z: the errors were identified over them.
    fn domain_mm(&self) -> Option<[[f64; 2]; 3]> {
        let m = self.model.machine();
        Some([m.travel(Axis::X), m.travel(Axis::Y), m.travel(Axis::Z)])
    }
    fn describe(&self) -> String {
        format!(
            "{KINEMATIC_FORMAT} ({}) from {}",
            self.model.machine().chain.text,
            self.source
        )
    }
}
