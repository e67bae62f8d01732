//! FANUC-style work-offset update: `G90 G10 L2 P<n> <axis><value>` or the custom-macro system
//! variable of the offset, `#<5201 + 20·n + axis − 1>=<value>`.
//!
//! Worked from (no FANUC manual page was found in mtec's reference library; these are manuals
//! of FANUC-compatible controls and must be checked on the control before the first use):
//! - `G10 L2 P<n> IP_`: "P1 through P9 correspond to the work coordinate systems G54 through
//!   G59.3"; the axis values "specify the location of the zero point of the specified work
//!   coordinate system relative to machine coordinate system"; in incremental mode (G91) the
//!   values are added to the table (Allen-Bradley 8520 CNC lathe manual, chapter 11
//!   "Coordinate System Offsets", p. 11-8). FANUC itself numbers P1–P6 = G54–G59 and P0 =
//!   the external offset. mtec writes P1–P6 only and puts `G90` in the block: the value is
//!   then absolute (idempotent: running the line twice gives the same offset), and the control
//!   is left in absolute mode, as it normally is at a tool change.
//! - System variables: "#5221-#5225 G54 X, Y, Z, A, B offset values", G55 at #5241, … G59 at
//!   #5321, a stride of 20 per offset; "all tool work offsets can be read and set within a
//!   macro expression" (HAAS Mill Operator's Manual 96-8000, "Offsets", p. 113). The axis
//!   number is the control's axis order (X1 Y2 Z3 on a mill; X1 Z2 on a lathe), so it is an
//!   option. #5201… is the external offset on a FANUC but G52 on a HAAS, so mtec does not write
//!   it.
//!
//! Values in mm with 3 decimals (1 µm, the usual least input increment) and always a decimal
//! point, so that the value cannot be read in least input increments, whatever the control's
//! decimal-point setting.

use super::{comment_text, update_line, OffsetError, OffsetUpdate};
use crate::table::decimal_number;

fn check(p: u32, base_mm: f64) -> Result<(), OffsetError> {
    if !(1..=6).contains(&p) {
        return Err(OffsetError::Usage(format!(
            "--offset {p}: the FANUC outputs write work offsets 1 (G54) to 6 (G59)"
        )));
    }
    mtec_io::plausible::position_option("--base-mm", base_mm).map_err(OffsetError::Usage)?;
    Ok(())
}

fn comments(u: &OffsetUpdate, header: &[String]) -> String {
    header
        .iter()
        .chain(std::iter::once(&update_line(u)))
        .map(|h| format!("({})\n", comment_text(h)))
        .collect()
}

/// `G90 G10 L2 P<p> <axis><base + c>` (module docs).
pub fn write_g10(
    u: &OffsetUpdate,
    p: u32,
    base_mm: f64,
    header: &[String],
) -> Result<String, OffsetError> {
    check(p, base_mm)?;
    // new offset = base + c  (thermal_offset docs, 2)
    Ok(format!(
        "{}G90 G10 L2 P{p} {}{}\n",
        comments(u, header),
        u.axis.letter(),
        decimal_number(base_mm + u.correction_um * 1e-3, 3)
    ))
}

/// `#<5201 + 20·p + axis_number − 1>=<base + c>` (module docs).
pub fn write_macro(
    u: &OffsetUpdate,
    p: u32,
    axis_number: u32,
    base_mm: f64,
    header: &[String],
) -> Result<String, OffsetError> {
    check(p, base_mm)?;
    if !(1..=5).contains(&axis_number) {
        return Err(OffsetError::Usage(format!(
            "--axis-number {axis_number}: the documented variables cover axes 1 to 5"
        )));
    }
    let var = 5201 + 20 * p + axis_number - 1;
    Ok(format!(
        "{}#{var}={}\n",
        comments(u, header),
        decimal_number(base_mm + u.correction_um * 1e-3, 3)
    ))
}
