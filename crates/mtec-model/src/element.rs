//! Error elements named as in ISO 230-1: `E` + direction + [`0`] + axis.
//!
//! - `EXX` positioning of X, `EYX`/`EZX` straightness of X in Y/Z, `EAX` roll, `EBX` pitch,
//!   `ECX` yaw (likewise for Y and Z: the letter after `E` is the direction of the error, the
//!   last letter the axis that moves).
//! - `EC0Y` squareness of Y to X, `EB0Z` of Z to X, `EA0Z` of Z to Y (position-independent).
//! - Rotary axis C: error motions `EXC EYC EZC EAC EBC ECC` (functions of the angle) and
//!   location errors `EX0C EY0C EA0C EB0C` (position of the axis average line).
//!
//! Translational elements are in µm, rotational ones in µrad.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A machine axis (or the direction of an error): X, Y, Z linear, A, B, C rotary about X, Y, Z.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Axis {
    X,
    Y,
    Z,
    A,
    B,
    C,
}

impl Axis {
    /// All six, in canonical order.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::A, Axis::B, Axis::C];

    /// The axis letter.
    pub fn letter(self) -> char {
        match self {
            Axis::X => 'X',
            Axis::Y => 'Y',
            Axis::Z => 'Z',
            Axis::A => 'A',
            Axis::B => 'B',
            Axis::C => 'C',
        }
    }

    /// The axis of a letter (upper or lower case).
    pub fn from_letter(c: char) -> Option<Axis> {
        match c.to_ascii_uppercase() {
            'X' => Some(Axis::X),
            'Y' => Some(Axis::Y),
            'Z' => Some(Axis::Z),
            'A' => Some(Axis::A),
            'B' => Some(Axis::B),
            'C' => Some(Axis::C),
            _ => None,
        }
    }

    /// True for A, B, C.
    pub fn is_rotary(self) -> bool {
        matches!(self, Axis::A | Axis::B | Axis::C)
    }

    /// 0, 1, 2 for X/A, Y/B, Z/C: the coordinate direction of the motion or rotation axis.
    pub fn index(self) -> usize {
        match self {
            Axis::X | Axis::A => 0,
            Axis::Y | Axis::B => 1,
            Axis::Z | Axis::C => 2,
        }
    }

    /// Unit vector of the axis direction (of the rotation axis for A, B, C).
    pub fn unit(self) -> [f64; 3] {
        let mut u = [0.0; 3];
        u[self.index()] = 1.0;
        u
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.letter())
    }
}

/// One ISO 230-1 error element, e.g. `EXX`, `EC0Y`, `EBC`, `EX0C`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ErrorElement {
    /// Direction of the error: X/Y/Z translation or A/B/C rotation about X/Y/Z.
    pub direction: Axis,
    /// The axis whose motion (or location) the error belongs to.
    pub axis: Axis,
    /// True for position-independent location errors (`0` in the name: squareness, axis-line position).
    pub location: bool,
}

/// Why a name is not an error element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{name}` is not an ISO 230-1 error element name ({why}); examples: EXX, EYX, ECX, EC0Y, EB0Z, EA0Z, EXC, EX0C")]
pub struct ElementNameError {
    pub name: String,
    pub why: &'static str,
}

impl ErrorElement {
    /// An error motion (position-dependent) of `axis` in `direction`.
    pub const fn motion(direction: Axis, axis: Axis) -> Self {
        ErrorElement {
            direction,
            axis,
            location: false,
        }
    }

    /// A location (position-independent) error of `axis` in `direction`.
    pub const fn location(direction: Axis, axis: Axis) -> Self {
        ErrorElement {
            direction,
            axis,
            location: true,
        }
    }

    /// Parses `EXX`, `EC0Y`, ... (case-insensitive).
    pub fn parse(name: &str) -> Result<Self, ElementNameError> {
        let err = |why| ElementNameError {
            name: name.to_string(),
            why,
        };
        let chars: Vec<char> = name.trim().chars().collect();
        if chars.first().map(|c| c.to_ascii_uppercase()) != Some('E') {
            return Err(err("must start with E"));
        }
        let (dir, loc, axis) = match chars.len() {
            3 => (chars[1], false, chars[2]),
            4 if chars[2] == '0' => (chars[1], true, chars[3]),
            _ => {
                return Err(err(
                    "must be E + direction + axis, or E + direction + 0 + axis",
                ))
            }
        };
        let direction =
            Axis::from_letter(dir).ok_or_else(|| err("direction must be one of X Y Z A B C"))?;
        let axis = Axis::from_letter(axis).ok_or_else(|| err("axis must be one of X Y Z A B C"))?;
        let el = ErrorElement {
            direction,
            axis,
            location: loc,
        };
        if loc && !el.is_valid_location() {
            return Err(err("not a location error of ISO 230-1 (squareness EC0Y, EB0Z, EA0Z; rotary e.g. EX0C EY0C EA0C EB0C)"));
        }
        Ok(el)
    }

    fn is_valid_location(&self) -> bool {
        if self.axis.is_rotary() {
            // 4 location errors per rotary axis: the two radial offsets and the two tilts of its line.
            self.direction.index() != self.axis.index()
        } else {
            matches!(
                (self.direction, self.axis),
                (Axis::C, Axis::Y) | (Axis::B, Axis::Z) | (Axis::A, Axis::Z)
            )
        }
    }

