//! mtec-measure: measurement files and their standard statistics.
//!
//! What it is for: reading and validating the measurement files of SPEC §4 that describe one
//! axis or one pair of axes (errors located by file, line and column), and evaluating them the
//! way the standards say:
//! - [`positioning`] + [`iso230_2`]: bidirectional positioning runs of a linear axis (laser
//!   interferometer), ISO 230-2:2014 statistics and the VDI/DGQ 3441 values;
//! - [`circular`]: ISO 230-4 circular tests (ballbar traces): least-squares circle, circular
//!   deviation G, hysteresis H, and the ballbar diagnostics (scale mismatch, squareness,
//!   backlash, lateral play, reversal spikes, cyclic error, servo mismatch, straightness) fitted
//!   by linear least squares on physically derived basis functions.
//!
//! What it is not for: identifying the error elements of a whole machine (that is
//! `mtec-identify`), simulating measurements (`mtec-sim`) or drawing plots (`mtec-report`).

pub mod air;
pub mod circular;
pub mod iso230_2;
pub mod positioning;

pub use iso230_2::{evaluate as evaluate_iso230_2, vdi3441, Iso230_2, Standard, Vdi3441};
pub use positioning::{Approach, PositioningData};
