//! A machine: its kinematic chain, axis travels, tool offset and conventions, from TOML.
//!
//! ```toml
//! name = "XYFZ vertical machining centre"
//! chain = "WXYFZT"            # workpiece on X on Y on the frame; Z carries the tool
//! tool_offset_mm = [0, 0, 100]
//! error_frame = "moving"      # or "reference" (see kinematics docs)
//! [axes.X]
//! travel = [0, 600]
//! [axes.C]
//! travel = [0, 360]
//! centre_mm = [0, 0, 0]       # a point of the rotary axis line at the machine's zero
//! ```
//!
//! A linear axis may give `period_mm = 10` (its ball screw's lead): the period of the pitch
//! error that line identification then models.
//!
//! Chain notation (SPEC §2): axis letters from the workpiece `W` to the tool `T` through the
//! frame `F`. Letters between W and F are workpiece-side axes (the first carries the workpiece);
//! letters between F and T are tool-side axes (the last carries the tool).

use crate::element::Axis;
use mtec_io::plausible::MAX_POSITION_MM;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Where an axis' error motion is defined relative to its ideal motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ErrorFrame {
    /// Error motion expressed in the moving frame, after the ideal motion: T = M(q)·E(q).
    /// What a laser or level measures on the moving carriage. The default.
    #[default]
    Moving,
    /// Error motion expressed in the reference (parent) frame, before the ideal motion: T = E(q)·M(q).
    Reference,
}

/// The chain of a machine.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Chain {
    /// The text, e.g. `WXYFZT`.
    pub text: String,
    /// Workpiece-side axes, from the workpiece toward the frame.
    pub workpiece_side: Vec<Axis>,
    /// Tool-side axes, from the frame toward the tool.
    pub tool_side: Vec<Axis>,
}

/// Why a machine description is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MachineError {
    #[error("chain `{0}`: {1}")]
    Chain(String, String),
    #[error("axis {0} is in the chain but has no [axes.{0}] table with its travel")]
    MissingAxis(char),
    #[error("[axes.{0}] is given but {0} is not in the chain `{1}`")]
    ExtraAxis(String, String),
    #[error("[axes.{0}]: travel must be [min, max] with min < max, finite (got [{1}, {2}])")]
    Travel(String, f64, f64),
    #[error("[axes.{0}]: period_mm is the lead of a linear axis' ball screw, a positive length in mm (got {1})")]
    Period(String, f64),
    #[error("{0} must be finite")]
    NotFinite(&'static str),
    #[error("{0} has {1:e}: implausible for a machine tool (|value| must be below {MAX_POSITION_MM:e} mm): check the unit")]
    Implausible(String, f64),
}

impl Chain {
    /// Parses a chain string such as `WXYFZT`, `WCFT` or `WCAYFXZT`.
    pub fn parse(text: &str) -> Result<Chain, MachineError> {
        let t = text.trim().to_ascii_uppercase();
        let err = |m: &str| MachineError::Chain(text.to_string(), m.to_string());
        let chars: Vec<char> = t.chars().collect();
        if chars.first() != Some(&'W') || chars.last() != Some(&'T') {
            return Err(err("must start with W (workpiece) and end with T (tool)"));
        }
        let inner = &chars[1..chars.len() - 1];
        let f = inner.iter().filter(|&&c| c == 'F').count();
        if f != 1 {
            return Err(err("must contain the frame F exactly once"));
        }
        let fpos = inner.iter().position(|&c| c == 'F').unwrap_or(0);
        let mut seen = Vec::new();
        let mut to_axes = |s: &[char]| -> Result<Vec<Axis>, MachineError> {
            s.iter()
                .map(|&c| {
                    let a = Axis::from_letter(c).ok_or_else(|| {
                        err(&format!("`{c}` is not an axis letter (X Y Z A B C)"))
                    })?;
                    if seen.contains(&a) {
                        return Err(err(&format!("axis {c} appears twice")));
                    }
                    seen.push(a);
                    Ok(a)
                })
                .collect()
        };
        let workpiece_side = to_axes(&inner[..fpos])?;
        let tool_side = to_axes(&inner[fpos + 1..])?;
        if workpiece_side.is_empty() && tool_side.is_empty() {
            return Err(err("has no axes"));
        }
        Ok(Chain {
            text: t,
            workpiece_side,
            tool_side,
        })
    }

