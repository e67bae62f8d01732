//! The options of a fit, as plain data: [`FitOptions`], what `thermal fit` takes (each kind reads
//! the ones it uses, [`crate::kind::Kind::from_options`]), and [`BlockSpec`], how a record is cut
//! into validation blocks ([`crate::validate::duty_cycle_blocks`]). Their usage checks against
//! the kinds are in [`crate::registry`].

use serde::{Deserialize, Serialize};

/// How a record is cut into validation blocks.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BlockSpec {
    /// Fixed block length (min) from the start of the record; overrides the duty cycle.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub block_min: Option<f64>,
    /// Column whose steps mark duty-cycle changes (e.g. `spindle_rpm`), when the data has it.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub input: Option<String>,
}

/// The options of a fit, as `thermal fit` takes them; each kind reads the ones it uses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FitOptions {
    /// Sensor columns to use (all `_c` columns but `ambient_c` when empty).
    pub sensors: Vec<String>,
    /// Ridge parameter k (correlation form); `None`: chosen by the kind.
    pub k: Option<f64>,
    /// Add a first-order lag of each sensor (linear kinds).
    pub lag: bool,
    /// Validation block length, min (`None`: experiments, or the steps of `input`).
    pub block_min: Option<f64>,
    /// Largest number of temperature sensors (`None`: the kind's default).
    pub max_sensors: Option<usize>,
    /// The heat-source column (spindle speed, rpm).
    pub input: String,
    /// exp-ambient: the sensors whose first principal component is ΔT_up.
    pub up_sensors: Vec<String>,
    /// exp-ambient: the sensors whose first principal component is ΔT_nut.
    pub nut_sensors: Vec<String>,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            sensors: Vec::new(),
            k: None,
            lag: false,
            block_min: None,
            max_sensors: None,
            input: "spindle_rpm".into(),
            up_sensors: Vec::new(),
            nut_sensors: Vec::new(),
        }
    }
}

impl FitOptions {
    /// The validation blocks the options ask for.
    pub fn blocks(&self) -> BlockSpec {
        BlockSpec {
            block_min: self.block_min,
            input: Some(self.input.clone()),
        }
    }
}
