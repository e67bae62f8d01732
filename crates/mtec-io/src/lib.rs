//! mtec-io: the one place where mtec touches files.
//!
//! What it is for: reading CSV tables (with `#` comments, unit-suffixed column names), TOML and
//! JSON documents into typed values, with every failure reported as an [`InputError`] that names
//! the file, the line and the column; building every CSV output with the `csv` crate
//! ([`CsvWriter`]); writing every output through one routine (a file
//! atomically by temporary file + rename, a device, FIFO or `-` straight through, a symlink's
//! target beside that target) and refusing to overwrite an input.
//!
//! What it is not for: the meaning of a file. Which columns a measurement needs and what their
//! values must satisfy is decided by the crate that owns the measurement (`mtec-measure`,
//! `mtec-thermal`, ...), using the typed accessors of [`Table`].

mod csv_writer;
mod error;
mod fields;
pub mod notes;
pub mod number;
pub mod plausible;
mod stream;
mod table;
mod write;

pub use csv_writer::CsvWriter;
pub use error::{InputError, Located};
pub use stream::{CsvReader, Row, MAX_RECORD_BYTES};
pub use table::{Table, TableRow};
pub use write::{write_output, Destination, Output, OutputError, OutputGuard};

use std::path::Path;

/// Reads a whole file as UTF-8 text; non-UTF-8 bytes are reported with their line and column.
pub fn read_text(path: &Path) -> Result<String, InputError> {
    let bytes =
        std::fs::read(path).map_err(|e| InputError::file(path, format!("cannot read: {e}")))?;
    match String::from_utf8(bytes) {
        Ok(mut s) => {
            if s.starts_with('\u{feff}') {
                s.drain(..'\u{feff}'.len_utf8());
            }
            Ok(s)
        }
        Err(e) => {
            let valid = e.utf8_error().valid_up_to();
            let bytes = e.as_bytes();
            let line = bytes[..valid].iter().filter(|&&b| b == b'\n').count() + 1;
            let col = valid
                - bytes[..valid]
                    .iter()
                    .rposition(|&b| b == b'\n')
                    .map(|p| p + 1)
                    .unwrap_or(0)
                + 1;
            Err(InputError::at(
                path,
                line,
                col,
                format!("byte 0x{:02x} is not valid UTF-8 text", bytes[valid]),
            ))
        }
    }
}

/// Parses a TOML document into `T`; syntax and type errors carry the line and column of the span.
pub fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, InputError> {
    let text = read_text(path)?;
    parse_toml(path, &text)
}

/// Parses TOML text (already read from `path`) into `T`.
pub fn parse_toml<T: serde::de::DeserializeOwned>(
    path: &Path,
    text: &str,
) -> Result<T, InputError> {
    toml::from_str(text).map_err(|e| {
        let msg = e.message().to_string();
        match e.span() {
            Some(span) => {
                let (line, col) = line_col(text, span.start);
                InputError::at(path, line, col, msg)
            }
            None => InputError::file(path, msg),
        }
    })
}

/// Parses a JSON document into `T`; errors carry serde_json's line and column.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, InputError> {
    let text = read_text(path)?;
    parse_json(path, &text)
}

/// Parses the JSON text of `path` into `T`; errors carry serde_json's line and column.
pub fn parse_json<T: serde::de::DeserializeOwned>(
    path: &Path,
    text: &str,
) -> Result<T, InputError> {
    serde_json::from_str(text).map_err(|e| json_error(path, &e))
}

/// A serde_json error as a located input error of `path`.
pub fn json_error(path: &Path, e: &serde_json::Error) -> InputError {
    // serde_json appends " at line L column C"; the location is carried separately
    let msg = e.to_string();
    let msg = msg
        .rsplit_once(" at line ")
        .map_or(msg.clone(), |(m, _)| m.to_string());
    // serde_json says column 0 for "before the first character" (an error at the end of a
    // line or file); mtec's columns are 1-based
    InputError::at(path, e.line().max(1), e.column().max(1), msg)
}

/// 1-based line and column of a byte offset in `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rsplit('\n')
        .next()
        .map(|s| s.chars().count())
        .unwrap_or(0)
        + 1;
    (line, col)
}
