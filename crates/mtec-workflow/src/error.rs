//! How a job fails: bad input (located message), a usage error, or an internal failure.

use mtec_io::InputError;

/// The error of a workflow job.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An input file is wrong; the message names file, line and column.
    #[error("{0}")]
    Input(#[from] InputError),
    /// The options are inconsistent (a value out of range, a missing companion option, ...).
    #[error("{0}")]
    Usage(String),
    /// Something failed that is not the user's input (an output cannot be written, ...).
    #[error("{0:#}")]
    Internal(#[from] anyhow::Error),
}

/// The result of a workflow job.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn usage(msg: impl Into<String>) -> Self {
        Error::Usage(msg.into())
    }

    /// The process exit code a command-line front gives this error: 2 for the user's mistakes
    /// (input or usage), 1 for internal failures.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Input(_) | Error::Usage(_) => 2,
            Error::Internal(_) => 1,
        }
    }

    /// True when the user can fix it (exit code 2).
    pub fn is_users(&self) -> bool {
        self.exit_code() == 2
    }
}

/// An output mtec will not write (an input, a directory, a block device) is the user's mistake;
/// a failed write is not.
impl From<mtec_io::OutputError> for Error {
    fn from(e: mtec_io::OutputError) -> Self {
        match e {
            mtec_io::OutputError::Refused(m) => Error::Usage(m),
            e @ mtec_io::OutputError::Io { .. } => Error::Internal(e.into()),
        }
    }
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::Internal(e.into())
    }
}

impl From<serde_json::Error> for Error {
    fn from(e: serde_json::Error) -> Self {
        Error::Internal(e.into())
    }
}
