//! A kinematic error model as a compensable [`ErrorModel`]: a machine and its identified error
//! set (JSON `{"format": "mtec.kinematic-model/1", "machine": {...}, "errors": {...}}`), evaluated
//! with the first-order HTM model (the identification side's model) at the commanded XYZ point.

use crate::ErrorModel;
use mtec_model::{ErrorSet, Formalism, Machine, MachineSpec, Order, VolumetricModel};
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

/// A three-axis kinematic error model.
#[derive(Debug, Clone)]
pub struct KinematicModel {
    model: VolumetricModel,
    source: String,
}

impl KinematicModel {
    /// Builds the model; the machine must have exactly the axes X, Y, Z.
    pub fn new(
        machine: &Machine,
        errors: &ErrorSet,
        source: impl Into<String>,
    ) -> Result<Self, String> {
        let xyz = [
            mtec_model::Axis::X,
            mtec_model::Axis::Y,
            mtec_model::Axis::Z,
        ];
        if machine.axes != xyz {
            return Err(format!(
                "compensation of a kinematic model needs a three-axis XYZ machine; `{}` has {:?}",
                machine.chain.text, machine.axes
            ));
        }
        errors.validate().map_err(|e| e.to_string())?;
        Ok(KinematicModel {
            model: VolumetricModel::new(machine, errors),
            source: source.into(),
        })
    }

    /// From the file form.
    pub fn from_file(f: KinematicFile, source: impl Into<String>) -> Result<Self, String> {
        let machine = Machine::from_spec(f.machine).map_err(|e| e.to_string())?;
        KinematicModel::new(&machine, &f.errors, source)
    }
}

impl ErrorModel for KinematicModel {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        self.model
            .error(&p_mm, Formalism::Htm, Order::FirstOrder)
            .position_um
    }
    fn describe(&self) -> String {
        format!(
            "{KINEMATIC_FORMAT} ({}) from {}",
            self.model.machine().chain.text,
            self.source
        )
    }
}
