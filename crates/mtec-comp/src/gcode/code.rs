//! G codes by name: the codes of LinuxCNC's dialect the rewriter and the modal-group rules
//! ([`super::modal`]) know, each a variant of [`GCode`] (`G59.1` is [`GCode::G59_1`]), and any
//! other code as [`GCode::Other`].
//!
//! **What it is for**: reading the value of a `G` word into a code ([`GCode::from_word`]),
//! matching on codes by name, and printing a code as a program writes it (`Display`: `G59.1`)
//! for messages. **Not for**: the text of the words in the program — the rewriter never writes
//! a code from this type back over a word it keeps (an unchanged word keeps its bytes,
//! `G01` stays `G01`); and not for the meaning of a code (modal groups are in
//! [`super::modal`], what the rewriter does with a code in `rewrite`).
//!
//! M codes stay plain integers (`M6` is 6): they have no decimal point.

/// Declares [`GCode`] from `name = tenths` pairs (the code times ten: G59.1 → 591); the tenths
/// are only used to read and print codes, never in matches.
macro_rules! gcodes {
    ($($name:ident = $tenths:literal,)*) => {
        /// A G code. Variant `Gn_m` is `Gn.m`. Codes not listed are [`GCode::Other`], holding
        /// the code times ten (G12.3 → 123); [`GCode::from_word`] never puts a listed code
        /// there, so two equal codes compare equal.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[allow(non_camel_case_types)]
        pub enum GCode {
            $($name,)*
            /// A code not listed above, times ten.
            Other(u32),
        }

        impl GCode {
            /// The code from its value times ten (591 → [`GCode::G59_1`]).
            pub(crate) fn from_tenths(tenths: u32) -> GCode {
                match tenths {
                    $($tenths => GCode::$name,)*
                    t => GCode::Other(t),
                }
            }

            /// The code's value times ten ([`GCode::G59_1`] → 591).
            fn tenths(self) -> u32 {
                match self {
                    $(GCode::$name => $tenths,)*
                    GCode::Other(t) => t,
                }
            }
        }
    };
}

gcodes! {
    // motion (group 1), dwell and splines
    G0 = 0, G1 = 10, G2 = 20, G3 = 30, G4 = 40,
    G5 = 50, G5_1 = 51, G5_2 = 52, G5_3 = 53,
    // lathe diameter / radius mode
    G7 = 70, G8 = 80,
    // offsets and tool table
    G10 = 100,
    // planes
    G17 = 170, G17_1 = 171, G18 = 180, G18_1 = 181, G19 = 190, G19_1 = 191,
    // units
    G20 = 200, G21 = 210,
    // reference points
    G28 = 280, G28_1 = 281, G30 = 300, G30_1 = 301,
    // threading, probing
    G33 = 330, G33_1 = 331, G38_2 = 382, G38_3 = 383, G38_4 = 384, G38_5 = 385,
    // cutter radius compensation
    G40 = 400, G41 = 410, G41_1 = 411, G42 = 420, G42_1 = 421,
    // tool length offset
    G43 = 430, G43_1 = 431, G43_2 = 432, G49 = 490,
    // local offset, machine coordinates, work systems
    G52 = 520, G53 = 530,
    G54 = 540, G55 = 550, G56 = 560, G57 = 570, G58 = 580, G59 = 590,
    G59_1 = 591, G59_2 = 592, G59_3 = 593,
    // path control
    G61 = 610, G61_1 = 611, G64 = 640,
    // lathe and canned cycles
    G70 = 700, G71 = 710, G71_1 = 711, G71_2 = 712, G72 = 720, G72_1 = 721, G72_2 = 722,
    G73 = 730, G74 = 740, G76 = 760,
    G80 = 800, G81 = 810, G82 = 820, G83 = 830, G84 = 840, G85 = 850, G86 = 860, G87 = 870,
    G88 = 880, G89 = 890,
    // distance modes
    G90 = 900, G90_1 = 901, G91 = 910, G91_1 = 911,
    // G92 offset
    G92 = 920, G92_1 = 921, G92_2 = 922, G92_3 = 923,
    // feed rate modes, spindle speed modes, canned cycle return
    G93 = 930, G94 = 940, G95 = 950, G96 = 960, G97 = 970, G98 = 980, G99 = 990,
}

/// The value `v` of a G or M word times ten, when it is a code at all: not negative, a whole
/// number of tenths (within 1e-6), and not absurdly large.
pub(crate) fn tenths_of(v: f64) -> Option<u32> {
    let tenths = (v * 10.0).round();
    if v < 0.0 || (v * 10.0 - tenths).abs() > 1e-6 || tenths > 1e7 {
        return None;
    }
    Some(tenths as u32)
}

impl GCode {
    /// The code of a `G` word's value (`59.1` → [`GCode::G59_1`]); None when the value is no
    /// code (negative, more than one decimal).
    pub fn from_word(value: f64) -> Option<GCode> {
        tenths_of(value).map(GCode::from_tenths)
    }
}

impl std::fmt::Display for GCode {
    /// As a program writes it: `G1`, `G59.1` (the shortest form; not the word's own text).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = self.tenths();
        if t.is_multiple_of(10) {
            write!(f, "G{}", t / 10)
        } else {
            write!(f, "G{}.{}", t / 10, t % 10)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_and_printed() {
        assert_eq!(GCode::from_word(59.1), Some(GCode::G59_1));
        assert_eq!(GCode::from_word(1.0), Some(GCode::G1));
        assert_eq!(GCode::from_word(0.0), Some(GCode::G0));
        assert_eq!(GCode::from_word(12.3), Some(GCode::Other(123)));
        assert_eq!(GCode::from_word(-1.0), None);
        assert_eq!(GCode::from_word(1.25), None);
        assert_eq!(GCode::G59_1.to_string(), "G59.1");
        assert_eq!(GCode::G38_2.to_string(), "G38.2");
        assert_eq!(GCode::G90.to_string(), "G90");
        assert_eq!(GCode::Other(123).to_string(), "G12.3");
        assert_eq!(GCode::Other(1000).to_string(), "G100");
        // every listed code reads back as itself
        for t in 0..1000 {
            let c = GCode::from_tenths(t);
            assert_eq!(c.tenths(), t);
            assert_eq!(GCode::from_word(t as f64 / 10.0), Some(c));
        }
    }
}
