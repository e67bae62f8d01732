//! LinuxCNC's modal groups of G and M codes, and the block rules built on them.
//!
//! **What it is for**: refusing a block that LinuxCNC refuses because it holds two codes of one
//! modal group (`G0 G1 X50`, `G90 G91 X10`, `M3 M4`), a group-0 code that uses axis words
//! together with a motion code (`G92 G1 X10`), axis words with `G80`, or more than four M
//! words — with LinuxCNC's meaning in the message, located at the offending word. A rewriter that
//! accepted such a block would guess which code wins; LinuxCNC never runs it.
//! **Not for**: rules that depend on the modal state before the block (`G53` needs G0 or G1 in
//! effect, axis words with no motion mode in effect, a G2 without I/J/K/R, …), word-level rules
//! (two X words), or unknown codes: codes not in the tables below are skipped here and left to
//! the caller.
//!
//! It follows LinuxCNC's documentation, *G-code Overview*, sections "Modal Groups" and
//! "Repeated Items" (docs/src/gcode/overview.adoc), and where the documentation and LinuxCNC
//! 2.9's `rs274` differ, `rs274` (every rule is in the test table below with the message
//! `rs274 -g` printed for the one-line program):
//! - `G92.1`, `G92.2`, `G92.3` are listed in group 0 by the documentation, but `rs274` accepts
//!   them with any other group-0 code (`G4 P1 G92.1`, `G10 L1 P1 Z1 G92.1`) and refuses two of
//!   them together: they form a group of their own here ([`GGroup::OffsetReset`]).
//! - `G80` with another motion code is not a conflict (`G0 G80 X1` moves, `G80 G80` is
//!   accepted): the other motion code is in effect.
//! - `M7 M8` (mist and flood together) is listed as allowed by the documentation, but `rs274`
//!   2.9 refuses it ("Two m codes used from same modal group"): refused here.
//! - M70–M73 (modal state save/restore) share group 7 with the spindle codes in `rs274` 2.9
//!   (`M3 M70`, `M19 M71`, `M70 M72` refused; `M1 M70`, `M70 M9` accepted); the documentation
//!   does not place them.
//! - Order, as `rs274` reports: the words are read left to right and a second code of a group
//!   is reported at once; then the rules between G groups (axis words, G80); the limit of four
//!   M words last ("Too many m codes on line" comes after rs274's G-code checks).
//!
//! Besides the table of hand-written cases, the tests compare [`check_block`] with rs274's
//! verdict on ~1450 random blocks (`tests/data/modal_random_rs274.tsv`).

use super::code::GCode;

/// A G-code modal group (LinuxCNC's numbering in the names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GGroup {
    /// Group 0: non-modal G4 G10 G28 G28.1 G30 G30.1 G52 G53 G92.
    NonModal,
    /// G92.1 G92.2 G92.3: group 0 in the documentation, a group of their own in `rs274` 2.9.
    OffsetReset,
    /// Group 1: motion (G0 G1 G2 G3 G5 G5.1 G5.2 G33 G33.1 G38.x G70–G76 G80–G89).
    Motion,
    /// Group 2: plane selection.
    Plane,
    /// Group 3: distance mode G90/G91.
    Distance,
    /// Group 4: arc IJK distance mode G90.1/G91.1.
    ArcDistance,
    /// Group 5: feed rate mode G93/G94/G95.
    FeedMode,
    /// Group 6: units G20/G21.
    Units,
    /// Group 7: cutter radius compensation.
    CutterComp,
    /// Group 8: tool length offset.
    ToolLength,
    /// Group 10: canned cycle return mode G98/G99.
    ReturnMode,
    /// Group 12: coordinate system G54–G59.3.
    CoordSystem,
    /// Group 13: path control mode G61/G61.1/G64.
    PathControl,
    /// Group 14: spindle speed mode G96/G97.
    SpindleMode,
    /// Group 15: lathe diameter/radius mode G7/G8.
    LatheDiameter,
}

