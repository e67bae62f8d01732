//! mtec-model: the kinematic error model of a machine tool.
//!
//! What it is for: naming error elements as ISO 230-1 does ([`ErrorElement`]), describing each as
//! a function of its axis position ([`ErrorFunction`], grouped in an [`ErrorSet`]), describing a
//! machine's chain ([`Machine`], from TOML), and computing the volumetric error of the tool tip
//! relative to the workpiece ([`VolumetricModel`]) with homogeneous transformation matrices or a
//! product of exponentials, exact or first-order; plus the first-order observation model
//! ([`VolumetricModel::first_order_jacobian`]) that identification and sensitivity build on.
//!
//! What it is not for: files (no I/O but serde), measurement, fitting.
//! Sign conventions and the order of ideal and error motion: see [`kinematics`].

pub mod element;
pub mod errors;
pub mod function;
pub mod htm;
pub mod kinematics;
pub mod line_design;
pub mod machine;
pub mod poe;

pub use element::{location_elements, motion_elements, three_axis_elements, Axis, ErrorElement};
pub use errors::{ErrorSet, ERRORS_FORMAT};
pub use function::{ErrorFunction, Shape, Temperatures, ThermalTerm};
pub use htm::Htm;
pub use kinematics::{Formalism, Order, Volumetric, VolumetricModel};
pub use line_design::{line_preset, LineSpec, LINE_PRESETS};
pub use machine::{AxisSpec, Chain, ErrorFrame, Machine, MachineSpec};
pub use poe::Twist;
