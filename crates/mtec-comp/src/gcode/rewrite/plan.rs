//! Planning a motion block: one block turned into corrected pieces.
//!
//! **What it is for**: the target of a move in machine coordinates (from its words and the
//! interpreter's state) and the pieces it is written as: the correction at its end and along
//! it, a straight move split until the bound of each piece's path error is within
//! `--tolerance-um`, an arc kept whole when its bound allows it or else cut into chords (the
//! numbers are the [`Planner`](super::planner::Planner)'s), a move of a rotary axis handed to
//! `rotary_move`; also the refusals of moves the model cannot compensate
//! ([`Rewriter::check_compensable`]).
//! **Not for**: the modal state and how a block changes it (`interp`), or the text of the
//! pieces (`emit`: the planner hands them to [`Rewriter::emit_pieces`]).

// axis loops index several per-axis arrays at once (target, correction, offsets, words)
#![allow(clippy::needless_range_loop)]

use super::super::arc::{center_arc_limit_mm, Arc, CENTER_ARC_MIN_RADIUS_MM};
use super::super::block::{Block, Issue};
use super::super::code::GCode;
use super::super::lexer::Value;
use super::block_checks::unused_word;
use super::interp::{Motion, OUT, PROG};
use super::options::{rounding_in_effect_um, Units};
use super::piece::{dist, Piece, RotaryMove};
use super::report::{GcodeError, ProblemKind};
use super::rewriter::Rewriter;

