//! The modal interpreter: the state the controller holds between blocks (positions, units,
//! distance modes, plane, work system and offsets, tool, motion and feed modes) and how one
//! block changes it, with LinuxCNC's meaning.
//!
//! **What it is for**: [`State::interpret`] reads a block's codes in the controller's order of
//! execution, updates the modes, computes the offsets a G10 / G92 / G52 block sets, and lists
//! the constructs the rewriter cannot follow (unknown codes, canned cycles, a mode that is not
//! known, axis words without a motion mode, …). The state is kept twice where the original and
//! the rewritten program differ: the position each one's commands reach (`prog`, `out`), the
//! offsets each one sets ([`PROG`], [`OUT`]) and the motion mode of the output (`out_motion`).
//! **Not for**: writing text (that is `emit`), computing corrected moves (`plan`), or deciding
//! whether a move can be compensated by the model (`plan`, `check_compensable`); the positions
//! a move reaches are set by the planner and the emitter, which know the rounded words.

// axis loops index several per-axis arrays at once
#![allow(clippy::needless_range_loop)]

use super::super::arc::{self, Plane};
use super::super::block::{Block, Issue};
use super::super::code::GCode;
use super::super::lexer::Value;
use super::super::modal;
use super::super::offsets::work_system_index;
use super::block_checks::{linuxcnc_stops, zero_feed};
use super::options::{BlockDelete, RewriteOptions, Units};
use std::collections::BTreeMap;

pub(super) use super::motion::Motion;

/// The coordinate offsets the controller holds, mm, per axis (`None` = not known).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Frame {
    /// G54 … G59.3 (set from `--offsets`, then by G10 L2 / L20).
    pub(super) work: [[Option<f64>; 3]; 9],
    /// The G92 offset (G92, G52 set it; G92.1, G92.2 zero it). It applies in every work system,
    /// in addition to the work offset; G53 moves ignore it (LinuxCNC's `rs274`).
    pub(super) g92: [Option<f64>; 3],
    /// The G92 offset kept in parameters 5211-5213, which G92.3 restores: set by G92 and G52,
    /// zeroed by G92.1, kept by G92.2 (rs274, 2026-11-28); not known at start (a parameter
    /// file of earlier runs) nor after a G92/G52 that also sets a rotary axis.
    pub(super) g92_saved: [Option<f64>; 3],
}

impl Frame {
    pub(super) fn work_of(&self, system: usize) -> Option<[f64; 3]> {
        let w = self.work.get(system)?;
        Some([w[0]?, w[1]?, w[2]?])
    }
}

/// Index into [`State::frames`]: the offsets as the original program sets them.
pub(super) const PROG: usize = 0;
/// Index into [`State::frames`]: the offsets as the rewritten program sets them.
pub(super) const OUT: usize = 1;

/// Why a block is refused: the token to report (its column) and the message.
pub(super) type Refusal = (Option<usize>, String);

/// What a G10 / G92 / G52 block does to the offsets, computed before it is applied.
#[derive(Debug, Clone)]
pub(super) struct OffsetChange {
    frames: [Frame; 2],
    tool: Option<(u32, f64)>,
}

/// Modal state of the program as the controller would see it; `None` = not known.
#[derive(Debug, Clone)]
pub(super) struct State {
    /// Where the program's commands put the tool, machine frame, mm.
    pub(super) prog: [Option<f64>; 3],
    /// Where the rewritten program's commands put the axes, machine frame, mm (as rounded).
    pub(super) out: [Option<f64>; 3],
    pub(super) units: Option<Units>,
    pub(super) absolute: Option<bool>,
    pub(super) arc_absolute: Option<bool>,
    pub(super) plane: Option<Plane>,
    pub(super) work: Option<usize>,
    pub(super) tool_length_mm: Option<f64>,
    /// The machine stands at `--start-position-mm` as commanded, uncorrected (nothing has been
    /// written yet that corrects it): a feed from there starts off the path by the error there.
    pub(super) start_uncorrected: bool,
    /// G20/G21 changed the units since the tool length offset was applied (G43/G49): LinuxCNC's
    /// interpreter then puts a G53 move elsewhere (it subtracts the offset unconverted).
    pub(super) units_changed_since_tool_length: bool,
    pub(super) selected_tool: Option<u32>,
    pub(super) current_tool: Option<u32>,
    pub(super) motion: Motion,
    pub(super) out_motion: Motion,
    pub(super) cutter_comp: bool,
    pub(super) inverse_time: bool,
    /// G95 (units per revolution) in effect.
    pub(super) feed_per_rev: bool,
    /// The last F value the program set (its units: per minute, per revolution or inverse
    /// time, as the mode it was given in). LinuxCNC's interpreter starts at zero.
    pub(super) feed: Option<f64>,
    /// The last S value the program set (rev/min, or surface speed under G96); zero at start.
    pub(super) spindle_speed: Option<f64>,
    /// Machine angles (deg) of A, B, C where the program's commands put them (`None`: not
    /// known). The rewritten program puts them at the same angles at the end of every move.
    pub(super) rot: [Option<f64>; 3],
    /// Coordinate offsets as the original program sets them ([`PROG`]) and as the rewritten
    /// program does ([`OUT`]). They differ only where an offset is set from the current
    /// position (G92, G10 L20): the rewritten program stands at the corrected position there,
    /// so the controller derives a different offset from the same words.
    pub(super) frames: [Frame; 2],
    /// The tool table's lengths, mm (from `--offsets` / `--tool-table`, then G10 L1).
    pub(super) tools: BTreeMap<u32, f64>,
}

