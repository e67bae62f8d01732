//! mtec-comp: compensation. Volumetric maps, correction values, G-code rewriting, controller
//! tables and the real-time evaluation API.
//!
//! What it is for: turning a predicted volumetric error into something that makes the machine cut
//! true. [`map`] builds a volumetric error map from a measured grid (trilinear interpolation, the
//! controller-style baseline); [`bpnn`] evaluates a fitted one-hidden-layer network (trained by
//! `mtec-nn`); [`load`] reads any model file by its `"format"`; [`correction`]
//! solves p + e(p) = target for the command p; [`table`] writes controller compensation tables
//! (LinuxCNC, Siemens CEC/LEC, FANUC, HEIDENHAIN, Beckhoff) with a checker of each format's rules;
//! [`machine`] sums a geometric model and thermal models that follow the machine's state
//! (temperatures, spindle speed) into one stateful [`ErrorModel`];
//! [`machine_build`] writes that model's file from fitted thermal models and their training
//! data; [`state_log`] brings a stateful model to the state of a log of readings (for offline
//! outputs), [`replay`] compensates a recorded day through the real-time path;
//! [`rt`] evaluates corrections each interpolation cycle without allocating (its C ABI lives in
//! the `mtec-rt` crate).
//!
//! What it is not for: identifying or fitting errors; it takes an [`ErrorModel`] from elsewhere.

pub mod bpnn;
pub mod chain;
pub mod correction;
pub mod gcode;
pub mod hand;
pub mod kinematic;
pub mod load;
pub mod machine;
pub mod machine_build;
pub mod map;
pub mod model;
pub mod pose;
pub mod replay;
pub mod rt;
pub mod state_log;
pub mod table;
pub mod thermal_offset;

pub use correction::{command_for_target, CorrectionError, CorrectionOptions};
pub use load::load_error_model;
pub use machine::MachineErrorModel;
pub use map::{GridLimits, GridMap, Outside};
pub use model::{eval_batch_threads, ErrorModel, StateError, StateStatus};
pub use pose::{command_for_pose, ChainKinematics, Pose, PoseError, PoseSolveOptions};
pub use rt::Compensator;
pub use state_log::{advance_through_log, LogStatus, WithState};
