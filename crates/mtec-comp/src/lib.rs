//! mtec-comp: compensation. Volumetric maps, correction values, G-code rewriting, controller
//! tables and the real-time evaluation API.
//!
//! What it is not for: identifying or fitting errors; it takes an [`ErrorModel`] from elsewhere.

pub mod gcode;
pub mod model;

pub use model::ErrorModel;