/// What one block asks for, as [`State::interpret`] read it.
#[derive(Debug)]
pub(super) struct Interpreted {
    /// The constructs the rewriter cannot follow, in the order found (the block's own first).
    pub issues: Vec<Issue>,
    /// The block's motion code (G0 G1 G2 G3 G80, or an unsupported motion) and its token.
    pub motion_word: Option<(Motion, usize)>,
    /// G53: the block moves in machine coordinates.
    pub g53: bool,
    /// G10, G28, G30, G52 or G92: the code that takes the block's axis words.
    pub axis_consumer: Option<GCode>,
    /// The block has axis words (or is a full circle written with centre words only).
    pub has_axis: bool,
    /// The motion the axis words command (the block's code or the modal one), when they move.
    pub motion: Option<Motion>,
    /// The axis words move in a mode the interpreter follows (no refusal of its own): the
    /// caller checks next whether the move can be compensated.
    pub axis_words_followed: bool,
    /// The offsets after a G10 / G92 / G52 block (boxed: two frames are ~1 kB, which every
    /// block would otherwise copy when the result is returned and taken apart).
    pub offset_change: Option<Box<OffsetChange>>,
}

impl State {
    /// The state at program start: the controller's power-on modes, the offsets and tools
    /// from the options, positions as far as the options know them.
    pub(super) fn new(opt: &RewriteOptions) -> State {
        State {
            prog: opt
                .start_position_mm
                .map(|p| p.map(Some))
                .unwrap_or([None; 3]),
            out: opt
                .start_position_mm
                .map(|p| p.map(Some))
                .unwrap_or([None; 3]),
            units: Some(opt.default_units),
            absolute: Some(true),
            arc_absolute: Some(false),
            plane: Some(arc::XY),
            work: Some(opt.offsets.active),
            tool_length_mm: Some(0.0),
            units_changed_since_tool_length: false,
            start_uncorrected: opt.start_position_mm.is_some(),
            selected_tool: None,
            current_tool: None,
            motion: Motion::Cancelled,
            out_motion: Motion::Cancelled,
            cutter_comp: false,
            inverse_time: false,
            feed_per_rev: false,
            feed: Some(0.0),
            spindle_speed: Some(0.0),
            rot: opt
                .start_rotary_deg
                .map(|r| r.map(Some))
                .unwrap_or([None; 3]),
            frames: {
                let mut f = Frame {
                    work: [[None; 3]; 9],
                    // the controller's persisted G92 offset is assumed zero at start
                    g92: [Some(0.0); 3],
                    g92_saved: [None; 3],
                };
                for i in 0..9 {
                    if let Some(w) = opt.offsets.work(i) {
                        f.work[i] = w.map(Some);
                    }
                }
                [f, f]
            },
            tools: opt.offsets.tool_length_mm.clone(),
        }
    }

