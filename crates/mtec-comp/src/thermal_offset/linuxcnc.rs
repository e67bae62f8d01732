//! LinuxCNC (RS274NGC) work-offset update: `G10 L2 P<n> <axis><value>`.
//!
//! Documented (LinuxCNC G-code reference, "G10 L2 Set Coordinate System"; the P0 form since the
//! documentation change of 2011-01-23, git.linuxcnc.org emc2 commit 6a2623a): `G10 L2 P- axes`
//! sets the origin of coordinate system P (P1 = G54 … P9 = G59.3, P0 = the active one) to the
//! given values "in terms of the not offset machine coordinate system"; only the axes named on
//! the line change. The value is absolute, so mtec writes the offset itself: the base (the
//! offset that is right with no drift, or the one set at the zeroing moment) plus the update,
//! in mm with 4 decimals (0.1 µm). Checked against LinuxCNC's own interpreter (`rs274`) in
//! `crates/mtec-cli/tests/thermal_offset_cli.rs`: the written offset moves the commanded
//! machine position of a programmed point by the update.

use super::{comment_text, update_line, OffsetError, OffsetUpdate};
use crate::table::trim_number;

/// Writes the update as a `G10 L2` block for coordinate system `p` (0–9) with `base_mm` the
/// offset's value before the update (module docs).
pub fn write(
    u: &OffsetUpdate,
    p: u32,
    base_mm: f64,
    header: &[String],
) -> Result<String, OffsetError> {
    if p > 9 {
        return Err(OffsetError::Usage(format!(
            "--offset {p}: LinuxCNC's G10 L2 takes P0 (the active system) to P9 (G59.3)"
        )));
    }
    mtec_io::plausible::position_option("--base-mm", base_mm).map_err(OffsetError::Usage)?;
    let mut out = String::new();
    for h in header.iter().chain(std::iter::once(&update_line(u))) {
        out.push_str(&format!("({})\n", comment_text(h)));
    }
    // new offset = base + c  (mod docs, 2)
    out.push_str(&format!(
        "G10 L2 P{p} {}{}\n",
        u.axis.letter(),
        trim_number(base_mm + u.correction_um * 1e-3, 4)
    ));
    Ok(out)
}