    /// The ISO 230-1 name.
    pub fn name(&self) -> String {
        if self.location {
            format!("E{}0{}", self.direction.letter(), self.axis.letter())
        } else {
            format!("E{}{}", self.direction.letter(), self.axis.letter())
        }
    }

    /// True for rotational errors (unit µrad); false for translational (unit µm).
    pub fn is_angular(&self) -> bool {
        self.direction.is_rotary()
    }

    /// `"um"` or `"urad"`.
    pub fn unit(&self) -> &'static str {
        if self.is_angular() {
            "urad"
        } else {
            "um"
        }
    }

    /// Factor from the element's unit to SI-ish model units: µm → mm, µrad → rad.
    pub fn to_model_units(&self) -> f64 {
        if self.is_angular() {
            1e-6
        } else {
            1e-3
        }
    }

    /// A short description in words (for reports).
    pub fn describe(&self) -> String {
        let a = self.axis.letter();
        let d = self.direction.letter();
        if self.location {
            return if self.axis.is_rotary() {
                if self.direction.is_rotary() {
                    format!(
                        "tilt of the {a} axis line about {}",
                        dir_letter(self.direction)
                    )
                } else {
                    format!("offset of the {a} axis line in {d}")
                }
            } else {
                match (self.direction, self.axis) {
                    (Axis::C, Axis::Y) => "squareness of Y to X".into(),
                    (Axis::B, Axis::Z) => "squareness of Z to X".into(),
                    _ => "squareness of Z to Y".into(),
                }
            };
        }
        if self.axis.is_rotary() {
            return match (
                self.direction.is_rotary(),
                self.direction.index() == self.axis.index(),
            ) {
                (false, true) => format!("axial error motion of {a}"),
                (false, false) => format!("radial error motion of {a} in {d}"),
                (true, true) => format!("angular positioning error of {a}"),
                (true, false) => format!(
                    "tilt error motion of {a} about {}",
                    dir_letter(self.direction)
                ),
            };
        }
        if !self.direction.is_rotary() {
            if self.direction.index() == self.axis.index() {
                format!("positioning of {a}")
            } else {
                format!("straightness of {a} in {d}")
            }
        } else if self.direction.index() == self.axis.index() {
            format!("roll of {a}")
        } else {
            format!("angular error of {a} about {}", dir_letter(self.direction))
        }
    }
}

fn dir_letter(d: Axis) -> char {
    ['X', 'Y', 'Z'][d.index()]
}

impl fmt::Display for ErrorElement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl Serialize for ErrorElement {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl<'de> Deserialize<'de> for ErrorElement {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        ErrorElement::parse(&s).map_err(serde::de::Error::custom)
    }
}

/// The six error motions of an axis, in the order of the ISO 230-1 tables
/// (three translations X, Y, Z then three rotations A, B, C).
pub fn motion_elements(axis: Axis) -> [ErrorElement; 6] {
    Axis::ALL.map(|d| ErrorElement::motion(d, axis))
}

/// The location errors of an axis: squareness for Y (EC0Y) and Z (EB0Z, EA0Z), none for X
/// (the reference), four for a rotary axis.
pub fn location_elements(axis: Axis) -> Vec<ErrorElement> {
    match axis {
        Axis::X => vec![],
        Axis::Y => vec![ErrorElement::location(Axis::C, Axis::Y)],
        Axis::Z => vec![
            ErrorElement::location(Axis::B, Axis::Z),
            ErrorElement::location(Axis::A, Axis::Z),
        ],
        r => Axis::ALL
            .iter()
            .filter(|d| d.index() != r.index())
            .map(|&d| ErrorElement::location(d, r))
            .collect(),
    }
}

/// The 21 elements of a three-axis machine: 6 motions of X, Y, Z each and 3 squareness errors.
pub fn three_axis_elements() -> Vec<ErrorElement> {
    let mut v = Vec::with_capacity(21);
    for a in [Axis::X, Axis::Y, Axis::Z] {
        v.extend(motion_elements(a));
    }
    for a in [Axis::Y, Axis::Z] {
        v.extend(location_elements(a));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for n in [
            "EXX", "EYX", "ECX", "EC0Y", "EB0Z", "EA0Z", "EXC", "ECC", "EX0C", "EY0C", "EA0C",
            "EB0C",
        ] {
            assert_eq!(ErrorElement::parse(n).unwrap().name(), n);
        }
        assert!(
            ErrorElement::parse("EZ0C").is_err(),
            "axial location of C is not an ISO location error"
        );
        assert!(ErrorElement::parse("EC0X").is_err());
        assert!(ErrorElement::parse("XXX").is_err());
        assert!(ErrorElement::parse("EQX").is_err());
    }

    #[test]
    fn catalogue_sizes() {
        assert_eq!(three_axis_elements().len(), 21);
        assert_eq!(location_elements(Axis::C).len(), 4);
        assert_eq!(
            location_elements(Axis::C)
                .iter()
                .map(|e| e.name())
                .collect::<Vec<_>>(),
            ["EX0C", "EY0C", "EA0C", "EB0C"]
        );
        assert_eq!(ErrorElement::parse("EBX").unwrap().unit(), "urad");
        assert_eq!(
            ErrorElement::parse("EYX").unwrap().describe(),
            "straightness of X in Y"
        );
    }
}
