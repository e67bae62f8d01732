//! mtec's errors as Python exceptions: located input errors keep their file, line and column.

use mtec_io::InputError as MtecInputError;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::path::Path;

pyo3::create_exception!(
    mtec,
    InputError,
    PyValueError,
    "An input (a file, or an array given in its place) is wrong; `str(e)` is `file:line:column: message`.\n\nAttributes: `file` (str), `line` and `column` (1-based int, or None when unknown), `message` (str). For arrays passed instead of a CSV file, `file` is `<arrays>`, `line` the 1-based row (index + 1) and `column` the 1-based position of the column in the mapping."
);

/// The `file` of an input error about arrays passed in place of a CSV file.
pub const ARRAYS: &str = "<arrays>";

/// Why a call failed: mtec's own error, or a Python error met while converting arguments.
pub enum Failure {
    Mtec(mtec_workflow::Error),
    Py(PyErr),
}

/// The result type of the functions behind the Python API.
pub type Result<T> = std::result::Result<T, Failure>;

impl From<mtec_workflow::Error> for Failure {
    fn from(e: mtec_workflow::Error) -> Self {
        Failure::Mtec(e)
    }
}
impl From<MtecInputError> for Failure {
    fn from(e: MtecInputError) -> Self {
        Failure::Mtec(e.into())
    }
}
impl From<mtec_io::OutputError> for Failure {
    fn from(e: mtec_io::OutputError) -> Self {
        Failure::Mtec(e.into())
    }
}
impl From<PyErr> for Failure {
    fn from(e: PyErr) -> Self {
        Failure::Py(e)
    }
}

/// A usage error (an option out of range, inconsistent arguments): `ValueError`.
pub fn usage(msg: impl Into<String>) -> Failure {
    Failure::Mtec(mtec_workflow::Error::usage(msg))
}

/// An internal failure (a serialisation that cannot fail on valid data): `RuntimeError`.
pub fn internal(e: impl std::fmt::Display) -> Failure {
    Failure::Mtec(mtec_workflow::Error::Internal(anyhow_msg(e)))
}

fn anyhow_msg(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::Error::msg(e.to_string())
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        match f {
            Failure::Py(e) => e,
            Failure::Mtec(mtec_workflow::Error::Input(e)) => input_error(e),
            Failure::Mtec(mtec_workflow::Error::Usage(m)) => PyValueError::new_err(m),
            Failure::Mtec(e @ mtec_workflow::Error::Internal(_)) => {
                PyRuntimeError::new_err(e.to_string())
            }
        }
    }
}

/// `mtec.InputError` with the location as attributes. Arrays have no header line: an error
/// located there (line 0, e.g. a missing column) is about the mapping as a whole.
fn input_error(mut e: MtecInputError) -> PyErr {
    if e.file == Path::new(ARRAYS) && e.line == Some(0) {
        e.line = None;
        e.column = None;
    }
    Python::attach(|py| {
        let err = InputError::new_err(e.to_string());
        let value = err.value(py);
        let set = || -> PyResult<()> {
            value.setattr("file", e.file.display().to_string())?;
            value.setattr("line", e.line)?;
            value.setattr("column", e.column)?;
            value.setattr("message", e.message.clone())?;
            Ok(())
        };
        match set() {
            Ok(()) => err,
            Err(other) => other,
        }
    })
}

/// The value of a closed set (`mtec_workflow::Choice`) named `name`, given for the argument
/// `what`; a usage error listing the names otherwise.
pub fn choice<C: mtec_workflow::Choice>(what: &str, name: &str) -> Result<C> {
    C::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = C::ALL.iter().map(|c| c.name()).collect();
        usage(format!(
            "{what} `{name}`: expected one of {}",
            names.join(", ")
        ))
    })
}

/// `-` is the command line's stdout; the module writes files only (argument `what`).
pub fn refuse_stdout(p: &std::path::Path, what: &str) -> Result<()> {
    if p == std::path::Path::new("-") {
        return Err(usage(format!(
            "`{what}` must be a file: `-` (stdout) is the command line's"
        )));
    }
    Ok(())
}
