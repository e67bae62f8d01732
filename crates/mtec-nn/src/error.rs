//! The errors of this crate: bad data or configuration (the caller's fault) and failures of the
//! tensor library (ours).

/// What went wrong while training, loading or evaluating a neural model.
#[derive(Debug, thiserror::Error)]
pub enum NnError {
    /// The data cannot train or evaluate the model (empty, inconsistent shapes, non-finite values).
    #[error("invalid data: {0}")]
    Data(String),
    /// A configuration value is out of range (hidden size 0, window 0, ...).
    #[error("invalid configuration: {0}")]
    Config(String),
    /// A model file is not a valid model of the expected format and version.
    #[error("invalid model file: {0}")]
    Model(String),
    /// A data file is wrong; the message names file, line and column.
    #[error("{0}")]
    Input(#[from] mtec_io::InputError),
    /// The tensor library failed (an internal error, not the user's input).
    #[error("tensor library: {0}")]
    Candle(#[from] candle_core::Error),
}

pub type Result<T> = std::result::Result<T, NnError>;

impl From<mtec_comp::bpnn::BpnnError> for NnError {
    fn from(e: mtec_comp::bpnn::BpnnError) -> NnError {
        match e {
            mtec_comp::bpnn::BpnnError::Data(m) => NnError::Data(m),
            mtec_comp::bpnn::BpnnError::Model(m) => NnError::Model(m),
        }
    }
}
