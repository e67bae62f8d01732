//! ISO 230-4 circular tests of two linear axes (ballbar traces): the file reader, the
//! standard's values, and the ballbar diagnostics.

pub mod diagnostics;
pub mod iso230_4;
pub mod trace;

pub use diagnostics::{diagnose, Diagnostic, Diagnostics, DiagnosticsConfig, DiagnosticsError};
pub use iso230_4::{evaluate, fit_circle, radii_about, Iso230_4, LsqCircle};
pub use trace::{
    circle_fit_condition, circle_fit_condition_of_span, Arc, CircularTrace, Plane, Sample,
    TraceOptions, Travel, MIN_ARC_DEG,
};