impl GGroup {
    /// What the group means, for messages.
    pub fn meaning(self) -> &'static str {
        match self {
            GGroup::NonModal => "group 0, non-modal codes (G4 G10 G28 G30 G52 G53 G92 …)",
            GGroup::OffsetReset => "the G92 offset reset codes G92.1 G92.2 G92.3",
            GGroup::Motion => "group 1, motion",
            GGroup::Plane => "group 2, plane selection",
            GGroup::Distance => "group 3, distance mode G90/G91",
            GGroup::ArcDistance => "group 4, arc IJK distance mode G90.1/G91.1",
            GGroup::FeedMode => "group 5, feed rate mode G93/G94/G95",
            GGroup::Units => "group 6, units G20/G21",
            GGroup::CutterComp => "group 7, cutter radius compensation",
            GGroup::ToolLength => "group 8, tool length offset",
            GGroup::ReturnMode => "group 10, canned cycle return mode G98/G99",
            GGroup::CoordSystem => "group 12, coordinate system G54-G59.3",
            GGroup::PathControl => "group 13, path control mode G61/G61.1/G64",
            GGroup::SpindleMode => "group 14, spindle speed mode G96/G97",
            GGroup::LatheDiameter => "group 15, lathe diameter mode G7/G8",
        }
    }
}

/// The group of a G code, None for codes not in the table.
pub fn g_group(code: GCode) -> Option<GGroup> {
    use GCode::*;
    use GGroup::*;
    Some(match code {
        G4 | G10 | G28 | G28_1 | G30 | G30_1 | G52 | G53 | G92 => NonModal,
        G92_1 | G92_2 | G92_3 => OffsetReset,
        G0 | G1 | G2 | G3 | G5 | G5_1 | G5_2 | G33 | G33_1 | G38_2 | G38_3 | G38_4 | G38_5 => {
            Motion
        }
        G70 | G71 | G71_1 | G71_2 | G72 | G72_1 | G72_2 | G73 | G74 | G76 => Motion,
        G80 | G81 | G82 | G83 | G84 | G85 | G86 | G87 | G88 | G89 => Motion,
        G17 | G18 | G19 | G17_1 | G18_1 | G19_1 => Plane,
        G90 | G91 => Distance,
        G90_1 | G91_1 => ArcDistance,
        G93 | G94 | G95 => FeedMode,
        G20 | G21 => Units,
        G40 | G41 | G41_1 | G42 | G42_1 => CutterComp,
        G43 | G43_1 | G43_2 | G49 => ToolLength,
        G98 | G99 => ReturnMode,
        G54 | G55 | G56 | G57 | G58 | G59 | G59_1 | G59_2 | G59_3 => CoordSystem,
        G61 | G61_1 | G64 => PathControl,
        G96 | G97 => SpindleMode,
        G7 | G8 => LatheDiameter,
        _ => return None,
    })
}

/// True for the group-0 codes that use axis words (G10 G28 G30 G52 G92): LinuxCNC refuses
/// them in a block with an explicit motion code other than G80.
pub fn g_uses_axis_words(code: GCode) -> bool {
    use GCode::*;
    matches!(code, G10 | G28 | G30 | G52 | G92)
}

/// An M-code modal group (LinuxCNC's numbering in the names).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MGroup {
    /// Group 4: stopping M0 M1 M2 M30 M60.
    Stopping,
    /// Group 5: I/O M62–M68.
    Io,
    /// Group 6: tool change M6 M61.
    ToolChange,
    /// Group 7: spindle M3 M4 M5 M19, and M70–M73 (modal state save/restore) in rs274 2.9.
    Spindle,
    /// Group 8: coolant M7 M8 M9.
    Coolant,
    /// Group 9: override switches M48–M53.
    Overrides,
    /// Group 10: user-defined M100–M199.
    User,
}

impl MGroup {
    pub fn meaning(self) -> &'static str {
        match self {
            MGroup::Stopping => "group 4, stopping (M0 M1 M2 M30 M60)",
            MGroup::Io => "group 5, I/O (M62-M68)",
            MGroup::ToolChange => "group 6, tool change (M6 M61)",
            MGroup::Spindle => {
                "group 7, spindle (M3 M4 M5 M19) and modal state save/restore (M70-M73)"
            }
            MGroup::Coolant => "group 8, coolant (M7 M8 M9)",
            MGroup::Overrides => "group 9, override switches (M48-M53)",
            MGroup::User => "group 10, user-defined (M100-M199)",
        }
    }
}

