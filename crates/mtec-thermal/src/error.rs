//! Why a thermal model cannot be read, fitted or applied.

/// The error of a thermal-model operation. Every variant says what the user can change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ThermalError {
    /// A column the model needs is not in the data (name it in the message).
    #[error("the data has no column `{0}`")]
    MissingColumn(String),
    /// A regressor does not vary, so its coefficient is undefined.
    #[error("`{0}` is constant over the fitted rows: it cannot be a regressor")]
    ConstantColumn(String),
    /// Too few rows for the number of parameters.
    #[error("{rows} rows cannot determine {params} parameters (need more rows than parameters)")]
    TooFewRows { rows: usize, params: usize },
    /// The regressors are linearly dependent (exactly or numerically).
    #[error("the regressors are linearly dependent (rank {rank} of {cols}); drop one of: {names}")]
    RankDeficient {
        rank: usize,
        cols: usize,
        names: String,
    },
    /// The data cannot determine the model (e.g. one ambient level, no position spread).
    #[error("{0}")]
    Undetermined(String),
    /// An option is out of range or inconsistent with the data.
    #[error("{0}")]
    Invalid(String),
    /// A nonlinear fit did not converge.
    #[error("the fit did not converge: {0}")]
    NotConverged(String),
}
