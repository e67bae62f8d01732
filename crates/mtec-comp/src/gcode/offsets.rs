//! Work offsets and tool lengths: how program coordinates become machine coordinates.
//!
//! The error model is a function of the machine (axis) position, while a program commands the
//! tool tip in a work coordinate system. With work offset `w` (G54–G59.3) and tool length `L`
//! (G43, along Z), `machine = program + w + [0, 0, L]` (LinuxCNC's convention; G53 blocks use
//! machine coordinates directly); a G92/G52 offset set by the program adds to it. The offsets
//! at program start come from a TOML file (`--offsets`); G10 L1/L2/L20 in the program change
//! them from there (the rewriter's modal state):
//!
//! ```toml
//! format = "mtec.gcode-offsets/1"
//! active = "G54"                      # the system in effect at program start (default G54)
//! [work_offsets_mm]
//! G54 = [250.0, 120.0, -300.0]
//! G55 = [0.0, 0.0, 0.0]
//! [tool_lengths_mm]
//! 1 = 85.25
//! 4 = 102.0
//! [rotary_offsets_deg]                # optional: A, B, C work offsets (degrees)
//! G54 = [0.0, 0.0, 90.0]
//! ```
//!
//! Decisions:
//! - Without an offsets file (or a file without `[work_offsets_mm]`) only the system active at
//!   program start (G54 unless `active` says otherwise) is known, as zero: program coordinates are
//!   taken as machine coordinates. A program that selects another system (G55…G59.3) is refused
//!   at that word: taking a missing offset as zero would compensate the wrong place.
//! - With `[work_offsets_mm]`, exactly the systems it lists are known; selecting (or starting
//!   in) any other is refused the same way.
//! - Rotary work offsets (LinuxCNC's G5x A, B, C entries) are zero for every system the file
//!   does not list under `[rotary_offsets_deg]`: LinuxCNC's tables hold zero there unless they
//!   are set, and a program that sets them (G10 L2/L20 with A, B or C) is refused. The angle a
//!   rotary axis stands at is machine = program + rotary offset.
//! - No tool has a known length unless the file gives it, so `G43` for an unknown tool is an
//!   unsupported construct — evaluating the model at a point off by a tool length would
//!   compensate the wrong place.

use super::code::GCode;
use serde::Deserialize;
use std::collections::BTreeMap;

/// The offsets file, as read from TOML.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OffsetsFile {
    #[serde(default)]
    pub format: Option<String>,
    #[serde(default)]
    pub active: Option<String>,
    #[serde(default)]
    pub work_offsets_mm: BTreeMap<String, [f64; 3]>,
    #[serde(default)]
    pub tool_lengths_mm: BTreeMap<String, f64>,
    /// Rotary work offsets [A, B, C] in degrees per system; a system not listed has none.
    #[serde(default)]
    pub rotary_offsets_deg: BTreeMap<String, [f64; 3]>,
}

/// Work offsets (indexed by [`work_system_index`]) and tool lengths, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Offsets {
    /// Offsets of G54, G55, G56, G57, G58, G59, G59.1, G59.2, G59.3 in mm.
    pub work_mm: [[f64; 3]; 9],
    /// Index of the system in effect at program start.
    pub active: usize,
    /// Tool number → length in mm.
    pub tool_length_mm: BTreeMap<u32, f64>,
    /// Which work systems have a known offset (see the module docs).
    pub known: [bool; 9],
    /// Rotary work offsets [A, B, C] in degrees of each system (zero unless the file says).
    pub rotary_deg: [[f64; 3]; 9],
}

impl Default for Offsets {
    /// No offsets file: G54 known as zero, the other systems unknown.
    fn default() -> Self {
        Offsets {
            work_mm: [[0.0; 3]; 9],
            active: 0,
            tool_length_mm: BTreeMap::new(),
            known: [true, false, false, false, false, false, false, false, false],
            rotary_deg: [[0.0; 3]; 9],
        }
    }
}