    /// All axes of the chain in canonical order X, Y, Z, A, B, C: the order of a pose vector.
    pub fn axes(&self) -> Vec<Axis> {
        let mut v: Vec<Axis> = self
            .workpiece_side
            .iter()
            .chain(self.tool_side.iter())
            .copied()
            .collect();
        v.sort();
        v
    }

    /// True if the axis carries the workpiece side.
    pub fn is_workpiece_side(&self, a: Axis) -> bool {
        self.workpiece_side.contains(&a)
    }
}

/// One axis' description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    /// [min, max] in mm (linear) or degrees (rotary).
    pub travel: [f64; 2],
    /// Linear axes: the carriage reference point about which its angular error motions act,
    /// in machine coordinates at zero position. Rotary axes: a point of the axis line.
    #[serde(default, alias = "reference_point_mm")]
    pub centre_mm: [f64; 3],
    /// Linear axes driven by a ball screw: its lead (mm per revolution), the period of the
    /// screw's pitch error. Optional; line identification then fits a sine/cosine pair of this
    /// period to the positioning error (`mtec identify lines`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub period_mm: Option<f64>,
}

/// The TOML form of a machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineSpec {
    #[serde(default)]
    pub name: String,
    pub chain: String,
    pub axes: BTreeMap<String, AxisSpec>,
    /// Tool tip relative to the tool-side end of the chain (spindle reference point), mm.
    #[serde(default)]
    pub tool_offset_mm: [f64; 3],
    /// Workpiece reference point relative to the workpiece-side end of the chain, mm.
    #[serde(default)]
    pub workpiece_origin_mm: [f64; 3],
    #[serde(default)]
    pub error_frame: ErrorFrame,
}

/// A validated machine.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    pub name: String,
    pub chain: Chain,
    /// Axes in pose order (X, Y, Z, A, B, C as present).
    pub axes: Vec<Axis>,
    pub specs: BTreeMap<Axis, AxisSpec>,
    pub tool_offset_mm: [f64; 3],
    pub workpiece_origin_mm: [f64; 3],
    pub error_frame: ErrorFrame,
}

impl Machine {
    /// Validates a spec.
    pub fn from_spec(spec: MachineSpec) -> Result<Machine, MachineError> {
        let chain = Chain::parse(&spec.chain)?;
        let mut specs = BTreeMap::new();
        for (k, s) in &spec.axes {
            let a = k
                .chars()
                .next()
                .filter(|_| k.len() == 1)
                .and_then(Axis::from_letter)
                .filter(|a| chain.axes().contains(a))
                .ok_or_else(|| MachineError::ExtraAxis(k.clone(), chain.text.clone()))?;
            if !(s.travel[0].is_finite() && s.travel[1].is_finite() && s.travel[0] < s.travel[1]) {
                return Err(MachineError::Travel(k.clone(), s.travel[0], s.travel[1]));
            }
            if !s.centre_mm.iter().all(|v| v.is_finite()) {
                return Err(MachineError::NotFinite("centre_mm"));
            }
            // a linear travel or a centre of 100 m is a unit mistake; identification of such
            // a machine ran on without a word (2026-11-29). A rotary axis that turns without
            // limit is written with huge limits (LinuxCNC: ±1e99), so its travel is not bounded
            let linear_end = s.travel.iter().find(|v| v.abs() >= MAX_POSITION_MM);
            if let Some(v) = linear_end.filter(|_| !a.is_rotary()) {
                return Err(MachineError::Implausible(format!("[axes.{k}] travel"), *v));
            }
            if let Some(v) = s.centre_mm.iter().find(|v| v.abs() >= MAX_POSITION_MM) {
                return Err(MachineError::Implausible(
                    format!("[axes.{k}] centre_mm"),
                    *v,
                ));
            }
            if let Some(p) = s.period_mm {
                if !(p.is_finite() && p > 0.0) || a.is_rotary() {
                    return Err(MachineError::Period(k.clone(), p));
                }
            }
            specs.insert(a, s.clone());
        }
        for a in chain.axes() {
            if !specs.contains_key(&a) {
                return Err(MachineError::MissingAxis(a.letter()));
            }
        }
        if !spec
            .tool_offset_mm
            .iter()
            .chain(spec.workpiece_origin_mm.iter())
            .all(|v| v.is_finite())
        {
            return Err(MachineError::NotFinite(
                "tool_offset_mm and workpiece_origin_mm",
            ));
        }
        for (name, v) in [
            ("tool_offset_mm", spec.tool_offset_mm),
            ("workpiece_origin_mm", spec.workpiece_origin_mm),
        ] {
            if let Some(x) = v.iter().find(|x| x.abs() >= MAX_POSITION_MM) {
                return Err(MachineError::Implausible(name.to_string(), *x));
            }
        }
        Ok(Machine {
            name: spec.name,
            axes: chain.axes(),
            chain,
            specs,
            tool_offset_mm: spec.tool_offset_mm,
            workpiece_origin_mm: spec.workpiece_origin_mm,
            error_frame: spec.error_frame,
        })
    }

