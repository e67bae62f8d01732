//! How a command fails: the workflow library's error (bad input or usage: exit 2 with a located
//! message; internal failure: exit 1).

use std::process::ExitCode;

/// The error of a subcommand: the same type the workflow library returns.
pub use mtec_workflow::Error as CliError;

/// Prints the error (if any) and turns it into the process exit code: 0, 2 or 1.
pub fn exit(result: Result<(), CliError>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is_users() => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
        Err(e) => {
            eprintln!("internal error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
