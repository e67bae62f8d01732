//! What LinuxCNC's interpreter refuses in a block that the rewriter would otherwise correct or
//! copy and report as success: words no code uses, missing or negative words, feeds at zero.
//! Each rule was checked with rs274 (linuxcnc-uspace 2.9.0~pre1), 2026-11-28; docs/methods.md §9.

use super::super::block::{Block, Issue};
use super::super::code::GCode;
use super::super::lexer::Value;
use super::motion::Motion;

/// Why LinuxCNC stops at a G1/G2/G3 move in G94 or G95 mode: a feed rate of zero (no F yet,
/// or F0), or feed per revolution with a spindle speed of zero (rs274: "Cannot do g1 with zero
/// feed rate", "Cannot feed with zero spindle speed in feed per rev mode"). A value the
/// rewriter does not know (`None`, after a line it cannot follow) is not refused.
pub(super) fn zero_feed(
    m: Motion,
    feed: Option<f64>,
    per_rev: bool,
    speed: Option<f64>,
) -> Option<String> {
    if !matches!(m, Motion::Linear | Motion::Cw | Motion::Ccw) {
        return None;
    }
    if feed == Some(0.0) {
        return Some("a feed move with a feed rate of zero (no F word yet, F0, or no F since a G93/G94/G95, which sets it to zero): LinuxCNC stops here (\"zero feed rate\"); set F before the move".into());
    }
    if per_rev && speed == Some(0.0) {
        return Some("feed per revolution (G95) with a spindle speed of zero (no S word yet, or S0): LinuxCNC stops here (\"Cannot feed with zero spindle speed in feed per rev mode\"); set S before the move".into());
    }
    None
}

/// The stops of a block as a whole (not of its motion): negative F, S, T or L; G96 without S;
/// a G2/G3 without axis words; a G53 without axis words and without G0/G1; M codes without the
/// word they need. `axis_words_taken`: G10/G28/G30/G52/G92 take the block's axis words.
pub(super) fn linuxcnc_stops(
    b: &Block,
    has_axis: bool,
    axis_words_taken: bool,
    motion_word: Option<(Motion, usize)>,
    issues: &mut Vec<Issue>,
) {
    // rs274: "Negative f word used", "Negative spindle speed used", "Negative tool id",
    // "Negative l word used"
    for (letter, what) in [
        (b'F', "feed rate"),
        (b'S', "spindle speed"),
        (b'T', "tool number"),
        (b'L', "loop or mode number"),
    ] {
        if let Some(w) = b
            .word(letter)
            .filter(|w| matches!(w.value, Value::Number(v) if v < 0.0))
        {
            issues.push(Issue {
                token: Some(w.token),
                message: format!(
                    "negative {} ({} word): LinuxCNC stops here",
                    what, letter as char
                ),
                poisons_all: false,
            });
        }
    }
    // rs274: "S word missing with G96"
    if let Some(tok) = b.has_g(GCode::G96).filter(|_| b.word(b'S').is_none()) {
        issues.push(Issue {
            token: Some(tok),
            message: "G96 (constant surface speed) without an S word: LinuxCNC stops here (\"S word missing with G96\")".into(),
            poisons_all: false,
        });
    }
    // rs274: "R i j k words all missing for arc", "X and y words missing for arc in xy plane"
    if let Some((Motion::Cw | Motion::Ccw, tok)) = motion_word {
        if !has_axis && !axis_words_taken {
            issues.push(Issue {
                token: Some(tok),
                message: "G2/G3 without an end point (no axis word) and without I, J or K: LinuxCNC stops here (\"R i j k words all missing for arc\" or \"X and y words missing for arc\")".into(),
                poisons_all: false,
            });
        }
    }
    // rs274: "Must use g0 or g1 with g53" for a G53 that moves nothing (a move is checked
    // with its motion in plan.rs)
    if let Some(tok) = b.has_g(GCode::G53).filter(|_| !has_axis) {
        if !matches!(motion_word, Some((Motion::Rapid | Motion::Linear, _))) {
            issues.push(Issue {
                token: Some(tok),
                message: "G53 without an axis word and without G0 or G1 in the block: LinuxCNC stops here (\"Must use g0 or g1 with g53\")".into(),
                poisons_all: false,
            });
        }
    }
    // M codes that need a word (rs274: "No valid P word with M62", "Need to have either a
    // valid P or a valid E word with M66", "Need non-negative Q-word … with M61", "Invalid
    // analog index with M67")
    for &(code, tok) in &b.m {
        let needs = match code {
            61 if b
                .word(b'Q')
                .is_none_or(|w| matches!(w.value, Value::Number(q) if q < 0.0)) =>
            {
                "a Q word of zero or more (the tool number)"
            }
            62..=65 if b.word(b'P').is_none() => "a P word (the output number)",
            19 if b
                .word(b'R')
                .is_some_and(|w| matches!(w.value, Value::Number(r) if !(0.0..=360.0).contains(&r))) =>
            {
                "an R word within 0..360 (the orientation angle)"
            }
            19 if b.word(b'P').is_some_and(
                |w| matches!(w.value, Value::Number(p) if ![0.0, 1.0, 2.0].contains(&p.round()) || (p - p.round()).abs() > 0.001),
            ) =>
            {
                "a P word of 0, 1 or 2 (the direction)"
            }
            66 if b.word(b'P').is_none() && b.word(b'E').is_none() => {
                "a P or E word (the input)"
            }
            67 | 68 if b.word(b'E').is_none() => "an E word (the analog output)",
            _ => continue,
        };
        issues.push(Issue {
            token: Some(tok),
            message: format!("M{code} without {needs}: LinuxCNC stops here"),
            poisons_all: false,
        });
    }
}