    /// The TOML form of this machine (for writing it back out).
    pub fn to_spec(&self) -> MachineSpec {
        MachineSpec {
            name: self.name.clone(),
            chain: self.chain.text.clone(),
            axes: self
                .specs
                .iter()
                .map(|(a, s)| (a.letter().to_string(), s.clone()))
                .collect(),
            tool_offset_mm: self.tool_offset_mm,
            workpiece_origin_mm: self.workpiece_origin_mm,
            error_frame: self.error_frame,
        }
    }

    /// Position of an axis in the pose vector.
    pub fn axis_index(&self, a: Axis) -> Option<usize> {
        self.axes.iter().position(|&x| x == a)
    }

    /// Travel of an axis.
    pub fn travel(&self, a: Axis) -> [f64; 2] {
        self.specs[&a].travel
    }

    /// The XYFZ vertical machining centre of the 9-line source (travels 600 × 800 × 300 mm).
    pub fn vmc_xyfz(tool_length_mm: f64) -> Machine {
        let mut axes = BTreeMap::new();
        for (k, t) in [("X", 600.0), ("Y", 800.0), ("Z", 300.0)] {
            axes.insert(
                k.to_string(),
                AxisSpec {
                    travel: [0.0, t],
                    centre_mm: [0.0; 3],
                    period_mm: None,
                },
            );
        }
        Machine::from_spec(MachineSpec {
            name: "XYFZ vertical machining centre (600 x 800 x 300 mm)".into(),
            chain: "WXYFZT".into(),
            axes,
            tool_offset_mm: [0.0, 0.0, tool_length_mm],
            workpiece_origin_mm: [0.0; 3],
            error_frame: ErrorFrame::Moving,
        })
        .expect("built-in machine is valid")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_period(p: Option<f64>, axis: &str) -> Result<Machine, MachineError> {
        let mut m = Machine::vmc_xyfz(100.0).to_spec();
        m.axes.get_mut(axis).expect("axis").period_mm = p;
        Machine::from_spec(m)
    }

    #[test]
    fn a_screw_lead_is_a_positive_length() {
        assert_eq!(
            with_period(Some(12.0), "X").unwrap().specs[&Axis::X].period_mm,
            Some(12.0)
        );
        assert!(matches!(
            with_period(Some(0.0), "Y"),
            Err(MachineError::Period(..))
        ));
        assert!(matches!(
            with_period(Some(f64::NAN), "Z"),
            Err(MachineError::Period(..))
        ));
        // absent: not written back out (files without it stay byte for byte)
        let spec = Machine::vmc_xyfz(100.0).to_spec();
        assert!(spec.axes.values().all(|a| a.period_mm.is_none()));
    }

    #[test]
    fn travels_and_offsets_no_machine_has_are_refused() {
        let mut m = Machine::vmc_xyfz(100.0).to_spec();
        m.axes.get_mut("X").expect("X").travel = [0.0, 99_999.0];
        assert!(Machine::from_spec(m.clone()).is_ok());
        m.axes.get_mut("X").expect("X").travel = [0.0, 1e300];
        let e = Machine::from_spec(m).unwrap_err();
        assert!(
            e.to_string().contains("[axes.X] travel has 1e300") && e.to_string().contains("mm"),
            "{e}"
        );
        let mut m = Machine::vmc_xyfz(100.0).to_spec();
        m.tool_offset_mm = [0.0, 0.0, -1e5];
        let e = Machine::from_spec(m).unwrap_err();
        assert!(e.to_string().contains("tool_offset_mm has -1e5"), "{e}");
        // a rotary axis without limits keeps its huge travel
        let mut m = Machine::vmc_xyfz(100.0).to_spec();
        m.chain = "WCXYFZT".into();
        let mut c = m.axes["X"].clone();
        c.travel = [-1e99, 1e99];
        m.axes.insert("C".into(), c);
        assert!(Machine::from_spec(m).is_ok());
    }
}