    /// Reads one block into the state after it (the controller's order of execution: feed
    /// mode, F, T, M6, then the G codes' modes, G92.1/G92.2) and says what it asks for
    /// ([`Interpreted`]): its motion, the offsets it sets, and every construct the rewriter
    /// cannot follow, in the order they are found. The offsets it sets are computed here but
    /// applied by the caller ([`State::apply_offsets`]), as are the positions it moves to.
    /// `block_delete`: the operator's switch; `kinematic`: the model has rotary axes.
    pub(super) fn interpret(
        &mut self,
        b: &Block,
        block_delete: BlockDelete,
        kinematic: bool,
    ) -> Interpreted {
        let mut issues: Vec<Issue> = b.issues.clone();
        let axis_letters = [b'X', b'Y', b'Z'];
        let has_xyz = axis_letters.iter().any(|&l| b.word(l).is_some());
        let other_axis = [b'A', b'B', b'C', b'U', b'V', b'W']
            .into_iter()
            .find(|&l| b.word(l).is_some());
        let has_axis = has_xyz || other_axis.is_some() || b.polar.is_some();

        if let Err((tok, message)) = modal::check_block(&b.g, &b.m, has_axis) {
            issues.push(Issue {
                token: Some(tok),
                message,
                poisons_all: true,
            });
        }
        if b.block_delete && block_delete == BlockDelete::Unknown {
            let meaningful = !b.g.is_empty()
                || b.m.iter().any(|(m, _)| matches!(m, 2 | 6 | 30 | 98 | 99))
                || has_axis
                || [b'T', b'H', b'I', b'J', b'K', b'R', b'P']
                    .iter()
                    .any(|&l| b.word(l).is_some());
            if meaningful {
                issues.push(Issue {
                    token: Some(0),
                    message: "block delete '/' on a block with motion or modal codes: whether it runs depends on the operator's switch (give --block-delete on or off)".into(),
                    poisons_all: true,
                });
            }
        }

        // --- classify G codes, in order; collect issues ---------------------------------
        let mut motion_word: Option<(Motion, usize)> = None;
        let mut g53 = false;
        let mut axis_consumer: Option<GCode> = None; // G10, G28, G30, G52, G92 take the axis words
        let mut g92_reset = false;
        let mut g92_zero_saved = false;
        let mut g92_restore = None;
        for &(code, tok) in &b.g {
            use GCode::*;
            match code {
                G0 => motion_word = Some((Motion::Rapid, tok)),
                G1 => motion_word = Some((Motion::Linear, tok)),
                G2 => motion_word = Some((Motion::Cw, tok)),
                G3 => motion_word = Some((Motion::Ccw, tok)),
                // LinuxCNC ignores a G80 in a block with another motion code (`G0 G80 X1`
                // moves; modal.rs lets the pair through), whichever comes first
                G80 => {
                    motion_word.get_or_insert((Motion::Cancelled, tok));
                }
                // rs274: "Dwell time missing with g4" (also for a negative P)
                G4 if b
                    .word(b'P')
                    .is_none_or(|w| matches!(w.value, Value::Number(p) if p < 0.0)) =>
                {
                    issues.push(Issue {
                        token: Some(tok),
                        message: "G4 without a dwell time (a P word of zero or more): LinuxCNC stops here (\"Dwell time missing with g4\"); add P".into(),
                        poisons_all: false,
                    })
                }
                G4 | G17 | G18 | G19 | G20 | G21 | G40 | G43 | G49 | G54 | G55 | G56 | G57
                | G58 | G59 | G59_1 | G59_2 | G59_3 | G61 | G61_1 | G64 | G8 | G90 | G91
                | G90_1 | G91_1 | G94 | G95 | G96 | G97 | G98 | G99 | G28_1 | G30_1 => {}
                G53 => g53 = true,
                G28 | G30 => axis_consumer = Some(code),
                G41 | G41_1 | G42 | G42_1 => issues.push(Issue {
                    token: Some(tok),
                    message: format!(
                        "{code}: cutter radius compensation offsets the path in the controller; compensate the offset path instead"
                    ),
                    poisons_all: false,
                }),
                G93 => {}
                G10 | G92 | G52 => axis_consumer = Some(code),
                // G92.1 and G92.2 zero the G92 offset; G92.1 also zeroes parameters 5211-5219
                G92_1 => {
                    g92_reset = true;
                    g92_zero_saved = true;
                }
                G92_2 => g92_reset = true,
                G92_3 => g92_restore = Some(tok),
                G33 | G33_1 | G38_2 | G38_3 | G38_4 | G38_5 | G73 | G74 | G76 | G81 | G82 | G83
                | G84 | G85 | G86 | G87 | G88 | G89 | G5 | G5_1 | G5_2 | G5_3 => {
                    motion_word = Some((Motion::Unknown, tok));
                    issues.push(Issue {
                        token: Some(tok),
                        message: format!(
                            "{code} (canned cycle, threading, probing or spline) cannot be compensated point by point"
                        ),
                        poisons_all: false,
                    });
                }
                _ => issues.push(Issue {
                    token: Some(tok),
                    message: format!("{code} is not a code the rewriter knows"),
                    poisons_all: true,
                }),
            }
        }
        for &(code, tok) in &b.m {
            if code == 98 || code == 99 {
                issues.push(Issue {
                    token: Some(tok),
                    message: format!("M{code}: subprogram call or return"),
                    poisons_all: true,
                });
            }
            // M70 saves the modal state, M72 restores it (units, distance modes, plane, feed
            // mode, F, S …), M73 restores it when a subroutine returns, M71 invalidates it: the
            // modes after them are not followed here (found 2026-11-28: `M70`, `G91`, `M72`,
            // `G1 X20` was compensated as an incremental move, 10 mm off on LinuxCNC)
            if (70..=73).contains(&code) {
                issues.push(Issue {
                    token: Some(tok),
                    message: format!("M{code}: modal state save/restore (M70-M73) is not followed; flatten the program with --flatten-with rs274"),
                    poisons_all: true,
                });
            }
        }

        // a G2/G3 block with centre words and no axis words is a full circle (LinuxCNC
        // executes `G3 I-50`, and a line `I-50` in modal G2): it moves like any other arc
        let arc_words = [b'I', b'J', b'K'].iter().any(|&l| b.word(l).is_some());
        let mode_now = motion_word.map(|(m, _)| m).unwrap_or(self.motion);
        let has_axis = has_axis
            || (arc_words
                && axis_consumer.is_none()
                && matches!(mode_now, Motion::Cw | Motion::Ccw));

        linuxcnc_stops(
            b,
            has_axis,
            axis_consumer.is_some(),
            motion_word,
            &mut issues,
        );

        // --- modal state changes, in the controller's order of execution ------------------
        let st = &mut *self;
        if b.has_g(GCode::G93).is_some() {
            st.inverse_time = true;
            st.feed_per_rev = false;
        }
        if b.has_g(GCode::G94).is_some() || b.has_g(GCode::G95).is_some() {
            st.inverse_time = false;
            st.feed_per_rev = b.has_g(GCode::G95).is_some();
        }
        // LinuxCNC sets the feed rate to zero on every G93, G94 or G95, even one that does not
        // change the mode (rs274: SET_FEED_MODE then SET_FEED_RATE(0)); an F in the block follows
        if [GCode::G93, GCode::G94, GCode::G95]
            .into_iter()
            .any(|c| b.has_g(c).is_some())
        {
            st.feed = Some(0.0);
        }
        if let Some(f) = b.word(b'F') {
            st.feed = match f.value {
                Value::Number(v) if v.is_finite() && v >= 0.0 => Some(v),
                _ => None,
            };
        }
        if let Some(s) = b.word(b'S') {
            st.spindle_speed = match s.value {
                Value::Number(v) if v.is_finite() && v >= 0.0 => Some(v),
                _ => None,
            };
        }
        if let Some(t) = b.word(b'T') {
            st.selected_tool = match t.value {
                Value::Number(v) if v >= 0.0 && v.fract() == 0.0 && v < 1e9 => Some(v as u32),
                _ => None,
            };
        }
        if b.has_m(6).is_some() {
            st.current_tool = st.selected_tool;
        }
        // M61 Q n puts tool n in the spindle without a change: a later G43 without H takes its
        // length on the controller (checked in LinuxCNC's simulation, MDI and AUTO), although
        // stand-alone rs274 keeps the length of the tool loaded before
        if b.has_m(61).is_some() {
            st.current_tool = match b.word(b'Q').map(|q| q.value) {
                Some(Value::Number(v)) if v >= 0.0 && v.fract() == 0.0 && v < 1e9 => Some(v as u32),
                _ => None,
            };
        }
        for &(code, tok) in &b.g {
            use GCode::*;
            match code {
                G17 => st.plane = Some(arc::XY),
                G18 => st.plane = Some(arc::ZX),
                G19 => st.plane = Some(arc::YZ),
                G20 | G21 => {
                    let units = if code == G20 { Units::Inch } else { Units::Mm };
                    if st.units != Some(units) {
                        st.units_changed_since_tool_length = true;
                    }
                    st.units = Some(units);
                }
                G40 => st.cutter_comp = false,
                G41 | G41_1 | G42 | G42_1 => st.cutter_comp = true,
                G43 => {
                    let tool = match b.word(b'H') {
                        Some(h) => match h.value {
                            Value::Number(v) if v >= 0.0 && v.fract() == 0.0 && v < 1e9 => {
                                Some(v as u32)
                            }
                            _ => None,
                        },
                        None => st.current_tool,
                    };
                    st.tool_length_mm = tool.and_then(|t| st.tools.get(&t).copied());
                    st.units_changed_since_tool_length = false;
                    if st.tool_length_mm.is_none() {
                        let what = match tool {
                            Some(t) => format!("tool {t} has no length: give the machine's tool table (--tool-table) or the length in the offsets file (--offsets, [tool_lengths_mm])"),
                            None => "the tool is not known (no H word and no T… M6 before)".into(),
                        };
                        issues.push(Issue {
                            token: Some(tok),
                            message: format!("G43: {what}"),
                            poisons_all: false,
                        });
                    }
                }
                G49 => {
                    st.tool_length_mm = Some(0.0);
                    st.units_changed_since_tool_length = false;
                }
                G54 | G55 | G56 | G57 | G58 | G59 | G59_1 | G59_2 | G59_3 => {
                    st.work = work_system_index(code);
                    if let Some(i) = st.work.filter(|&i| st.frames[PROG].work_of(i).is_none()) {
                        st.work = None;
                        issues.push(Issue {
                            token: Some(tok),
                            message: format!(
                                "{} is selected but its offset is not known: give it in the offsets file (--offsets, [work_offsets_mm] {} = [x, y, z]) or set all three axes with G10 L2 first; taking it as zero would compensate the wrong place",
                                code,
                                super::super::offsets::WORK_SYSTEMS[i]
                            ),
                            poisons_all: false,
                        });
                    }
                }
                G90 => st.absolute = Some(true),
                G91 => st.absolute = Some(false),
                G90_1 => st.arc_absolute = Some(true),
                G91_1 => st.arc_absolute = Some(false),
                _ => {}
            }
        }
        if g92_reset {
            for f in st.frames.iter_mut() {
                f.g92 = [Some(0.0); 3];
                if g92_zero_saved {
                    f.g92_saved = [Some(0.0); 3];
                }
            }
        }
        if let Some(tok) = g92_restore {
            if st
                .frames
                .iter()
                .all(|f| f.g92_saved.iter().all(Option::is_some))
            {
                for f in st.frames.iter_mut() {
                    f.g92 = f.g92_saved;
                }
            } else {
                issues.push(Issue {
                    token: Some(tok),
                    message: "G92.3 restores the G92 offset from parameters 5211-5219, which this program has not set (no G92, G52 or G92.1 before it; the values of earlier runs are not known here); use G52 or G92 with literal values".into(),
                    poisons_all: true,
                });
            }
        }

        // --- G28 / G30: an intermediate point that moves is a rapid the rewriter cannot
        // compensate (its unnamed axes go on to the reference point in the same block)
        if let Some(code) = axis_consumer.filter(|&c| matches!(c, GCode::G28 | GCode::G30)) {
            let stays = st.absolute == Some(false)
                && b"XYZABCUVW".iter().all(|&l| {
                    b.word(l)
                        .is_none_or(|w| matches!(w.value, Value::Number(v) if v == 0.0))
                });
            if has_axis && !stays {
                issues.push(Issue {
                    token: b.has_g(code),
                    message: format!(
                        "{code} with an intermediate point: the rapid to it cannot be compensated in this block; program the point as a G0 move first and give {code} G91 with zero axis words (e.g. {code} G91 Z0), or use --flatten-with rs274"
                    ),
                    poisons_all: false,
                });
            }
        }

        // --- G10 / G92 / G52: the new offsets, from the state after this block's modes -------
        let mut offset_change = None;
        if let Some(code) =
            axis_consumer.filter(|&c| matches!(c, GCode::G10 | GCode::G52 | GCode::G92))
        {
            let reset = [GCode::G92_1, GCode::G92_2]
                .into_iter()
                .find_map(|c| b.has_g(c));
            if let Some(tok) = reset {
                // LinuxCNC accepts both in one block, in an order of its own: not guessed
                issues.push(Issue {
                    token: Some(tok),
                    message: format!(
                        "{} with {} in one block: write them on separate lines",
                        b.g.iter()
                            .find(|(_, t)| *t == tok)
                            .map_or(GCode::G92_1, |g| g.0),
                        code
                    ),
                    poisons_all: true,
                });
            }
            match self.offset_change(b, code, kinematic) {
                Ok(c) => offset_change = Some(Box::new(c)),
                Err((tok, message)) => issues.push(Issue {
                    token: tok,
                    message,
                    poisons_all: true,
                }),
            }
        }
        let st = &mut *self;

        // --- what the axis words mean ------------------------------------------------------
        let mut motion = None;
        let mut axis_words_followed = false;
        if has_axis && axis_consumer.is_none() {
            let m = motion_word.map(|(m, _)| m).unwrap_or(st.motion);
            motion = Some(m);
            let tok = axis_letters
                .iter()
                .chain([b'A', b'B', b'C', b'U', b'V', b'W', b'I', b'J', b'K'].iter())
                .find_map(|&l| b.word(l))
                .map(|w| w.token)
                .or(b.polar);
            let mut why: Option<String> = None;
            match m {
                Motion::Cancelled => {
                    why = Some(
                        "axis words with no motion mode in effect (after G80 or at program start)"
                            .into(),
                    )
                }
                Motion::Unknown if motion_word.is_none() => {
                    why = Some("axis words in a motion mode the rewriter cannot follow (a canned cycle repeats, or the mode was set by an unsupported line)".into())
                }
                _ => {}
            }
            if why.is_none() && st.cutter_comp && m != Motion::Unknown {
                why = Some("cutter radius compensation (G41/G42) is active: the controller offsets this path".into());
            }
            if why.is_none()
                && st.inverse_time
                && matches!(m, Motion::Linear | Motion::Cw | Motion::Ccw)
                && b.word(b'F').is_none()
            {
                why = Some("inverse-time feed (G93) without an F word on this feed move (LinuxCNC requires one on every G1, G2, G3 block)".into());
            }
            if why.is_none() && !st.inverse_time {
                why = zero_feed(m, st.feed, st.feed_per_rev, st.spindle_speed);
            }
            axis_words_followed = why.is_none();
            if let Some(w) = why {
                issues.push(Issue {
                    token: tok,
                    message: w,
                    poisons_all: false,
                });
            }
        }
        if let Some((m, _)) = motion_word {
            st.motion = m;
        }

        Interpreted {
            issues,
            motion_word,
            g53,
            axis_consumer,
            has_axis,
            motion,
            axis_words_followed,
            offset_change,
        }
    }