/// The group of an M code, None for codes not in the table.
pub fn m_group(code: u32) -> Option<MGroup> {
    use MGroup::*;
    Some(match code {
        0 | 1 | 2 | 30 | 60 => Stopping,
        62..=68 => Io,
        6 | 61 => ToolChange,
        3 | 4 | 5 | 19 | 70..=73 => Spindle,
        7..=9 => Coolant,
        48..=53 => Overrides,
        100..=199 => User,
        _ => return None,
    })
}

/// LinuxCNC's limit of M words in one block.
pub const MAX_M_WORDS: usize = 4;

/// Checks one block's G codes (with their token index) and M codes (with their token
/// index) as LinuxCNC does; `axis_words` tells whether the block has any of X Y Z A B C U V W.
/// The error names the token of the word LinuxCNC reports and the rule, with LinuxCNC's message
/// in quotes.
pub fn check_block(
    g_codes: &[(GCode, usize)],
    m_codes: &[(u32, usize)],
    axis_words: bool,
) -> Result<(), (usize, String)> {
    // 1. reading the words left to right: a second code of one group, or a fifth M word
    let (mut gi, mut mi) = (0, 0);
    while gi < g_codes.len() || mi < m_codes.len() {
        let take_g = mi >= m_codes.len() || (gi < g_codes.len() && g_codes[gi].1 <= m_codes[mi].1);
        if take_g {
            let (code, tok) = g_codes[gi];
            gi += 1;
            let Some(group) = g_group(code) else { continue };
            if group == GGroup::Motion && code == GCode::G80 {
                continue;
            }
            if let Some(&(other, _)) = g_codes[..gi - 1].iter().find(|(c, _)| {
                g_group(*c) == Some(group) && !(group == GGroup::Motion && *c == GCode::G80)
            }) {
                return Err((
                    tok,
                    format!(
                        "{} and {} in one block: both are in {}, where only one can be in \
                         effect (LinuxCNC: \"Two g codes used from same modal group\")",
                        other,
                        code,
                        group.meaning()
                    ),
                ));
            }
        } else {
            let (code, tok) = m_codes[mi];
            mi += 1;
            if let Some(group) = m_group(code) {
                if let Some(&(other, _)) = m_codes[..mi - 1]
                    .iter()
                    .find(|(c, _)| m_group(*c) == Some(group))
                {
                    return Err((
                        tok,
                        format!(
                            "M{other} and M{code} in one block: both are in {}, where only one \
                             can be in effect (LinuxCNC: \"Two m codes used from same modal \
                             group\")",
                            group.meaning()
                        ),
                    ));
                }
            }
        }
    }
    // 2. rules between groups
    let motion = g_codes
        .iter()
        .find(|(c, _)| g_group(*c) == Some(GGroup::Motion) && *c != GCode::G80);
    let axis_user = g_codes.iter().find(|(c, _)| g_uses_axis_words(*c));
    if let (Some(&(m, mt)), Some(&(a, at))) = (motion, axis_user) {
        return Err((
            mt.max(at),
            format!(
                "{} and {} in one block: both use axis words, so LinuxCNC cannot tell whose \
                 they are (LinuxCNC: \"Cannot use two g codes that both use axis values\")",
                a, m
            ),
        ));
    }
    if let Some(&(_, t80)) = g_codes.iter().find(|(c, _)| *c == GCode::G80) {
        if axis_words && motion.is_none() && axis_user.is_none() {
            return Err((
                t80,
                "axis words with G80 (cancel canned cycle, no motion) and no code that uses \
                 them (LinuxCNC: \"Cannot use axis values with g80\")"
                    .to_string(),
            ));
        }
    }
    // 3. the number of M words
    if let Some(&(_, tok)) = m_codes.get(MAX_M_WORDS) {
        return Err((
            tok,
            format!(
                "more than {MAX_M_WORDS} M words in one block (LinuxCNC: \"Too many m codes on \
                 line\")"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-line program as the rewriter's block sees it: G codes and M codes with token
    /// indices (each word is one token, in order), and whether it has axis words.
    type Codes = (Vec<(GCode, usize)>, Vec<(u32, usize)>, bool);

    fn block(line: &str) -> Codes {
        let (mut g, mut m, mut axis) = (vec![], vec![], false);
        for (i, w) in line.split_whitespace().enumerate() {
            let (l, v) = w.split_at(1);
            match l {
                "G" => g.push((GCode::from_word(v.parse().unwrap()).unwrap(), i)),
                "M" => m.push((v.parse().unwrap(), i)),
                "X" | "Y" | "Z" | "A" | "B" | "C" | "U" | "V" | "W" => axis = true,
                _ => {}
            }
        }
        (g, m, axis)
    }

    /// Golden: each one-line program was run with `rs274 -g` (LinuxCNC 2.9.0~pre1, Debian
    /// linuxcnc-uspace); `None` = rs274 accepted it (or stopped only for a reason outside this
    /// module, noted), `Some((word index, fragment))` = rs274 refused it with the message
    /// quoted in the comment.
    type Expected = Option<(usize, &'static str)>;
    const GOLDEN: &[(&str, Expected)] = &[
        // "Two g codes used from same modal group"
        ("G0 G1 X50", Some((1, "group 1"))),
        ("G90 G91 X10", Some((1, "group 3"))),
        ("G0 G0 X1", Some((1, "group 1"))),
        ("G1 G38.2 X1", Some((1, "group 1"))),
        ("G0 G38.3 X1", Some((1, "group 1"))),
        ("G2 G3 X0 I1", Some((1, "group 1"))),
        ("G33 G76", Some((1, "group 1"))),
        ("G0 G81 X1 Z-1 R1", Some((1, "group 1"))),
        ("G33.1 G0 X1", Some((1, "group 1"))),
        ("G73 G83", Some((1, "group 1"))),
        ("G5 G1", Some((1, "group 1"))),
        ("G5.1 G0", Some((1, "group 1"))),
        ("G5.2 G1", Some((1, "group 1"))),
        ("G70 G0", Some((1, "group 1"))),
        ("G71.1 G0", Some((1, "group 1"))),
        ("G72.2 G1", Some((1, "group 1"))),
        ("G74 G0", Some((1, "group 1"))),
        ("G0 G80 G1 X1", Some((2, "group 1"))),
        ("G17 G18", Some((1, "group 2"))),
        ("G17.1 G17", Some((1, "group 2"))),
        ("G90.1 G91.1", Some((1, "group 4"))),
        ("G93 G94", Some((1, "group 5"))),
        ("G93 G95", Some((1, "group 5"))),
        ("G20 G21", Some((1, "group 6"))),
        ("G20 G20", Some((1, "group 6"))),
        ("G40 G41", Some((1, "group 7"))),
        ("G41.1 G42.1", Some((1, "group 7"))),
        ("G43 G49", Some((1, "group 8"))),
        ("G43 H1 G43.1 Z1", Some((2, "group 8"))),
        ("G43.2 G49", Some((1, "group 8"))),
        ("G98 G99", Some((1, "group 10"))),
        ("G54 G55", Some((1, "group 12"))),
        ("G61 G64", Some((1, "group 13"))),
        ("G64 G61.1", Some((1, "group 13"))),
        ("G96 G97 S100", Some((1, "group 14"))),
        ("G7 G8", Some((1, "group 15"))),
        ("G4 P1 G10 L2 P1 X1", Some((2, "group 0"))),
        ("G52 G92 X1", Some((1, "group 0"))),
        ("G4 G53 G0 X1", Some((1, "group 0"))),
        ("G28 G30", Some((1, "group 0"))),
        ("G28.1 G30.1", Some((1, "group 0"))),
        ("G53 G28.1", Some((1, "group 0"))),
        ("G92.1 G92.2", Some((1, "G92.1 G92.2 G92.3"))),
        ("G92.1 G92.3", Some((1, "G92.1 G92.2 G92.3"))),
        // reported before the axis-word rule, at the first repeated group
        ("G1 F10 G38.2 X1 G28", Some((2, "group 1"))),
        // "Two m codes used from same modal group"
        ("M3 M4", Some((1, "group 7"))),
        ("M3 M3", Some((1, "group 7"))),
        ("M3 M19", Some((1, "group 7"))),
        ("M7 M8", Some((1, "group 8"))), // allowed by the documentation, refused by rs274 2.9
        ("M8 M9", Some((1, "group 8"))),
        ("M0 M1", Some((1, "group 4"))),
        ("M2 M30", Some((1, "group 4"))),
        ("M60 M0", Some((1, "group 4"))),
        ("M48 M49", Some((1, "group 9"))),
        ("M52 M53", Some((1, "group 9"))),
        ("M62 P1 M63 P2", Some((2, "group 5"))),
        ("M66 P1 L0 M62 P1", Some((3, "group 5"))),
        ("M6 T1 M61 Q1", Some((2, "group 6"))),
        ("M6 T1 M6", Some((2, "group 6"))),
        ("M70 M72", Some((1, "M70-M73"))),
        ("M3 M70", Some((1, "M70-M73"))),
        ("M19 M71", Some((1, "M70-M73"))),
        ("M70 M9", None),
        ("M70 M48", None),
        // the fifth M word: same group is reported first, else "Too many m codes on line"
        ("M3 M7 M48 M62 P1 M5", Some((5, "group 7"))),
        ("M3 M7 M48 M62 P1 M0", Some((5, "more than 4 M words"))),
        ("M0 M3 M7 M48 M62 P1", Some((4, "more than 4 M words"))),
        ("M6 M3 M7 M48 M0", Some((4, "more than 4 M words"))),
        // "Cannot use two g codes that both use axis values"
        ("G92 G1 X10", Some((1, "both use axis words"))),
        ("G28 G1 X1", Some((1, "both use axis words"))),
        ("G28 G0", Some((1, "both use axis words"))),
        ("G30 G1 X1 F1", Some((1, "both use axis words"))),
        ("G52 X1 G0", Some((2, "both use axis words"))),
        ("G1 G10 L2 P1 X1", Some((1, "both use axis words"))),
        ("G10 L20 P1 X0 G1 F1", Some((4, "both use axis words"))),
        ("G92 X1 G80 G0", Some((3, "both use axis words"))),
        // "Cannot use axis values with g80"
        ("G80 X10", Some((0, "G80"))),
        ("G80 A1", Some((0, "G80"))),
        ("G80 G4 P1 X1", Some((0, "G80"))),
        ("G80 G53 X1", Some((0, "G80"))),
        // accepted by rs274
        ("G0 G80 X1", None),
        ("G80 G0 X1", None),
        ("G80 G0 G80 X1", None),
        ("G80 G80", None),
        ("G80 F100", None),
        ("G80 G92 X10", None),
        ("G92 X1 G80", None),
        ("G53 G0 X1", None),
        ("G0 G53 X1", None),
        ("G4 P1 G1 X1 F1", None),
        ("G0 G4 P1 X1", None),
        ("G28.1 G0 X1", None),
        ("G30.1 G1 X1 F1", None),
        ("G92.1 G0 X1", None),
        ("G92.2 G1 X1 F1", None),
        ("G4 P1 G92.1", None),
        ("G28.1 G92.1", None),
        ("G10 L1 P1 Z1 G92.1", None),
        ("G92.3 G52 X1", None),
        ("G92 G92.1", None), // rs274 then stops for "All axes missing with g52 or g92"
        ("G92.1 G17", None),
        ("G92.1 G54", None),
        ("G92.1 G61.1", None),
        ("G90 G90.1", None),
        ("G91 G91.1", None),
        ("G4 G43 P1", None),
        ("M5 M30", None),
        ("M1 M70", None),
        ("M3 M7 M48 M62 P1", None),
        ("M6 T1 M3 M8 M48", None),
        ("G81 G80 X1 Z-1 R1", None), // rs274 then stops for "Cannot feed with zero feed rate"
    ];

    #[test]
    fn every_rule_as_rs274_decides() {
        for (line, want) in GOLDEN {
            let (g, m, axis) = block(line);
            let got = check_block(&g, &m, axis);
            match (want, &got) {
                (None, Ok(())) => {}
                (Some((tok, frag)), Err((t, msg))) => {
                    assert_eq!(t, tok, "{line}: {msg}");
                    assert!(msg.contains(frag), "{line}: {msg}");
                    assert!(msg.contains("(LinuxCNC: \""), "{line}: {msg}");
                }
                _ => panic!("{line}: expected {want:?}, got {got:?}"),
            }
        }
        assert!(GOLDEN.len() >= 90);
    }

    /// rs274's verdict on random blocks: where rs274 gives one of this module's messages, the
    /// same rule must refuse the block; where rs274 accepts it, so must [`check_block`]; where
    /// rs274 stops for another reason first, a refusal here must be the M-word limit (rs274
    /// checks it after its other G-code rules).
    #[test]
    fn random_blocks_agree_with_rs274() {
        let text = include_str!("../../tests/data/modal_random_rs274.tsv");
        let rule = |s: &str| {
            [
                ("Two g codes used from same modal group", 0),
                ("Two m codes used from same modal group", 0),
                ("Cannot use two g codes that both use axis values", 1),
                ("Cannot use axis values with g80", 2),
                ("Too many m codes on line", 3),
            ]
            .iter()
            .find(|(m, _)| s.contains(m))
            .map(|(_, r)| *r)
        };
        let (mut refused, mut accepted) = (0, 0);
        for row in text.lines().filter(|l| !l.starts_with("%%")) {
            let (line, msg) = row.split_once('\t').unwrap();
            let (g, m, axis) = block(line);
            let got = check_block(&g, &m, axis);
            match (rule(msg), &got) {
                (Some(r), Err((_, e))) => {
                    assert_eq!(rule(e), Some(r), "{line}: rs274 {msg}, mtec {e}");
                    refused += 1;
                }
                (None, Ok(())) => accepted += 1,
                (None, Err((_, e))) if !msg.is_empty() => {
                    assert_eq!(rule(e), Some(3), "{line}: rs274 {msg}, mtec {e}")
                }
                _ => panic!("{line}: rs274 {msg:?}, mtec {got:?}"),
            }
        }
        assert!(
            refused > 400 && accepted > 500,
            "{refused} refused, {accepted} accepted"
        );
    }

    use proptest::strategy::Strategy;

    proptest::proptest! {
        /// Any codes, in any order and number: an answer, never a panic, and a refusal always
        /// names one of the block's own tokens.
        #[test]
        fn never_panics(
            g in proptest::collection::vec((0u32..1000).prop_map(GCode::from_tenths), 0..6),
            m in proptest::collection::vec(0u32..200, 0..7),
            axis in proptest::bool::ANY,
        ) {
            let g: Vec<(GCode, usize)> = g.into_iter().enumerate().map(|(i, c)| (c, 2 * i)).collect();
            let m: Vec<(u32, usize)> = m.into_iter().enumerate().map(|(i, c)| (c, 2 * i + 1)).collect();
            if let Err((tok, msg)) = check_block(&g, &m, axis) {
                proptest::prop_assert!(g.iter().map(|c| c.1).chain(m.iter().map(|c| c.1)).any(|t| t == tok));
                proptest::prop_assert!(msg.contains("(LinuxCNC: \""));
            }
        }
    }

    #[test]
    fn tables() {
        use GCode::*;
        assert_eq!(g_group(G59_1), Some(GGroup::CoordSystem));
        assert_eq!(g_group(G38_2), Some(GGroup::Motion));
        assert_eq!(g_group(G92_1), Some(GGroup::OffsetReset));
        assert_eq!(g_group(G53), Some(GGroup::NonModal));
        assert_eq!(g_group(Other(123)), None); // unknown: left to the caller
        assert_eq!(m_group(19), Some(MGroup::Spindle));
        assert_eq!(m_group(150), Some(MGroup::User));
        assert_eq!(m_group(72), Some(MGroup::Spindle));
        assert_eq!(m_group(98), None);
        assert!(g_uses_axis_words(G92) && !g_uses_axis_words(G53) && !g_uses_axis_words(G92_1));
        // unknown codes never conflict
        assert_eq!(
            check_block(
                &[(Other(123), 0), (Other(123), 1)],
                &[(98, 2), (99, 3)],
                true
            ),
            Ok(())
        );
        assert!(check_block(&[(G59_1, 0), (G54, 1)], &[], false)
            .unwrap_err()
            .1
            .starts_with("G59.1 and G54 in one block"));
    }
}
