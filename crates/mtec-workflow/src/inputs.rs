//! Readers shared by several jobs: machine TOML, error-set JSON, pose CSV.

use mtec_io::{read_json, read_toml, InputError, Table};
use mtec_model::{Axis, ErrorSet, Machine, MachineSpec};
use std::path::Path;

/// Reads and validates a machine description.
pub fn read_machine(path: &Path) -> Result<Machine, InputError> {
    let spec: MachineSpec = read_toml(path)?;
    Machine::from_spec(spec).map_err(|e| InputError::file(path, e.to_string()))
}

/// Reads an error set: a `mtec.errors/1` file, or a simulation's `truth.json` (its `errors`).
pub fn read_errors(path: &Path) -> Result<ErrorSet, InputError> {
    let v: serde_json::Value = read_json(path)?;
    let set: ErrorSet = if v.get("format").and_then(|f| f.as_str()) == Some("mtec.truth/1") {
        serde_json::from_value(v.get("errors").cloned().unwrap_or_default()).map_err(|e| {
            InputError::file(
                path,
                format!("the truth's `errors` is not an error set: {e}"),
            )
        })?
    } else {
        // parse the text again as an error set so that mistakes are located (line, column)
        read_json(path).map_err(|e| InputError {
            message: format!("not an error set: {}", e.message),
            ..e
        })?
    };
    set.validate()
        .map_err(|e| InputError::file(path, e.to_string()))?;
    Ok(set)
}

/// The pose column of an axis: `x_mm` for X, `c_deg` for C.
pub fn pose_column(a: Axis) -> String {
    let l = a.letter().to_ascii_lowercase();
    if a.is_rotary() {
        format!("{l}_deg")
    } else {
        format!("{l}_mm")
    }
}

/// Reads commanded poses (one column per machine axis), checking they lie within the travels
/// (a point beyond a travel is refused: the error functions are not known there).
pub fn read_poses(path: &Path, machine: &Machine) -> Result<Vec<Vec<f64>>, InputError> {
    let t = Table::read(path)?;
    let cols: Vec<usize> = machine
        .axes
        .iter()
        .map(|a| t.column(&pose_column(*a)))
        .collect::<Result<_, _>>()?;
    let mut out = Vec::with_capacity(t.rows.len());
    for row in &t.rows {
        let mut q = Vec::with_capacity(cols.len());
        for (&c, &a) in cols.iter().zip(&machine.axes) {
            let v = t.cell_f64(row, c)?;
            let [lo, hi] = machine.travel(a);
            let tol = 1e-9 * (hi - lo).abs().max(1.0);
            if v < lo - tol || v > hi + tol {
                return Err(InputError::at(
                    path,
                    row.line,
                    c + 1,
                    format!(
                        "{} = {v} is outside the travel [{lo}, {hi}] of axis {a}",
                        t.header[c]
                    ),
                ));
            }
            q.push(v);
        }
        out.push(q);
    }
    Ok(out)
}
