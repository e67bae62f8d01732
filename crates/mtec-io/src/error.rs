//! The input error: what went wrong, and where (file, line, column).

use std::fmt;
use std::path::{Path, PathBuf};

/// A problem with an input file, located as precisely as it can be.
///
/// Displayed as `file:line:column: message` (line and column omitted when unknown), the form
/// editors and terminals turn into links. The CLI maps it to exit code 2.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub message: String,
}

impl InputError {
    /// An error about the whole file (cannot be read, is empty, ...).
    pub fn file(path: &Path, message: impl Into<String>) -> Self {
        InputError {
            file: path.to_path_buf(),
            line: None,
            column: None,
            message: message.into(),
        }
    }
    /// An error at a line (1-based) with no particular column.
    pub fn line(path: &Path, line: usize, message: impl Into<String>) -> Self {
        InputError {
            file: path.to_path_buf(),
            line: Some(line),
            column: None,
            message: message.into(),
        }
    }
    /// An error at a line and column (both 1-based; for CSV the column is the field number).
    pub fn at(path: &Path, line: usize, column: usize, message: impl Into<String>) -> Self {
        InputError {
            file: path.to_path_buf(),
            line: Some(line),
            column: Some(column),
            message: message.into(),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for InputError {}

/// Converts a domain error that knows no file into an [`InputError`] about `path`.
pub trait Located<T> {
    /// Attach the file (and nothing more precise) to an error.
    fn in_file(self, path: &Path) -> Result<T, InputError>;
}

impl<T, E: fmt::Display> Located<T> for Result<T, E> {
    fn in_file(self, path: &Path) -> Result<T, InputError> {
        self.map_err(|e| InputError::file(path, e.to_string()))
    }
}