    /// Everything a line the rewriter cannot follow may have changed becomes unknown:
    /// positions, modes, offsets, the tool table.
    pub(super) fn poison_all(&mut self) {
        let st = self;
        st.prog = [None; 3];
        st.out = [None; 3];
        st.units = None;
        st.absolute = None;
        st.arc_absolute = None;
        st.plane = None;
        st.work = None;
        st.tool_length_mm = None;
        st.motion = Motion::Unknown;
        st.out_motion = Motion::Unknown;
        st.rot = [None; 3];
        st.feed = None;
        st.spindle_speed = None;
        // the line may have set offsets or the tool table (G10, G92, G52, a subprogram…)
        for f in st.frames.iter_mut() {
            f.work = [[None; 3]; 9];
            f.g92 = [None; 3];
            f.g92_saved = [None; 3];
        }
        st.tools.clear();
    }

    /// The offsets and tool lengths a G10 / G92 / G52 block set (the line itself is copied).
    pub(super) fn apply_offsets(&mut self, c: OffsetChange) {
        self.frames = c.frames;
        if let Some((t, len)) = c.tool {
            self.tools.insert(t, len);
        }
    }

    /// After a G28 / G30 block: the axes it sent to a reference point (all, without axis
    /// words) and the rotary axes are at positions not known here.
    pub(super) fn reference_move(&mut self, b: &Block, has_axis: bool, motion_word: bool) {
        // the rotary axes may go to their reference positions too
        self.rot = [None; 3];
        for (a, l) in [b'X', b'Y', b'Z'].iter().enumerate() {
            if !has_axis || b.word(*l).is_some() {
                self.prog[a] = None;
                self.out[a] = None;
            }
        }
        if motion_word {
            self.out_motion = self.motion;
        }
    }

