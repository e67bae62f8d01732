//! HEIDENHAIN nonlinear axis error compensation: compensation value tables (`*.COM`) and their
//! assignment table (`*.CMA`).
//!
//! Documented rules (HEIDENHAIN Technical Manual MANUALplus 620, §6.10.3 "Nonlinear axis error
//! compensation", pp. 713–718; TNC 407/415/425 Technical Manual, "Non-linear axis error
//! compensation", pp. 4-28…4-31 and module 9095):
//! - A `.COM` table has the column `AXISPOS` (compensation points, relative to the machine
//!   datum) and a column named after the axis that is compensated, holding the compensation
//!   values; an optional `BACKLASH` column: "If required, enter the compensation values measured
//!   in the negative direction of traverse in the BACKLASH column" (MANUALplus 620 Technical
//!   Manual p. 716). [`write`] leaves it out (mtec's models have no reversal error);
//!   [`write_bidirectional`] writes an ISO 230-2 run with the axis column = the error measured
//!   in the positive direction (x̄↑) and `BACKLASH` = the error measured in the negative
//!   direction (x̄↓), in the same form. That `BACKLASH` holds the whole negative-direction value
//!   (not its difference to the axis column) is mtec's reading of that sentence.
//! - The `.CMA` table has one column per axis; the `.COM` name is entered in the column of the
//!   axis on which the compensation depends: "[axis in column of *.com] = F(axis in column of
//!   *.cma in which *.com is entered)". The column `ACTIVE` marks the active line with `*`.
//! - At most 256 entries per `.COM` (module 9095 error 3).
//! - Tables are TNC table files: a `BEGIN <name> <unit>` line, a header line, rows, `[END]`.
//!
//! Values: the axis error e = −c in mm with 4 decimals (0.1 µm), signed (`+0.0030`). The
//! manuals do not state the sign in words; their worked example (TNC 407 Technical Manual p. 4-28,
//! Z = F(Y) sag) plots the curve the table is read from as "Error in Z [mm]", and the function
//! is named *axis error* compensation, so mtec enters the error and the control removes it. This is
//! mtec's reading, not a quoted rule: check one point on the machine before relying on it.

use super::bidirectional::BidirectionalProfile;
use super::{AxisProfile, TableError};

const FORMAT: &str = "HEIDENHAIN .COM/.CMA";
/// Most entries of a `.COM` table.
pub const MAX_ENTRIES: usize = 256;

/// The two files of a HEIDENHAIN compensation.
#[derive(Debug, Clone, PartialEq)]
pub struct HeidenhainTables {
    pub com_name: String,
    pub com: String,
    pub cma_name: String,
    pub cma: String,
}

/// Writes the `.COM` table named `com_name` (e.g. `ZY.COM`) and a one-line `.CMA` assigning it.
pub fn write(
    profile: &AxisProfile,
    com_name: &str,
    cma_name: &str,
) -> Result<HeidenhainTables, TableError> {
    let out_axis = profile.output_axis.letter();
    let mut com = format!("BEGIN {com_name} MM\n");
    com.push_str(&format!("{:<5} {:>13} {:>10}\n", "NR", "AXISPOS", out_axis));
    for (n, &c_um) in profile.checked_values()?.iter().enumerate() {
        let e_mm = -c_um * 1e-3; // the axis error
        let c_txt = format!("{:+.4}", if e_mm.abs() < 5e-5 { 0.0 } else { e_mm });
        com.push_str(&format!(
            "{:<5} {:>13} {:>10}\n",
            n,
            format!("{:+.4}", profile.position(n)),
            c_txt
        ));
    }
    com.push_str("[END]\n");
    check_com(&com)?;
    Ok(HeidenhainTables {
        com_name: com_name.to_string(),
        com,
        cma_name: cma_name.to_string(),
        cma: assignment(profile.input_axis, com_name, cma_name),
    })
}

