//! mtec-identify: Identification of error elements from measurements: line sets (9-line method), ballbar rotary-axis modes; identifiability and conditioning.

pub mod ballbar;
pub mod lines;