    /// After a block copied unchanged because of an unsupported construct that does not
    /// poison everything: the axes it names (all three for an arc) are no longer known.
    pub(super) fn copied_unfollowed(
        &mut self,
        b: &Block,
        has_axis: bool,
        motion: Option<Motion>,
        motion_word: bool,
    ) {
        for (a, l) in [b'X', b'Y', b'Z'].iter().enumerate() {
            if b.word(*l).is_some()
                || (has_axis && matches!(motion, Some(Motion::Cw | Motion::Ccw)))
            {
                self.prog[a] = None;
                self.out[a] = None;
            }
        }
        for (k, l) in [b'A', b'B', b'C'].into_iter().enumerate() {
            if b.word(l).is_some() {
                self.rot[k] = None;
            }
        }
        if motion_word {
            self.out_motion = self.motion;
        }
    }

    /// Program stops M2/M30 reset modes as LinuxCNC does.
    pub(super) fn after_block(&mut self, b: &Block) {
        if b.has_m(2).is_some() || b.has_m(30).is_some() {
            let st = self;
            st.work = Some(0);
            st.plane = Some(arc::XY);
            st.absolute = Some(true);
            st.inverse_time = false;
            st.cutter_comp = false;
            st.motion = Motion::Linear;
            // the output program is reset the same way
            st.out_motion = Motion::Linear;
        }
    }