/// The first D, E, H, I, J, K, L, P, Q or R word that no code in the block uses: LinuxCNC
/// refuses such a block ("P word with no G2 G3 G4 G10 G64 … to use it"). The rules are those
/// of LinuxCNC's `check_other_codes` (interp_check.cc), restricted to the codes the rewriter
/// follows; each letter was checked with rs274 on random blocks (2026-11-28).
///
/// `motion_to_be` is the motion the block runs, as LinuxCNC's `motion_to_be`: the modal or
/// the block's motion when axis words move (I/J/K count for a full circle), only the block's
/// own motion code when they do not (`R5` or `P1` alone after a G2 are refused) or when
/// G10/G28/G30/G52/G92 take the axis words. A canned cycle or an unknown motion (refused or
/// poisoned elsewhere) is not checked. User M codes (M100–M199) take P and Q.
pub(super) fn unused_word(b: &Block, motion_to_be: Option<Motion>) -> Option<(char, usize)> {
    use super::super::code::GCode::*;
    if matches!(motion_to_be, Some(Motion::Unknown)) {
        return None;
    }
    // most blocks carry none of these words: answer without looking at the block's codes
    // (the closure below asks for several G and M codes per letter)
    if !b"DEHIJKLPQR".iter().any(|&l| b.word(l).is_some()) {
        return None;
    }
    let arc = matches!(motion_to_be, Some(Motion::Cw | Motion::Ccw));
    let g = |c: GCode| b.has_g(c).is_some();
    let m = |k: u32| b.has_m(k).is_some();
    let g10 = g(G10);
    let comp = g(G41) || g(G42) || g(G41_1) || g(G42_1);
    let user_m = b.m.iter().any(|(k, _)| (100..=199).contains(k));
    let used = |l: u8| match l {
        b'D' => comp || g(G96),
        b'E' => m(66) || m(67) || m(68),
        b'H' => g(G43) || g(G43_2),
        b'I' | b'J' => arc || g10,
        b'K' => arc,
        b'L' => g10 || comp || m(66),
        b'P' => {
            arc || g10 || g(G4) || g(G64) || (50..=53).any(m) || (62..=66).any(m) || m(19) || user_m
        }
        b'Q' => g10 || g(G64) || (66..=68).any(m) || m(61) || m(19) || user_m,
        b'R' => arc || g10 || g(G41_1) || g(G42_1) || m(19),
        _ => true,
    };
    // LinuxCNC marks an absent Q word by the value -1, so `Q-1` passes its check (a negative L
    // is refused when read: see `linuxcnc_stops`)
    let sentinel = |l: u8| {
        l == b'Q' && matches!(b.word(l).map(|w| w.value), Some(Value::Number(v)) if v == -1.0)
    };
    b"DEHIJKLPQR"
        .iter()
        .filter(|&&l| !used(l) && !sentinel(l))
        .filter_map(|&l| b.word(l).map(|w| (l as char, w.token)))
        .min_by_key(|&(_, t)| t)
}
