//! Beckhoff TwinCAT CNC (ISG kernel) volumetric compensation (TF5280): error parameters in the
//! "ISG CSV" file format.
//!
//! Documented format (Beckhoff Information System, TF5280 Volumetric Compensation, "ISG CSV
//! format" and "Units of measure"; <https://infosys.beckhoff.com/content/1033/tf5280_volumetric_comp/296429067.html>):
//! a header row names the columns — arguments (`X`, `Y`, `Z` in mm) and parameters (ISO 230-1
//! error names such as `EXX`, `EYX`); rows of values below; `//` starts a comment line; columns
//! are separated by white space; parameter values in mm (offsets) or rad (angles); "any
//! functional dependencies can be implemented", e.g. a component error given as a function of
//! several axes, interpolated linearly on a grid (`interpolation` = `GRID`, the default).
//!
//! How a volumetric map is written: translational errors add up at the tool tip whatever their
//! place in the kinematic chain, so the volumetric error field (ex, ey, ez)(X, Y, Z) is given as
//! the three positioning components `EXX`, `EYY`, `EZZ`, each a function of X, Y and Z, and no
//! angular error. The values are the errors themselves (+e, mm, 6 decimals): the CNC compensates
//! its error parameters (its `negate` parameter exists to flip data given the other way round).
//! Rows run with X slowest and Z fastest; the grid must be complete.

use super::{check_correction, Axis, TableError};
use crate::ErrorModel;

const FORMAT: &str = "Beckhoff ISG CSV";

/// Writes the error field of `model` on the grid `axes_mm` (each strictly increasing); the
/// length of the correction vector at every node must pass [`check_correction`] with
/// `max_correction_um` (µm).
pub fn write(
    model: &dyn ErrorModel,
    axes_mm: &[Vec<f64>; 3],
    provenance: &str,
    max_correction_um: f64,
) -> Result<String, TableError> {
    let mut out = String::new();
    out.push_str("// volumetric error map written by mtec (TF5280 ISG CSV format)\n");
    for line in provenance.lines() {
        out.push_str(&format!("// {line}\n"));
    }
    out.push_str(
        "// arguments X Y Z in mm; EXX EYY EZZ = volumetric error ex ey ez of the tool tip in mm\n",
    );
    out.push_str("X Y Z EXX EYY EZZ\n");
    for &x in &axes_mm[0] {
        for &y in &axes_mm[1] {
            for &z in &axes_mm[2] {
                let e = model.error_um([x, y, z]);
                if e.iter().any(|v| v.is_nan()) {
                    return Err(TableError::Undefined { p_mm: [x, y, z] });
                }
                // the same bound as `compensate gcode`: the length of the correction vector;
                // the error names the largest component (or the one that is not finite)
                let k = (0..3).find(|&k| !e[k].is_finite()).unwrap_or_else(|| {
                    (0..3).fold(0, |b, k| if e[k].abs() > e[b].abs() { k } else { b })
                });
                let axis = [Axis::X, Axis::Y, Axis::Z][k];
                let size = e[0].hypot(e[1]).hypot(e[2]); // no overflow for 1e297
                check_correction(axis, None, [x, y, z], -e[k], size, max_correction_um)?;
                out.push_str(&format!(
                    "{} {} {} {:.6} {:.6} {:.6}\n",
                    super::decimal_number(x, 6),
                    super::decimal_number(y, 6),
                    super::decimal_number(z, 6),
                    e[0] * 1e-3 + 0.0,
                    e[1] * 1e-3 + 0.0,
                    e[2] * 1e-3 + 0.0
                ));
            }
        }
    }
    check(&out)?;
    Ok(out)
}

/// Constraint checker: one header naming known arguments and ISO 230-1 parameters, every row as
/// wide as the header and numeric, the argument values forming a complete grid.
pub fn check(text: &str) -> Result<(), TableError> {
    let mut header: Option<Vec<&str>> = None;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with("//") {
            continue;
        }
        let f: Vec<&str> = line.split_whitespace().collect();
        match &header {
            None => {
                for name in &f {
                    let arg = ["X", "Y", "Z", "A", "B", "C"].contains(name);
                    let b = name.as_bytes();
                    let param = b.len() == 3
                        && b[0] == b'E'
                        && b"XYZABC".contains(&b[1])
                        && b"XYZABC".contains(&b[2]);
                    if !arg && !param {
                        return Err(TableError::rule(
                            FORMAT,
                            Some(i + 1),
                            format!("`{name}` is neither an argument (X Y Z A B C) nor a component error name"),
                        ));
                    }
                }
                header = Some(f);
            }
            Some(h) => {
                if f.len() != h.len() {
                    return Err(TableError::rule(
                        FORMAT,
                        Some(i + 1),
                        "row width differs from the header",
                    ));
                }
                let nums: Option<Vec<f64>> = f.iter().map(|s| s.parse::<f64>().ok()).collect();
                match nums {
                    Some(v) if v.iter().all(|x| x.is_finite()) => rows.push(v),
                    _ => {
                        return Err(TableError::rule(
                            FORMAT,
                            Some(i + 1),
                            "values must be numbers",
                        ))
                    }
                }
            }
        }
    }
    let Some(h) = header else {
        return Err(TableError::rule(FORMAT, None, "no header row"));
    };
    let args: Vec<usize> = (0..h.len()).filter(|&c| h[c].len() == 1).collect();
    let mut distinct = 1usize;
    for &c in &args {
        let mut v: Vec<f64> = rows.iter().map(|r| r[c]).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        distinct *= v.len();
    }
    let mut keys: Vec<Vec<u64>> = rows
        .iter()
        .map(|r| args.iter().map(|&c| r[c].to_bits()).collect())
        .collect();
    keys.sort();
    keys.dedup();
    if keys.len() != rows.len() || rows.len() != distinct {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!("{} rows do not form a complete grid without repeats ({distinct} argument combinations)", rows.len()),
        ));
    }
    Ok(())
}