    /// Machine = program coordinate + this, mm: work offset + G92 offset (+ tool length on Z),
    /// as the original program ([`PROG`]) or the rewritten one ([`OUT`]) has set them.
    pub(super) fn offset_mm(&self, axis: usize, g53: bool, frame: usize) -> Option<f64> {
        if g53 {
            return Some(0.0);
        }
        let f = &self.frames[frame];
        let w = f.work[self.work?][axis]? + f.g92[axis]?;
        Some(if axis == 2 {
            w + self.tool_length_mm?
        } else {
            w
        })
    }

    /// The offsets after a G10 (L1, L2, L20), G92 or G52 block, with LinuxCNC's meaning
    /// (checked with its `rs274`): values in the block's units, absolute also in G91, axes not
    /// given keep their offset; G92 and G10 L20 set an offset so that the current position
    /// becomes the given value. Err: the token to report and why the block is refused.
    /// `kinematic`: the model has rotary axes (their offsets set by the program are refused).
    fn offset_change(
        &self,
        b: &Block,
        code: GCode,
        kinematic: bool,
    ) -> Result<OffsetChange, Refusal> {
        let st = self;
        let name = code.to_string();
        let code_tok = b.has_g(code);
        let num = |l: u8| -> Result<Option<(f64, usize)>, Refusal> {
            match b.word(l) {
                None => Ok(None),
                Some(w) => match w.value {
                    Value::Number(v) if v.is_finite() => Ok(Some((v, w.token))),
                    _ => Err((
                        Some(w.token),
                        format!("{name}: the {} word has no literal value here", l as char),
                    )),
                },
            }
        };
        let int = |l: u8| -> Result<Option<(i64, usize)>, Refusal> {
            match num(l)? {
                None => Ok(None),
                Some((v, t)) if v.fract() == 0.0 && v.abs() < 1e9 => Ok(Some((v as i64, t))),
                Some((v, t)) => Err((
                    Some(t),
                    format!("{name}: {}{v} is not an integer", l as char),
                )),
            }
        };
        let Some(units) = st.units else {
            return Err((
                code_tok,
                format!("{name}: the units (G20/G21) are not known here"),
            ));
        };
        if kinematic {
            if let Some(w) = [b'A', b'B', b'C'].into_iter().find_map(|l| b.word(l)) {
                return Err((
                    Some(w.token),
                    format!("{name} with a rotary axis word: rotary offsets set by the program are not followed (give them in the offsets file, [rotary_offsets_deg])"),
                ));
            }
        }
        let scale = units.mm_per_unit();
        let mut xyz = [None; 3];
        for (a, l) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            xyz[a] = num(l)?.map(|(v, _)| v * scale);
        }
        let mut frames = st.frames;
        let pos = [st.prog, st.out];
        // the current position of axis `a` in the frame of the program `f`, less the given
        // value: the offset that makes the position read as the value
        let from_position = |f: usize, a: usize, v: f64, g92: bool| -> Option<f64> {
            let tool = if a == 2 { st.tool_length_mm? } else { 0.0 };
            let other = if g92 {
                st.frames[f].work[st.work?][a]?
            } else {
                st.frames[f].g92[a]?
            };
            Some(pos[f][a]? - other - tool - v)
        };
        let not_known = |a: usize| {
            (
                b.word([b'X', b'Y', b'Z'][a]).map(|w| w.token),
                format!(
                    "{name} sets an offset from the current position, which is not known here for {} (program an absolute move first, or give where the machine stands with --start-position-mm; the work offset, G92 offset and tool length in effect must be known too)",
                    ["X", "Y", "Z"][a]
                ),
            )
        };
        match code {
            GCode::G52 | GCode::G92 => {
                let any_axis = [b'X', b'Y', b'Z', b'A', b'B', b'C', b'U', b'V', b'W']
                    .iter()
                    .any(|&l| b.word(l).is_some());
                if !any_axis {
                    return Err((code_tok, format!("{name} without axis words (LinuxCNC: \"All axes missing with g52 or g92\")")));
                }
                for (a, v) in xyz.iter().enumerate() {
                    let Some(v) = *v else { continue };
                    for f in [PROG, OUT] {
                        frames[f].g92[a] = if code == GCode::G52 {
                            Some(v)
                        } else {
                            Some(from_position(f, a, v, true).ok_or_else(|| not_known(a))?)
                        };
                    }
                }
                // the offset goes to parameters 5211-5219 too (G92.3 restores it); a rotary
                // part of it is not followed here
                let rotary = [b'A', b'B', b'C'].iter().any(|&l| b.word(l).is_some());
                for f in [PROG, OUT] {
                    frames[f].g92_saved = if rotary { [None; 3] } else { frames[f].g92 };
                }
                Ok(OffsetChange { frames, tool: None })
            }
            _ => {
                let Some((l, l_tok)) = int(b'L')? else {
                    return Err((code_tok, "G10 without an L word".into()));
                };
                match l {
                    1 => {
                        let Some((p, p_tok)) = int(b'P')? else {
                            return Err((code_tok, "G10 L1 without a P word (the tool number)".into()));
                        };
                        if p < 1 {
                            return Err((Some(p_tok), format!("G10 L1 P{p}: not a tool number")));
                        }
                        if let Some(l) = [b'X', b'Y', b'A', b'B', b'C', b'U', b'V', b'W']
                            .into_iter()
                            .find(|&l| b.word(l).is_some())
                        {
                            return Err((
                                b.word(l).map(|w| w.token),
                                format!("G10 L1 sets a tool offset along {}: only tool lengths (Z) are followed", l as char),
                            ));
                        }
                        // the active tool length offset keeps its value until the next G43
                        Ok(OffsetChange {
                            frames,
                            tool: xyz[2].map(|z| (p as u32, z)),
                        })
                    }
                    2 | 20 => {
                        let Some((p, p_tok)) = int(b'P')? else {
                            return Err((code_tok, format!("G10 L{l} without a P word (the coordinate system)")));
                        };
                        if !(0..=9).contains(&p) {
                            return Err((Some(p_tok), format!("G10 L{l} P{p}: P must be 0 (the active system) to 9 (G59.3)")));
                        }
                        // rs274: "I J words not allowed with G10 L2"
                        if let Some(w) = b.word(b'I').or(b.word(b'J')) {
                            return Err((Some(w.token), format!("G10 L{l} with an I or J word: LinuxCNC stops here (\"I J words not allowed with G10 L2\")")));
                        }
                        if let Some((r, r_tok)) = num(b'R')? {
                            if r != 0.0 {
                                return Err((Some(r_tok), format!("G10 L{l} R{r} rotates the coordinate system: rotation is not supported")));
                            }
                        }
                        let n = if p == 0 {
                            st.work.ok_or((
                                Some(p_tok),
                                format!("G10 L{l} P0: the active coordinate system is not known here"),
                            ))?
                        } else {
                            (p - 1) as usize
                        };
                        for (a, v) in xyz.iter().enumerate() {
                            let Some(v) = *v else { continue };
                            for f in [PROG, OUT] {
                                frames[f].work[n][a] = if l == 2 {
                                    Some(v)
                                } else {
                                    Some(from_position(f, a, v, false).ok_or_else(|| not_known(a))?)
                                };
                            }
                        }
                        Ok(OffsetChange { frames, tool: None })
                    }
                    _ => Err((
                        Some(l_tok),
                        format!("G10 L{l} (tool table or offsets from the current position or probe) is not supported; only G10 L1, L2 and L20 with literal values are followed"),
                    )),
                }
            }
        }
    }
}
