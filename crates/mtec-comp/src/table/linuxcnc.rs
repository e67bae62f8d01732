//! LinuxCNC joint compensation file (`[JOINT_n] COMP_FILE` with `COMP_FILE_TYPE` 0 or 1).
//!
//! Documented format (LinuxCNC INI configuration, section `[JOINT_<num>]`,
//! <https://linuxcnc.org/docs/html/config/ini-config.html>): one triplet per line, separated by
//! spaces, in machine units: the nominal (commanded) position, then the value for travel in the
//! positive and in the negative direction; nominals ascending; at most 256 triplets per joint.
//! Type 0: the two values are the *actual* positions reached. Type 1: they are the offsets
//! (trims) added to the nominal. The loader (`usrmotLoadComp` in
//! `src/emc/motion/usrmotintf.cc`) reads `"%lf %lf %lf"` line by line and stops silently at the
//! first line that is not three numbers, and converts type 0 to trims as `nom - fwd`: hence no
//! header or comment line may appear (the whole table would be ignored), and
//! type 0 actual = nominal + e, type 1 trim = c = −e.
//!
//! The motion module (`src/emc/motion/control.c`, the compensation block of
//! `compute_screw_comp`) applies `fwd_trim` (interpolated) while the joint's commanded velocity is
//! positive, `rev_trim` while it is negative, and keeps the last one at standstill: a target
//! approached from below gets the forward column, from above the reverse one.
//!
//! mtec's models have no reversal error, so [`write`] makes the forward and reverse columns
//! equal; [`write_bidirectional`] writes the two columns of an ISO 230-2 run (forward = c↑ =
//! −x̄↑, reverse = c↓ = −x̄↓). Values are written in mm with 6 decimals (1 nm).

use super::bidirectional::BidirectionalProfile;
use super::{AxisProfile, TableError};

const FORMAT: &str = "LinuxCNC COMP_FILE";
/// Most triplets a joint's compensation file may hold.
pub const MAX_TRIPLETS: usize = 256;

/// Writes the compensation file of `profile` (input axis = output axis = the joint).
pub fn write(profile: &AxisProfile, comp_type: u8) -> Result<String, TableError> {
    if profile.input_axis != profile.output_axis {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "a joint compensation file corrects the joint's own position: output axis {} must equal input axis {} (use sinumerik-cec for cross-axis tables)",
                profile.output_axis.letter(),
                profile.input_axis.letter()
            ),
        ));
    }
    let mut out = String::new();
    for (n, &c_um) in profile.checked_values()?.iter().enumerate() {
        let nominal = profile.position(n);
        let value = match comp_type {
            0 => nominal - c_um * 1e-3, // actual position = nominal + e
            1 => c_um * 1e-3,           // trim = c = −e
            t => {
                return Err(TableError::rule(
                    FORMAT,
                    None,
                    format!("COMP_FILE_TYPE must be 0 or 1, not {t}"),
                ))
            }
        };
        out.push_str(&format!("{nominal:.6} {value:.6} {value:.6}\n"));
    }
    check(&out)?;
    Ok(out)
}

/// Writes the compensation file of a direction-dependent profile: `nominal forward reverse` at
/// each target; type 1 trims c↑, c↓ (mm), type 0 actual positions nominal − c↑, nominal − c↓.
pub fn write_bidirectional(
    profile: &BidirectionalProfile,
    comp_type: u8,
) -> Result<String, TableError> {
    if comp_type > 1 {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!("COMP_FILE_TYPE must be 0 or 1, not {comp_type}"),
        ));
    }
    if profile.len() > MAX_TRIPLETS {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!(
                "{} targets; LinuxCNC holds at most {MAX_TRIPLETS} triplets per joint",
                profile.len()
            ),
        ));
    }
    let (fwd, rev) = profile.checked_values()?;
    let mut out = String::new();
    for (n, &nominal) in profile.positions_mm.iter().enumerate() {
        // type 1: trim = c; type 0: actual = nominal + e = nominal − c
        let value = |c_um: f64| match comp_type {
            0 => nominal - c_um * 1e-3,
            _ => c_um * 1e-3,
        };
        out.push_str(&format!(
            "{nominal:.6} {:.6} {:.6}\n",
            value(fwd[n]),
            value(rev[n])
        ));
    }
    check(&out)?;
    Ok(out)
}

/// The loader's rules: only lines of three numbers, nominals strictly increasing, ≤ 256 lines.
pub fn check(text: &str) -> Result<(), TableError> {
    let mut last: Option<f64> = None;
    let mut count = 0;
    for (i, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let nums: Vec<f64> = fields.iter().filter_map(|f| f.parse().ok()).collect();
        if fields.len() != 3 || nums.len() != 3 || !nums.iter().all(|v| v.is_finite()) {
            return Err(TableError::rule(
                FORMAT,
                Some(i + 1),
                format!("`{line}` is not three numbers: LinuxCNC stops reading the file here"),
            ));
        }
        if let Some(prev) = last {
            if nums[0] <= prev {
                return Err(TableError::rule(
                    FORMAT,
                    Some(i + 1),
                    format!("nominal {} does not increase (previous {prev})", nums[0]),
                ));
            }
        }
        last = Some(nums[0]);
        count += 1;
    }
    if count == 0 {
        return Err(TableError::rule(FORMAT, None, "the table is empty"));
    }
    if count > MAX_TRIPLETS {
        return Err(TableError::rule(
            FORMAT,
            None,
            format!("{count} triplets; LinuxCNC holds at most {MAX_TRIPLETS} per joint"),
        ));
    }
    Ok(())
}