impl Offsets {
    /// Offsets with every system known (the given values; zero where not set).
    pub fn all_known(work_mm: [[f64; 3]; 9]) -> Offsets {
        Offsets {
            work_mm,
            known: [true; 9],
            ..Offsets::default()
        }
    }

    /// The offset of work system `index` (0 = G54 … 8 = G59.3) when it is known.
    pub fn work(&self, index: usize) -> Option<[f64; 3]> {
        (index < 9 && self.known[index]).then(|| self.work_mm[index])
    }
}

/// The names of the work coordinate systems, in index order.
pub const WORK_SYSTEMS: [&str; 9] = [
    "G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3",
];

/// Index of a work system from its G code (G54 → 0, …, G59.3 → 8).
pub fn work_system_index(code: GCode) -> Option<usize> {
    use GCode::*;
    [G54, G55, G56, G57, G58, G59, G59_1, G59_2, G59_3]
        .iter()
        .position(|&c| c == code)
}

impl OffsetsFile {
    /// Validates names and values; the error names the offending key.
    pub fn validate(&self) -> Result<Offsets, String> {
        if let Some(f) = &self.format {
            if f != "mtec.gcode-offsets/1" {
                return Err(format!("format '{f}' is not 'mtec.gcode-offsets/1'"));
            }
        }
        let find = |name: &str| {
            WORK_SYSTEMS
                .iter()
                .position(|s| s.eq_ignore_ascii_case(name.trim()))
                .ok_or_else(|| {
                    format!(
                        "'{name}' is not a work coordinate system (one of {})",
                        WORK_SYSTEMS.join(", ")
                    )
                })
        };
        let mut out = Offsets::default();
        if !self.work_offsets_mm.is_empty() {
            out.known = [false; 9];
        }
        for (name, v) in &self.work_offsets_mm {
            let i = find(name)?;
            if !v.iter().all(|x| x.is_finite()) {
                return Err(format!("work offset {name} is not finite"));
            }
            out.work_mm[i] = *v;
            out.known[i] = true;
        }
        if let Some(a) = &self.active {
            out.active = find(a)?;
            if self.work_offsets_mm.is_empty() {
                // no offsets listed: the active system is the one taken as zero
                out.known = [false; 9];
                out.known[out.active] = true;
            }
        }
        for (k, len) in &self.tool_lengths_mm {
            let t: u32 = k
                .trim()
                .parse()
                .map_err(|_| format!("tool '{k}' is not a tool number"))?;
            if !len.is_finite() {
                return Err(format!("tool {t} length is not finite"));
            }
            out.tool_length_mm.insert(t, *len);
        }
        for (name, v) in &self.rotary_offsets_deg {
            let i = find(name)?;
            if !v.iter().all(|x| x.is_finite()) {
                return Err(format!("rotary offset {name} is not finite"));
            }
            out.rotary_deg[i] = *v;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_indices() {
        assert_eq!(work_system_index(GCode::G54), Some(0));
        assert_eq!(work_system_index(GCode::G59), Some(5));
        assert_eq!(work_system_index(GCode::G59_3), Some(8));
        assert_eq!(work_system_index(GCode::Other(541)), None);
        let f = OffsetsFile {
            active: Some("g55".into()),
            work_offsets_mm: [("G59.2".to_string(), [1.0, 2.0, 3.0])].into(),
            tool_lengths_mm: [("4".to_string(), 102.0)].into(),
            ..Default::default()
        };
        let o = f.validate().unwrap();
        assert_eq!(o.active, 1);
        assert_eq!(o.work_mm[7], [1.0, 2.0, 3.0]);
        assert_eq!(o.tool_length_mm[&4], 102.0);
        let bad = OffsetsFile {
            work_offsets_mm: [("G60".to_string(), [0.0; 3])].into(),
            ..Default::default()
        };
        assert!(bad.validate().unwrap_err().contains("G60"));
    }
}
