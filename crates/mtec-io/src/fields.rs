//! The rules of a CSV header and its fields that the streaming reader and [`crate::Table`]
//! share: the dialect (commas, or a spreadsheet export's semicolons or tabs with decimal
//! commas), the header's checks, column lookup by name with the unit-suffix hint, and the row
//! type. Below both readers: no reading here.

use crate::error::InputError;
use std::path::Path;

/// One data row: its fields as text and the line of the file it came from (1-based).
#[derive(Debug, Clone, PartialEq)]
pub struct TableRow {
    pub line: usize,
    pub fields: Vec<String>,
}

/// The field separator of a file, decided from its header.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Dialect {
    Comma,
    /// Semicolons or tabs, with decimal commas in numbers.
    Spreadsheet(char),
}

/// `-1,25`, `3,5e-3`: a number with a decimal comma (digits on both sides, one comma).
pub(crate) fn decimal_comma(f: &str) -> Option<String> {
    let (int, frac) = f.split_once(',')?;
    let int_digits = int.strip_prefix(['-', '+']).unwrap_or(int);
    let (frac_digits, exp) = match frac.find(['e', 'E']) {
        Some(i) => (&frac[..i], &frac[i + 1..]),
        None => (frac, "0"),
    };
    let exp_digits = exp.strip_prefix(['-', '+']).unwrap_or(exp);
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (all_digits(int_digits) && all_digits(frac_digits) && all_digits(exp_digits))
        .then(|| f.replacen(',', ".", 1))
}

/// Index of column `name` in `header`, or an error that says what is there instead.
pub(crate) fn column_index(
    path: &Path,
    header: &[String],
    header_line: usize,
    name: &str,
) -> Result<usize, InputError> {
    if let Some(i) = header.iter().position(|h| h == name) {
        return Ok(i);
    }
    let stem = stem_of(name);
    if let Some((i, other)) = header
        .iter()
        .enumerate()
        .find(|(_, h)| stem_of(h) == stem && h.as_str() != name)
    {
        return Err(InputError::at(
            path,
            header_line,
            i + 1,
            format!("column `{other}` has the wrong unit suffix: mtec expects `{name}` (units are part of the column name: docs/formats.md, Rules for every file)"),
        ));
    }
    Err(InputError::line(
        path,
        header_line,
        format!(
            "missing column `{name}`; the header has: {}",
            header.join(", ")
        ),
    ))
}

fn stem_of(name: &str) -> &str {
    const SUFFIXES: [&str; 10] = [
        "_mm", "_deg", "_um", "_urad", "_c", "_min", "_s", "_in", "_rad", "_k",
    ];
    for s in SUFFIXES {
        if let Some(stem) = name.strip_suffix(s) {
            return stem;
        }
    }
    name
}

/// Comma-separated unless the header has no comma and has semicolons (or tabs).
pub(crate) fn detect_dialect(header_line: &str) -> Dialect {
    if header_line.contains(',') {
        Dialect::Comma
    } else if header_line.contains(';') {
        Dialect::Spreadsheet(';')
    } else if header_line.contains('\t') {
        Dialect::Spreadsheet('\t')
    } else {
        Dialect::Comma
    }
}

pub(crate) fn check_header(
    path: &Path,
    line_no: usize,
    line: &str,
    fields: &[String],
) -> Result<(), InputError> {
    if fields.len() == 1 {
        for (d, name) in [('|', "bars")] {
            if line.contains(d) {
                return Err(InputError::line(
                    path,
                    line_no,
                    format!("the header is separated by {name}: mtec reads comma-separated files (or semicolon- or tab-separated spreadsheet exports)"),
                ));
            }
        }
    }
    for (i, f) in fields.iter().enumerate() {
        if f.is_empty() {
            return Err(InputError::at(
                path,
                line_no,
                i + 1,
                "empty column name in the header",
            ));
        }
        if let Some(j) = fields[..i].iter().position(|g| g == f) {
            return Err(InputError::at(
                path,
                line_no,
                i + 1,
                format!(
                    "column `{f}` appears twice (columns {} and {})",
                    j + 1,
                    i + 1
                ),
            ));
        }
    }
    Ok(())
}