impl Rewriter<'_> {
    /// Refusals of a move the interpreter follows but the rewriter cannot compensate: U, V, W
    /// words, a rotary axis the model does not have or an arc that turns one, polar
    /// coordinates, and words computed from parameters that could not be evaluated. Pushed
    /// after the interpreter's issues (the first by column is reported).
    pub(super) fn check_compensable(&self, b: &Block, m: Motion, issues: &mut Vec<Issue>) {
        let tok = [b'X', b'Y', b'Z']
            .iter()
            .chain([b'A', b'B', b'C', b'U', b'V', b'W', b'I', b'J', b'K'].iter())
            .find_map(|&l| b.word(l))
            .map(|w| w.token)
            .or(b.polar);
        let mut why: Option<String> = None;
        // the word a refusal points at, when it is not the first axis word
        let mut why_tok: Option<usize> = None;
        let rotary = self.planner.view.rotary_axes();
        // a rotary word the model does not have is harmless when it repeats the angle the
        // axis stands at (`A0.` in every block of some posts): then it is copied unchanged
        let moved_rotary = [b'A', b'B', b'C']
            .into_iter()
            .enumerate()
            .find(|&(k, l)| b.word(l).is_some() && (rotary[k] || !self.rotary_stays(b, k)));
        if let Some(l) = [b'U', b'V', b'W']
            .into_iter()
            .find(|&l| b.word(l).is_some())
        {
            why = Some(format!(
                "axis {} moves: U, V and W (linear axes parallel to X, Y, Z) are in no chain mtec models; only X, Y, Z and the model's rotary axes are compensated",
                l as char
            ));
            why_tok = b.word(l).map(|w| w.token);
        } else if let Some((k, l)) = moved_rotary {
            why_tok = b.word(l).map(|w| w.token);
            if !rotary[k] {
                why = Some(match self.planner.view.kinematics() {
                    Some(kin) => format!(
                        "axis {} moves but the model's machine (chain `{}`) has no {} axis",
                        l as char,
                        kin.chain(),
                        l as char
                    ),
                    None => format!(
                        "axis {} moves but the error model has no rotary axes (a kinematic model, `mtec.kinematic-model/1`, of a chain with {} compensates it; a word that only repeats the angle the axis stands at is copied, given that angle with --start-rotary-deg)",
                        l as char, l as char
                    ),
                });
            } else if matches!(m, Motion::Cw | Motion::Ccw) {
                why = Some(format!(
                    "an arc that also turns the rotary axis {} is not compensated (write it as straight moves)",
                    l as char
                ));
            }
        } else if b.polar.is_some() {
            why = Some("polar coordinates (@ ^) are not supported".into());
        }
        if why.is_none() {
            for l in [
                b'X', b'Y', b'Z', b'A', b'B', b'C', b'I', b'J', b'K', b'R', b'P',
            ] {
                if l == b'P' && !matches!(m, Motion::Cw | Motion::Ccw) {
                    continue;
                }
                if let Some(w) = b.word(l) {
                    if w.value == Value::Computed {
                        issues.push(Issue {
                            token: Some(w.token),
                            message: format!(
                                "{} word with a parameter or expression in a motion block",
                                l as char
                            ),
                            poisons_all: false,
                        });
                    }
                }
            }
        }
        if let Some(w) = why {
            issues.push(Issue {
                token: why_tok.or(tok),
                message: w,
                poisons_all: false,
            });
        }
        if let Some((letter, token)) = unused_word(b, Some(m)) {
            issues.push(Issue {
                token: Some(token),
                message: format!(
                    "{letter} word in a {} block with no code that uses it: LinuxCNC refuses the block (\"{letter} word with no ... to use it\"); remove it",
                    if matches!(m, Motion::Cw | Motion::Ccw) { "G2/G3" } else { "G0/G1" }
                ),
                poisons_all: false,
            });
        }
    }

    /// Plans one move: its target from the words and the state, the corrections, the pieces
    /// (split, arcs kept or linearised, rotary moves), then has them written.
    pub(super) fn motion_block(
        &mut self,
        b: &Block,
        body: &[u8],
        m: Motion,
        motion_tok: Option<usize>,
        g53: bool,
    ) -> Result<(), GcodeError> {
        self.rot_move = None;
        let first_axis_tok = [b'X', b'Y', b'Z', b'A', b'B', b'C']
            .iter()
            .find_map(|&l| b.word(l))
            .map(|w| w.token);
        let col = self.column_of(first_axis_tok.or(motion_tok));
        let (Some(units), Some(absolute)) = (self.st.units, self.st.absolute) else {
            let d = self.diag(
                col,
                ProblemKind::Unsupported,
                "units or distance mode not known here (after an unsupported line)".into(),
            );
            self.unsupported(d)?;
            self.st.prog = [None; 3];
            self.st.out = [None; 3];
            return Ok(());
        };
        if g53 && !absolute {
            let d = self.diag(
                col,
                ProblemKind::Syntax,
                "G53 needs absolute distance mode (G90)".into(),
            );
            return self.unsupported(d);
        }
        if g53 && !matches!(m, Motion::Rapid | Motion::Linear) {
            let d = self.diag(
                col,
                ProblemKind::Syntax,
                "G53 needs G0 or G1 (LinuxCNC: \"Must use g0 or g1 with g53\")".into(),
            );
            return self.unsupported(d);
        }
        if g53
            && self.st.units_changed_since_tool_length
            && self.st.tool_length_mm.is_some_and(|l| l != 0.0)
        {
            // found with rs274 (linuxcnc-uspace 2.9): after G43 in mm and G20, `G53 G0 Z1`
            // goes to Z −24.4 in for a 25.4 mm tool, not to machine Z 1 in
            let d = self.diag(
                col,
                ProblemKind::Unsupported,
                "G53 with a tool length offset applied before a G20/G21 change: LinuxCNC's interpreter subtracts that offset in the wrong units, so the move does not go where G53 says; apply G43 again after the unit change (or G49 before the G53)".into(),
            );
            return self.unsupported(d);
        }
        self.g53 = g53;
        let scale = units.mm_per_unit();
        // program coordinates → machine: `offsets` as the original program has set them (its
        // targets), `out_offsets` as the rewritten program has (its written words)
        let mut offsets = [0.0; 3];
        let mut out_offsets = [0.0; 3];
        for a in 0..3 {
            match (
                self.st.offset_mm(a, g53, PROG),
                self.st.offset_mm(a, g53, OUT),
            ) {
                (Some(o), Some(oo)) => {
                    offsets[a] = o;
                    out_offsets[a] = oo;
                }
                _ => {
                    let frame = &self.st.frames[PROG];
                    let d = self.diag(
                        col,
                        ProblemKind::Unsupported,
                        match self.st.work {
                            Some(i) if frame.work_of(i).is_none() => format!(
                                "work offset {} (in effect) is not known: give it in the offsets file (--offsets, [work_offsets_mm]) or set all three axes with G10 L2",
                                super::super::offsets::WORK_SYSTEMS[i]
                            ),
                            Some(_) if frame.g92.iter().any(|g| g.is_none()) => "the G92/G52 offset is not known here (after an unsupported line): set it with G52 or G92 with literal values, or zero it with G92.1".into(),
                            _ => "work offset or tool length not known here (after an unsupported line)".into(),
                        },
                    );
                    self.unsupported(d)?;
                    self.st.prog = [None; 3];
                    self.st.out = [None; 3];
                    return Ok(());
                }
            }
        }
        self.shift = [0, 1, 2].map(|a| offsets[a] - out_offsets[a]);
        // target of the program, machine frame
        let start = self.st.prog;
        let mut target = start;
        let mut words = [None; 3];
        for (a, l) in [b'X', b'Y', b'Z'].iter().enumerate() {
            if let Some(w) = b.word(*l) {
                let Value::Number(v) = w.value else {
                    // refused in `block` before motion is interpreted; kept safe here
                    let d = self.diag(
                        col,
                        ProblemKind::Unsupported,
                        "parameter or expression in an axis word".into(),
                    );
                    return self.unsupported(d);
                };
                words[a] = Some((v, w.token));
                target[a] = if absolute {
                    Some(v * scale + offsets[a])
                } else {
                    start[a].map(|s| s + v * scale)
                };
            }
        }
        // the rotary axes: degrees in every unit system, machine = program + rotary offset
        let rot_axes = self.planner.view.rotary_axes();
        let rot_start = self.st.rot;
        let mut rot_target = rot_start;
        let mut rot_words: [Option<(f64, usize)>; 3] = [None; 3];
        for (k, l) in [b'A', b'B', b'C'].into_iter().enumerate() {
            if let Some(w) = b.word(l).filter(|_| rot_axes[k]) {
                let Value::Number(v) = w.value else {
                    let d = self.diag(
                        col,
                        ProblemKind::Unsupported,
                        "parameter or expression in an axis word".into(),
                    );
                    return self.unsupported(d);
                };
                rot_words[k] = Some((v, w.token));
                let off = if g53 {
                    0.0
                } else {
                    self.st
                        .work
                        .map_or(0.0, |w| self.opt.offsets.rotary_deg[w][k])
                };
                rot_target[k] = if absolute {
                    Some(v + off)
                } else {
                    rot_start[k].map(|s| s + v)
                };
            }
        }
        // the end pose is what a correction needs; the start, for splitting (as for X, Y, Z)
        let rot_known = (0..3).all(|k| !rot_axes[k] || rot_target[k].is_some());
        let rot_start_known = (0..3).all(|k| !rot_axes[k] || rot_start[k].is_some());
        let is_arc = matches!(m, Motion::Cw | Motion::Ccw);
        let uses_modal = motion_tok.is_none();
        let target_known = target.iter().all(|t| t.is_some());
        let start_known =
            start.iter().all(|t| t.is_some()) && self.st.out.iter().all(|t| t.is_some());

        let start_known = start_known && rot_start_known;
        if !target_known || !rot_known || (is_arc && !start_known) {
            for k in 0..3 {
                if rot_words[k].is_some() {
                    self.st.rot[k] = rot_target[k];
                }
            }
            if m == Motion::Rapid {
                // positioning before every axis is known: copied, not compensated
                self.report.rapids_not_compensated += 1;
                for a in 0..3 {
                    if let Some((v, _)) = words[a] {
                        self.st.prog[a] = target[a];
                        self.st.out[a] = if absolute {
                            Some(v * scale + out_offsets[a])
                        } else {
                            self.st.out[a].map(|o| o + v * scale)
                        };
                    }
                }
                self.restore_motion_word(b, m, uses_modal);
                self.emitted = true;
                return Ok(());
            }
            let missing = match (0..3)
                .find(|&a| target[a].is_none() || (is_arc && start[a].is_none()))
            {
                Some(a) => ["X", "Y", "Z"][a],
                None => {
                    let k = (0..3)
                        .find(|&k| {
                            rot_axes[k]
                                && (rot_target[k].is_none() || (is_arc && rot_start[k].is_none()))
                        })
                        .unwrap_or(0);
                    ["A", "B", "C"][k]
                }
            };
            let d = self.diag(
                col,
                ProblemKind::Unsupported,
                format!(
                    "the position of {missing} is not known before this feed move (program it in an absolute move first{})",
                    if target_known { ", or give --start-rotary-deg" } else { "" }
                ),
            );
            self.unsupported(d)?;
            for a in 0..3 {
                if words[a].is_some() {
                    self.st.prog[a] = None;
                    self.st.out[a] = None;
                }
            }
            return Ok(());
        }
        let rot_target = rot_target.map(|r| r.unwrap_or(0.0));
        // an unknown start angle: the move is corrected at its end only (no c_start below)
        let rot_start = [0, 1, 2].map(|k| rot_start[k].unwrap_or(rot_target[k]));
        if let Some(kin) = self.planner.view.kinematics() {
            if kin.has_tool_side_rotary()
                && !g53
                && self.st.tool_length_mm.is_some_and(|l| l != 0.0)
            {
                let d = self.diag(
                    col,
                    ProblemKind::Unsupported,
                    format!("a tool length offset (G43) on chain `{}`, whose rotary head turns the tool: the model's tool_offset_mm is the tool, so compensate with G49 and the tool in the machine file", kin.chain()),
                );
                self.unsupported(d)?;
                self.st.prog = [None; 3];
                self.st.out = [None; 3];
                self.st.rot = [None; 3];
                return Ok(());
            }
        }
        let rot_moves = (0..3).any(|k| rot_axes[k] && rot_target[k] != rot_start[k]);
        if let Err(msg) = self.planner.view.set_rotary(rot_target) {
            let d = self.diag(col, ProblemKind::Unsupported, msg);
            self.unsupported(d)?;
            self.st.prog = [None; 3];
            self.st.out = [None; 3];
            self.st.rot = [None; 3];
            return Ok(());
        }
        self.st.rot = rot_target.map(Some);
        let target = target.map(|t| t.unwrap_or(0.0));
        let c_end = self.correct(target, col)?;
        let mut c_start = if start_known {
            Some([0, 1, 2].map(|a| self.st.out[a].unwrap_or(0.0) - self.st.prog[a].unwrap_or(0.0)))
        } else {
            None
        };
        // the first move from an uncorrected --start-position-mm: if the error there is over
        // the tolerance, no path from it can stay within it, so the move is corrected at its
        // end point only, as from an unknown start (before, a G1 first was refused as "a
        // piece shorter than 1 nm", found 2026-11-28 on a jscut program)
        if let (true, Some(c0)) = (self.st.start_uncorrected, c_start) {
            let start_p = start.map(|s| s.unwrap_or(0.0));
            let needed = self.correct(start_p, col)?;
            let off_um = dist(needed, c0) * 1000.0;
            if off_um > self.opt.tolerance_um {
                c_start = None;
            }
        }
        self.st.start_uncorrected = false;
        let start_p = start.map(|s| s.unwrap_or(0.0));
        if rot_moves {
            let mv = RotaryMove {
                x0: start_p,
                x1: target,
                r0: rot_start,
                r1: rot_target,
                c0: c_start,
                c1: c_end,
                words: rot_words,
                absolute,
                offset: if g53 {
                    [0.0; 3]
                } else {
                    self.st
                        .work
                        .map_or([0.0; 3], |w| self.opt.offsets.rotary_deg[w])
                },
            };
            self.rotary_move(
                b,
                body,
                m,
                uses_modal,
                &mv,
                &words,
                out_offsets,
                absolute,
                scale,
                col,
            )?;
            self.st.prog = target.map(Some);
            return Ok(());
        }

        // an arc is built, and checked as LinuxCNC checks it, whether its start is corrected
        // or not (until 2026-11-29 an arc from an uncorrected start was written unchecked: an
        // arc off its circle right after a G92, found on mecode's output)
        let arc = if matches!(m, Motion::Cw | Motion::Ccw) {
            match self.arc_of(
                b,
                start_p,
                target,
                m == Motion::Cw,
                absolute,
                scale,
                offsets,
            ) {
                Ok(a) => Some(a),
                Err(msg) => return self.arc_refused(col, ProblemKind::Syntax, msg),
            }
        } else {
            None
        };
        match (m, c_start, arc) {
            (Motion::Linear, Some(c0), _) => {
                let start_xyz = self.st.out.map(|o| o.unwrap_or(0.0));
                let mut pieces = std::mem::take(&mut self.pieces);
                pieces.clear();
                let (planner, mut at) = self.at(col);
                planner.split_linear(
                    start_p,
                    target,
                    c0,
                    c_end,
                    (0.0, 1.0),
                    &mut pieces,
                    &mut at,
                )?;
                self.emit_pieces(
                    b,
                    body,
                    m,
                    uses_modal,
                    &pieces,
                    &words,
                    out_offsets,
                    absolute,
                    scale,
                    false,
                )?;
                self.pieces = pieces;
                self.apply_feed(
                    b,
                    body,
                    start_xyz,
                    None,
                    (dist(start_p, target) / scale, 0.0),
                    scale,
                    col,
                )?;
            }
            (Motion::Cw | Motion::Ccw, Some(c0), Some(arc)) => {
                // kept as an arc when the bound of its path error allows it (NaN: linearised,
                // where the pieces report the missing model value)
                let tolerance_um = self.opt.tolerance_um;
                let fits = self.arc_stays_within_linuxcnc_tolerance(&arc, c0, c_end);
                let (planner, at) = self.at(col);
                let keep = fits && planner.arc_bound_um(&arc, c0, c_end, &at) <= tolerance_um;
                if keep {
                    let moved = c0 != [0.0; 3] || c_end != [0.0; 3];
                    self.write_centre(b, &arc, start_p, c0, moved, out_offsets, scale);
                    let pieces = [Piece::new(target, c_end, 1.0)];
                    self.emit_pieces(
                        b,
                        body,
                        m,
                        uses_modal,
                        &pieces,
                        &words,
                        out_offsets,
                        absolute,
                        scale,
                        false,
                    )?;
                } else {
                    let n = arc.chord_count(self.opt.chord_tolerance_um * 1e-3);
                    if n > self.opt.max_pieces_per_move {
                        return Err(self.too_many(col));
                    }
                    let mut pieces = Vec::new();
                    let mut prev = start_p;
                    let mut c_prev = c0;
                    for k in 1..=n {
                        let v = arc.point(k as f64 / n as f64);
                        let cv = if k == n { c_end } else { self.correct(v, col)? };
                        let s_range = ((k - 1) as f64 / n as f64, k as f64 / n as f64);
                        let (planner, mut at) = self.at(col);
                        planner.split_linear(prev, v, c_prev, cv, s_range, &mut pieces, &mut at)?;
                        prev = v;
                        c_prev = cv;
                    }
                    self.report.arcs_linearised += 1;
                    let start_xyz = self.st.out.map(|o| o.unwrap_or(0.0));
                    self.emit_pieces(
                        b,
                        body,
                        m,
                        uses_modal,
                        &pieces,
                        &words,
                        out_offsets,
                        absolute,
                        scale,
                        true,
                    )?;
                    self.apply_feed(
                        b,
                        body,
                        start_xyz,
                        None,
                        (arc_length(&arc) / scale, 0.0),
                        scale,
                        col,
                    )?;
                }
            }
            (_, _, arc) => {
                // rapids and feed moves from an unknown start: end point only. An arc's start
                // is known (else refused above), only not corrected: its end corrected alone
                // must leave a radius LinuxCNC accepts
                if let Some(arc) = arc {
                    let c0 = [0, 1, 2].map(|a| {
                        self.st.out[a].unwrap_or(start_p[a]) - self.st.prog[a].unwrap_or(start_p[a])
                    });
                    if !self.arc_stays_within_linuxcnc_tolerance(&arc, c0, c_end) {
                        let msg = format!(
                            "this arc starts where the machine stands uncorrected (the first move, or the first after G92 or a reference point) and its end moves by {:.1} um: LinuxCNC would refuse the arc's changed radius; start with a straight move (e.g. G0 to the arc's start) so that the arc starts corrected",
                            dist(c_end, c0) * 1000.0
                        );
                        return self.arc_refused(col, ProblemKind::Unsupported, msg);
                    }
                    // an R arc whose end moves alone no longer reaches it near 180° (found on
                    // mecode's output): written in centre form
                    self.write_centre(b, &arc, start_p, c0, c_end != c0, out_offsets, scale);
                }
                if m != Motion::Rapid {
                    self.report.moves_end_point_only += 1;
                }
                let pieces = [Piece::new(target, c_end, 1.0)];
                self.emit_pieces(
                    b,
                    body,
                    m,
                    uses_modal,
                    &pieces,
                    &words,
                    out_offsets,
                    absolute,
                    scale,
                    false,
                )?;
            }
        }
        self.st.prog = target.map(Some);
        Ok(())
    }

    /// Refuses an arc block (or passes it through, warned, as the options say) and forgets the
    /// position it would have changed.
    fn arc_refused(
        &mut self,
        col: usize,
        kind: ProblemKind,
        msg: String,
    ) -> Result<(), GcodeError> {
        let d = self.diag(col, kind, msg);
        self.unsupported(d)?;
        for a in 0..3 {
            self.st.prog[a] = None;
            self.st.out[a] = None;
        }
        Ok(())
    }

    /// The centre words of an arc kept as an arc whose start is written moved by `c0`: an R
    /// arc whose end point is `moved` is written in centre form (R kept with a moved end moves
    /// the centre, badly so near 180°), absolute centres (G90.1) move with the start.
    #[allow(clippy::too_many_arguments)]
    fn write_centre(
        &mut self,
        b: &Block,
        arc: &Arc,
        start_p: [f64; 3],
        c0: [f64; 3],
        moved: bool,
        out_offsets: [f64; 3],
        scale: f64,
    ) {
        if let Some(rw) = b.word(b'R').filter(|_| moved) {
            self.r_to_center(arc, rw.token, start_p, c0, out_offsets, scale);
        } else if self.st.arc_absolute == Some(true) {
            self.shift_center_words(b, c0, scale);
        }
    }

    /// Whether the arc, written with its start (and centre) moved by `c0` and its end by
    /// `c_end`, still has end and start radii that LinuxCNC accepts: the end radius changes by
    /// up to |c_end − c0| and the written end point and centre are rounded; and both radii
    /// stay well above LinuxCNC's smallest centre-format radius (an R arc, which has none, is
    /// written with its centre). An arc near either limit is cut into chords instead, so that
    /// the compensated program runs wherever the original does.
    fn arc_stays_within_linuxcnc_tolerance(
        &self,
        arc: &Arc,
        c0: [f64; 3],
        c_end: [f64; 3],
    ) -> bool {
        let rounding_um = rounding_in_effect_um(self.opt, self.st.units);
        let slack_mm = dist(c_end, c0) + 4.0 * rounding_um * 1e-3;
        let written = (arc.r_end - arc.r_start).abs() + slack_mm;
        let inch = self.st.units == Some(Units::Inch);
        // the written radii (start and centre moved by c0, the end by c_end, each word rounded)
        // must stay above LinuxCNC's smallest centre-format radius: an R arc has none
        let smallest_written = arc.r_start.min(arc.r_end) - slack_mm;
        written <= center_arc_limit_mm(arc.r_start, arc.r_end, inch)
            && smallest_written > 2.0 * CENTER_ARC_MIN_RADIUS_MM
    }

    /// Whether the block's word for rotary axis `k` (0 = A) leaves the axis where it stands:
    /// zero in incremental mode, or the known angle (`--start-rotary-deg`, work offset
    /// included) in absolute mode. Used for axes the model does not have, whose angle the
    /// rewriter keeps from the start and never changes.
    fn rotary_stays(&self, b: &Block, k: usize) -> bool {
        let Some(Value::Number(v)) = b.word([b'A', b'B', b'C'][k]).map(|w| w.value) else {
            return false;
        };
        let g53 = b.has_g(GCode::G53).is_some();
        if !g53 && self.st.absolute == Some(false) {
            return v == 0.0;
        }
        if !g53 && self.st.absolute != Some(true) {
            return false;
        }
        let off = if g53 {
            Some(0.0)
        } else {
            self.st.work.map(|w| self.opt.offsets.rotary_deg[w][k])
        };
        match (self.st.rot[k], off) {
            (Some(at), Some(off)) => at == v + off,
            _ => false,
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn arc_of(
        &self,
        b: &Block,
        start: [f64; 3],
        end: [f64; 3],
        clockwise: bool,
        _absolute: bool,
        scale: f64,
        offsets: [f64; 3],
    ) -> Result<Arc, String> {
        let plane = self.st.plane.ok_or("plane not known here")?;
        let num = |l: u8| -> Option<f64> {
            b.word(l).map(|w| match w.value {
                Value::Number(v) => v,
                Value::Computed => f64::NAN,
            })
        };
        let turns = match num(b'P') {
            None => 1,
            Some(p) if p >= 1.0 && p.fract() == 0.0 && p < 1e6 => p as u32,
            Some(p) => return Err(format!("arc P word {p} is not a whole number of turns ≥ 1")),
        };
        if let Some(r) = num(b'R') {
            if [b'I', b'J', b'K'].iter().any(|&l| b.word(l).is_some()) {
                return Err("arc with both R and I/J/K".into());
            }
            if turns != 1 {
                return Err("R-format arc with a P word".into());
            }
            return Arc::from_radius(start, end, r * scale, plane, clockwise);
        }
        let ijk = [num(b'I'), num(b'J'), num(b'K')];
        let (f, s) = (plane.first, plane.second);
        if ijk[plane.normal].is_some() {
            let l = [b'I', b'J', b'K'][plane.normal] as char;
            return Err(format!("arc offset {l} is not in the selected plane"));
        }
        if ijk[f].is_none() && ijk[s].is_none() {
            return Err("arc without R or centre offsets (I, J, K) in its plane".into());
        }
        let center = if self.st.arc_absolute == Some(true) {
            [
                ijk[f].map(|v| v * scale + offsets[f]).unwrap_or(start[f]),
                ijk[s].map(|v| v * scale + offsets[s]).unwrap_or(start[s]),
            ]
        } else {
            [
                start[f] + ijk[f].unwrap_or(0.0) * scale,
                start[s] + ijk[s].unwrap_or(0.0) * scale,
            ]
        };
        let inch = self.st.units == Some(Units::Inch);
        Arc::from_center(start, end, center, plane, clockwise, turns, inch)
    }
}

/// Length (mm) of an arc as LinuxCNC's interpreter measures it for inverse-time feeds
/// (`find_arc_length`): the helix over the start radius, √((r·|θ|)² + Δnormal²).
fn arc_length(arc: &Arc) -> f64 {
    let n = arc.plane.normal;
    (arc.r_start * arc.sweep.abs()).hypot(arc.end[n] - arc.start[n])
}
