//! mtec-comp: compensation. Volumetric maps, correction values, G-code rewriting, controller
//! tables and the real-time evaluation API.
//!
//! What it is not for: identifying or fitting errors; it takes an [`ErrorModel`] from elsewhere.

pub mod correction;
pub mod load;
pub mod map;
pub mod model;
pub mod table;

pub use correction::{command_for_target, CorrectionError, CorrectionOptions};
pub use load::load_error_model;
pub use map::{GridLimits, GridMap, Outside};
pub use model::ErrorModel;
