//! What can go wrong in a sensitivity analysis, as values (never panics on user data).

/// The error of a sampling or analysis step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    /// A problem definition is unusable (no inputs, a bad distribution, duplicated names, ...).
    #[error("invalid problem: {0}")]
    Problem(String),
    /// Settings that the method cannot work with (too few samples for the interference factor, ...).
    #[error("invalid settings: {0}")]
    Settings(String),
    /// Outputs that do not match the sample design (wrong length, NaN, ...).
    #[error("invalid model outputs: {0}")]
    Outputs(String),
}
