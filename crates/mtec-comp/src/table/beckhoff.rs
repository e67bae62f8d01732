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

/// Leadscrew error compensation (SSFK) of TwinCAT CNC, the direction-dependent table of one
/// axis: the axis compensation value list `kw.ssfk.*` (Beckhoff Information System, TF5200 Axis
/// compensation parameters, P-COMP-00017…00024 and "Example of a compensation value list"):
/// `kw.ssfk.bilateral 1` (one table per direction), `kw.ssfk.interval 0` (every interpolation
/// point given as `table[i].setpoint`), `kw.ssfk.unit 1` (metric), positions and values in
/// 0.1 µm. The values are position errors, "Δs_i = s_ist,i − s_soll,i" (actual − setpoint, the
/// manual's worked point: 19856.5 µm reached for 19866.7 µm → `pos` = −102), i.e. the ISO 230-2
/// mean deviations x̄↑ (`pos`) and x̄↓ (`neg`) = −c↑, −c↓, rounded to 0.1 µm.
pub mod ssfk {
    use super::super::bidirectional::BidirectionalProfile;
    use super::super::TableError;

    const FORMAT: &str = "Beckhoff SSFK list";
    /// Default largest number of table entries (P-COMP-00059 `kw.ssfk.max_points`).
    pub const DEFAULT_MAX_POINTS: usize = 1500;

    /// A length in mm as a whole number of 0.1 µm, if it is one (to 1e-6 of the unit).
    fn tenth_um(mm: f64) -> Option<i64> {
        let u = mm * 1e4;
        ((u - u.round()).abs() < 1e-6).then_some(u.round() as i64)
    }

    /// Writes the list for logical axis `axis_number` (`kopf.log_achs_nr`).
    pub fn write(
        profile: &BidirectionalProfile,
        axis_number: u8,
        max_points: usize,
    ) -> Result<String, TableError> {
        let (fwd, rev) = profile.checked_values()?;
        let mut setpoints = Vec::with_capacity(profile.len());
        for &p in &profile.positions_mm {
            setpoints.push(tenth_um(p).ok_or_else(|| {
                TableError::rule(
                    FORMAT,
                    None,
                    format!("target {p} mm is not a whole number of 0.1 um, the list's unit"),
                )
            })?);
        }
        // x̄ = −c, µm → 0.1 µm
        let units =
            |c: &[f64]| -> Vec<i64> { c.iter().map(|c| (-c * 10.0).round() as i64).collect() };
        let (pos, neg) = (units(fwd), units(rev));
        let n = setpoints.len();
        let mut out = String::new();
        let mut kv = |k: String, v: String| out.push_str(&format!("{k:<36}{v}\n"));
        kv("kopf.log_achs_nr".into(), axis_number.to_string());
        kv(
            "kopf.log_achs_name".into(),
            profile.axis.letter().to_string(),
        );
        kv("kw.ssfk.interval".into(), "0".into());
        kv("kw.ssfk.kw_startpos".into(), setpoints[0].to_string());
        kv("kw.ssfk.kw_nr_max".into(), n.to_string());
        kv("kw.ssfk.unit".into(), "1".into());
        kv("kw.ssfk.bilateral".into(), "1".into());
        for (i, s) in setpoints.iter().enumerate() {
            kv(format!("kw.ssfk.table[{i}].setpoint"), s.to_string());
        }
        for (i, v) in pos.iter().enumerate() {
            kv(format!("kw.ssfk.table[{i}].pos"), v.to_string());
        }
        for (i, v) in neg.iter().enumerate() {
            kv(format!("kw.ssfk.table[{i}].neg"), v.to_string());
        }
        check(&out, max_points)?;
        Ok(out)
    }

    /// Constraint checker: `key value` lines, integer values, `kw_nr_max` entries of
    /// `setpoint`, `pos` and `neg` with indices 0..kw_nr_max−1, setpoints strictly increasing and
    /// the first equal to `kw_startpos`, at most `max_points` entries.
    pub fn check(text: &str, max_points: usize) -> Result<(), TableError> {
        let mut scalars = std::collections::BTreeMap::new();
        let mut cols: [Vec<(usize, i64, usize)>; 3] = Default::default();
        for (i, line) in text.lines().enumerate() {
            let bad = |m: &str| TableError::rule(FORMAT, Some(i + 1), format!("`{line}`: {m}"));
            let mut f = line.split_whitespace();
            let (Some(key), Some(value), None) = (f.next(), f.next(), f.next()) else {
                return Err(bad("not a `key value` line"));
            };
            if key == "kopf.log_achs_name" {
                continue;
            }
            let v: i64 = value
                .parse()
                .map_err(|_| bad("the value is not an integer"))?;
            if let Some(rest) = key.strip_prefix("kw.ssfk.table[") {
                let (idx, field) = rest.split_once("].").ok_or_else(|| bad("bad table key"))?;
                let idx: usize = idx.parse().map_err(|_| bad("bad table index"))?;
                let c = ["setpoint", "pos", "neg"]
                    .iter()
                    .position(|f| *f == field)
                    .ok_or_else(|| bad("unknown table field"))?;
                cols[c].push((idx, v, i + 1));
            } else {
                scalars.insert(key.to_string(), v);
            }
        }
        let get = |k: &str| {
            scalars
                .get(k)
                .copied()
                .ok_or_else(|| TableError::rule(FORMAT, None, format!("{k} missing")))
        };
        let n = get("kw.ssfk.kw_nr_max")?;
        if get("kw.ssfk.interval")? != 0 || get("kw.ssfk.bilateral")? != 1 {
            return Err(TableError::rule(
                FORMAT,
                None,
                "mtec writes interval 0 (setpoints given) and bilateral 1",
            ));
        }
        if n < 2 || n as usize > max_points {
            return Err(TableError::rule(
                FORMAT,
                None,
                format!("{n} entries: a table needs 2..{max_points} (P-COMP-00059)"),
            ));
        }
        for (c, name) in cols.iter().zip(["setpoint", "pos", "neg"]) {
            let idx: Vec<usize> = c.iter().map(|e| e.0).collect();
            if idx != (0..n as usize).collect::<Vec<_>>() {
                return Err(TableError::rule(
                    FORMAT,
                    None,
                    format!(
                        "table[i].{name} must be given for i = 0..{} in order",
                        n - 1
                    ),
                ));
            }
        }
        let sp = &cols[0];
        if sp[0].1 != get("kw.ssfk.kw_startpos")? {
            return Err(TableError::rule(
                FORMAT,
                Some(sp[0].2),
                "the first setpoint must equal kw_startpos",
            ));
        }
        if let Some(w) = sp.windows(2).find(|w| w[1].1 <= w[0].1) {
            return Err(TableError::rule(
                FORMAT,
                Some(w[1].2),
                "setpoints must increase",
            ));
        }
        Ok(())
    }
}
