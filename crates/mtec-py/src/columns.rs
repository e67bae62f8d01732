//! Tabular inputs: a CSV path, or a mapping of column name to 1-D array turned into the same
//! [`Table`] the CSV reader makes, so that both go through the library's one validation.
//!
//! An array-built table has the path [`ARRAYS`], the header on line 0 and row `i` on line
//! `i + 1`; numbers are written with Rust's shortest round-trip form, so the reader gets back
//! exactly the `float64` it was given (NaN and infinities stay refusable, located).

use crate::errors::{usage, Result, ARRAYS};
use mtec_io::{Table, TableRow};
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::path::{Path, PathBuf};

/// The files a table was read from (none for arrays): outputs may not overwrite them.
pub fn file_inputs(t: &Table) -> Vec<PathBuf> {
    if t.path == Path::new(ARRAYS) {
        Vec::new()
    } else {
        vec![t.path.clone()]
    }
}

/// Where a table came from: the path that located errors name.
pub fn read_table(obj: &Bound<'_, PyAny>, what: &str) -> Result<Table> {
    match as_path(obj)? {
        Some(p) => Ok(Table::read(&p)?),
        None => table_from_mapping(obj, what),
    }
}

/// The path of a `str` or `os.PathLike`, or `None` for anything else.
pub fn as_path(obj: &Bound<'_, PyAny>) -> Result<Option<PathBuf>> {
    if obj.is_instance_of::<PyString>() || obj.hasattr("__fspath__")? {
        return Ok(Some(obj.extract::<PathBuf>()?));
    }
    Ok(None)
}

/// A required path argument.
pub fn path_arg(obj: &Bound<'_, PyAny>, what: &str) -> Result<PathBuf> {
    as_path(obj)?.ok_or_else(|| usage(format!("`{what}` must be a path (str or os.PathLike)")))
}

fn table_from_mapping(obj: &Bound<'_, PyAny>, what: &str) -> Result<Table> {
    if !obj.hasattr("keys")? {
        return Err(usage(format!(
            "`{what}` must be a CSV path or a mapping of column name to 1-D array (dict, pandas.DataFrame), not {}",
            obj.get_type().name()?
        )));
    }
    let np = obj.py().import("numpy")?;
    let mut header = Vec::new();
    let mut cols: Vec<Vec<String>> = Vec::new();
    for key in obj.call_method0("keys")?.try_iter()? {
        let key = key?;
        let name: String = key
            .extract()
            .map_err(|_| usage(format!("`{what}`: column names must be str")))?;
        let arr = np.call_method1("asarray", (obj.get_item(&key)?,))?;
        let ndim: usize = arr.getattr("ndim")?.extract()?;
        if ndim != 1 {
            return Err(usage(format!(
                "`{what}`: column `{name}` must be 1-D, it has {ndim} dimensions"
            )));
        }
        cols.push(cells(&np, &arr)?);
        header.push(name);
    }
    if header.is_empty() {
        return Err(usage(format!("`{what}` has no columns")));
    }
    let n = cols[0].len();
    if let Some((name, c)) = header.iter().zip(&cols).find(|(_, c)| c.len() != n) {
        return Err(usage(format!(
            "`{what}`: column `{name}` has {} values, column `{}` has {n}: every column needs one value per row",
            c.len(),
            header[0]
        )));
    }
    if n == 0 {
        return Err(usage(format!("`{what}` has no rows")));
    }
    let rows = (0..n)
        .map(|i| TableRow {
            line: i + 1,
            fields: cols.iter().map(|c| c[i].clone()).collect(),
        })
        .collect();
    Ok(Table {
        path: Path::new(ARRAYS).to_path_buf(),
        header,
        header_line: 0,
        rows,
        comments: Vec::new(),
        comment_lines: Vec::new(),
        notes: Vec::new(),
    })
}

/// The cells of a 1-D array as the text a CSV file would hold.
fn cells(np: &Bound<'_, PyModule>, arr: &Bound<'_, PyAny>) -> Result<Vec<String>> {
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    Ok(match kind.as_str() {
        "b" | "i" | "u" => {
            let v: Vec<i64> = arr
                .call_method1("astype", (np.getattr("int64")?,))?
                .call_method0("tolist")?
                .extract()?;
            v.iter().map(i64::to_string).collect()
        }
        "f" => {
            let v: Vec<f64> = arr
                .call_method1("astype", (np.getattr("float64")?,))?
                .call_method0("tolist")?
                .extract()?;
            v.iter().map(|x| format!("{x}")).collect()
        }
        _ => arr
            .call_method0("tolist")?
            .try_iter()?
            .map(|x| Ok(x?.str()?.to_cow()?.trim().to_string()))
            .collect::<PyResult<Vec<String>>>()?,
    })
}
