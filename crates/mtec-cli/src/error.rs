//! How a command fails: bad input (exit 2, located message) or internal failure (exit 1).

use mtec_io::InputError;
use std::process::ExitCode;

/// The error of a subcommand.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// An input file or option is wrong; the message names file, line and column.
    #[error("{0}")]
    Input(#[from] InputError),
    /// The command line itself is inconsistent (an option value out of range, ...).
    #[error("{0}")]
    Usage(String),
    /// Something failed that is not the user's input (an output cannot be written, ...).
    #[error("{0:#}")]
    Internal(#[from] anyhow::Error),
}

impl CliError {
    pub fn usage(msg: impl Into<String>) -> Self {
        CliError::Usage(msg.into())
    }
}

/// An output mtec will not write (an input, a directory, a block device) is the user's mistake
/// (exit 2); a failed write is not (exit 1).
impl From<mtec_io::OutputError> for CliError {
    fn from(e: mtec_io::OutputError) -> Self {
        match e {
            mtec_io::OutputError::Refused(m) => CliError::Usage(m),
            e @ mtec_io::OutputError::Io { .. } => CliError::Internal(e.into()),
        }
    }
}

impl From<std::io::Error> for CliError {
    fn from(e: std::io::Error) -> Self {
        CliError::Internal(e.into())
    }
}

/// Prints the error (if any) and turns it into the process exit code: 0, 2 or 1.
pub fn exit(result: Result<(), CliError>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ (CliError::Input(_) | CliError::Usage(_))) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
        Err(e) => {
            eprintln!("internal error: {e}");
            ExitCode::from(1)
        }
    }
}