/// Writes an ISO 230-2 profile as a `.COM` table `NR AXISPOS <axis> BACKLASH` (the errors x̄↑ and
/// x̄↓ = −c↑, −c↓ in mm, 4 decimals) and its `.CMA` assignment.
pub fn write_bidirectional(
    profile: &BidirectionalProfile,
    com_name: &str,
    cma_name: &str,
) -> Result<HeidenhainTables, TableError> {
    if profile.len() > MAX_ENTRIES {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "{} targets; a .COM table holds at most {MAX_ENTRIES}",
                profile.len()
            ),
        ));
    }
    let (fwd, rev) = profile.checked_values()?;
    let axis = profile.axis.letter();
    let mut com = format!("BEGIN {com_name} MM\n");
    com.push_str(&format!(
        "{:<5} {:>13} {:>10} {:>10}\n",
        "NR", "AXISPOS", axis, "BACKLASH"
    ));
    for (n, &p) in profile.positions_mm.iter().enumerate() {
        com.push_str(&format!(
            "{:<5} {:>13} {:>10} {:>10}\n",
            n,
            format!("{p:+.4}"),
            error_mm(fwd[n]),
            error_mm(rev[n])
        ));
    }
    com.push_str("[END]\n");
    check_com(&com)?;
    Ok(HeidenhainTables {
        com_name: com_name.to_string(),
        com,
        cma_name: cma_name.to_string(),
        cma: assignment(profile.axis, com_name, cma_name),
    })
}

/// The axis error e = −c (mm) as the table holds it: 4 decimals, signed, no negative zero.
fn error_mm(c_um: f64) -> String {
    let e_mm = -c_um * 1e-3;
    format!("{:+.4}", if e_mm.abs() < 5e-5 { 0.0 } else { e_mm })
}

/// A one-line `.CMA` entering `com_name` in the column of `input_axis`.
fn assignment(input_axis: super::Axis, com_name: &str, cma_name: &str) -> String {
    let mut cma = format!("BEGIN {cma_name}\n");
    let col = |a: char| {
        if a == input_axis.letter() {
            com_name.to_string()
        } else {
            String::new()
        }
    };
    cma.push_str(&format!(
        "{:<5} {:<12} {:<12} {:<12} {}\n",
        "NR", "X", "Y", "Z", "ACTIVE"
    ));
    cma.push_str(&format!(
        "{:<5} {:<12} {:<12} {:<12} {}\n",
        0,
        col('X'),
        col('Y'),
        col('Z'),
        "*"
    ));
    cma.push_str("[END]\n");
    cma
}

/// Constraint checker of a `.COM` table: framing, NR 0..N−1, AXISPOS strictly increasing,
/// numeric values, at most 256 entries.
pub fn check_com(text: &str) -> Result<(), TableError> {
    let lines: Vec<&str> = text.lines().collect();
    if !lines.first().is_some_and(|l| l.starts_with("BEGIN ")) {
        return Err(TableError::rule(
            FORMAT,
            Some(1),
            "a table starts with `BEGIN <name> <unit>`",
        ));
    }
    if lines.last() != Some(&"[END]") {
        return Err(TableError::rule(
            FORMAT,
            Some(lines.len()),
            "a table ends with `[END]`",
        ));
    }
    let header: Vec<&str> = lines
        .get(1)
        .map(|l| l.split_whitespace().collect())
        .unwrap_or_default();
    if header.len() < 3 || header[0] != "NR" || header[1] != "AXISPOS" {
        return Err(TableError::rule(
            FORMAT,
            Some(2),
            "header must be `NR AXISPOS <axis>…`",
        ));
    }
    let rows = &lines[2..lines.len() - 1];
    if rows.len() > MAX_ENTRIES {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "{} entries; a .COM table holds at most {MAX_ENTRIES}",
                rows.len()
            ),
        ));
    }
    let mut last: Option<f64> = None;
    for (k, row) in rows.iter().enumerate() {
        let line = k + 3;
        let f: Vec<&str> = row.split_whitespace().collect();
        if f.len() != header.len() {
            return Err(TableError::rule(
                FORMAT,
                Some(line),
                "row width differs from the header",
            ));
        }
        if f[0].parse::<usize>().ok() != Some(k) {
            return Err(TableError::rule(
                FORMAT,
                Some(line),
                format!("NR must be {k}"),
            ));
        }
        let nums: Option<Vec<f64>> = f[1..].iter().map(|s| s.parse::<f64>().ok()).collect();
        let Some(nums) = nums else {
            return Err(TableError::rule(
                FORMAT,
                Some(line),
                "AXISPOS and values must be numbers",
            ));
        };
        if let Some(prev) = last {
            if nums[0] <= prev {
                return Err(TableError::rule(
                    FORMAT,
                    Some(line),
                    "AXISPOS must increase",
                ));
            }
        }
        last = Some(nums[0]);
    }
    Ok(())
}
