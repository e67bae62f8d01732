//! Closed sets of named choices (a table format, a method, a policy): the names the command
//! line and a project file give them, with the one line the command's help shows beside each,
//! in one place for every front end.
//!
//! The choices of this crate's own options implement [`Choice`] beside their type (e.g.
//! `ops::compensate_table::Format`); those of the numerical crates do here.

use mtec_comp::gcode::tooltable::MachineUnits;
use mtec_comp::gcode::{OnUnsupported, Units};
use mtec_comp::map::Outside;
use mtec_comp::thermal_offset::OutsidePolicy;
use mtec_measure::air::AirFormula;

/// A closed set of named values.
pub trait Choice: Copy + Send + Sync + 'static {
    /// Every value, in the order a listing shows them.
    const ALL: &'static [Self];

    /// The value's name (`sinumerik-cec`, `pass-through-with-warning`, ...).
    fn name(self) -> &'static str;

    /// One line on the value, shown beside its name in a listing ("": none).
    fn help(self) -> &'static str {
        ""
    }

    /// The value named `name`.
    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|c| c.name() == name)
    }
}

impl Choice for OnUnsupported {
    const ALL: &'static [Self] = &[OnUnsupported::Refuse, OnUnsupported::PassThroughWithWarning];

    fn name(self) -> &'static str {
        match self {
            OnUnsupported::Refuse => "refuse",
            OnUnsupported::PassThroughWithWarning => "pass-through-with-warning",
        }
    }
}

impl Choice for Units {
    const ALL: &'static [Self] = &[Units::Mm, Units::Inch];

    fn name(self) -> &'static str {
        match self {
            Units::Mm => "mm",
            Units::Inch => "inch",
        }
    }
}

impl Choice for MachineUnits {
    const ALL: &'static [Self] = &[MachineUnits::Mm, MachineUnits::Inch];

    fn name(self) -> &'static str {
        match self {
            MachineUnits::Mm => "mm",
            MachineUnits::Inch => "inch",
        }
    }
}

impl Choice for OutsidePolicy {
    const ALL: &'static [Self] = &[OutsidePolicy::Refuse, OutsidePolicy::Fade];

    fn name(self) -> &'static str {
        match self {
            OutsidePolicy::Refuse => "refuse",
            OutsidePolicy::Fade => "fade",
        }
    }
}

impl Choice for Outside {
    const ALL: &'static [Self] = &[Outside::Clamp, Outside::Extrapolate, Outside::Refuse];

    fn name(self) -> &'static str {
        Outside::name(self)
    }
}

impl Choice for AirFormula {
    const ALL: &'static [Self] = &[
        AirFormula::Ciddor,
        AirFormula::Edlen,
        AirFormula::BonschPotulski,
    ];

    fn name(self) -> &'static str {
        AirFormula::name(self)
    }

    fn help(self) -> &'static str {
        match self {
            AirFormula::Ciddor => "Ciddor (1996)",
            AirFormula::Edlen => "updated Edlén (Birch & Downs 1993/1994)",
            AirFormula::BonschPotulski => "updated Edlén with CO2 (Bönsch & Potulski 1998)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every value's name is unique and names it back.
    fn round_trip<T: Choice + PartialEq + std::fmt::Debug>() {
        for (i, c) in T::ALL.iter().enumerate() {
            assert_eq!(T::from_name(c.name()), Some(*c));
            assert!(T::ALL[..i].iter().all(|o| o.name() != c.name()));
        }
    }

    #[test]
    fn names_round_trip() {
        round_trip::<OnUnsupported>();
        round_trip::<Units>();
        round_trip::<MachineUnits>();
        round_trip::<OutsidePolicy>();
        round_trip::<Outside>();
        round_trip::<AirFormula>();
        round_trip::<crate::ops::compensate_table::Format>();
        round_trip::<crate::ops::compensate_thermal_offset::Format>();
        round_trip::<crate::ops::volumetric::Form>();
        round_trip::<crate::ops::sensitivity::MethodKind>();
    }
}
