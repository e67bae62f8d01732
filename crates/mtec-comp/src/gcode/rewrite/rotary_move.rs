//! Moves that turn a rotary axis, and the feed words of split moves.
//!
//! **What the controller does.** Without tool centre point control (LinuxCNC's default
//! kinematics), a `G1` that names a rotary axis moves every joint linearly from its start to
//! its end value in the same time: q(s) = q₀ + s·(q₁ − q₀), s ∈ [0, 1]. The nominal tool tip is
//! the ideal chain's tool tip along that joint path, N(s) = P₀(q(s)) in the workpiece frame — a
//! curve, not a line, as soon as a rotary axis turns.
//!
//! **Compensation.** The rotary commands are kept (only the tool tip is corrected, see
//! [`crate::pose`]); the move is cut at parameters s_k. At each cut the rotary axes are written
//! at w_k, the programmed angle rounded to [`ROTARY_DECIMALS`] digits (the last piece ends at
//! the programmed word exactly), and the linear axes at the command x'_k that puts the actual
//! tool tip on N(s_k) at those angles: x'_k + ε(x'_k) = J(w_k)⁻¹·(N(s_k) − b(w_k))
//! (`super::super::rotary`), so the rounding of the rotary words is absorbed by X, Y, Z.
//! Between cuts the controller again moves the joints linearly; the distance of the actual tool
//! tip from the nominal one at the same s, |P₀(q'(u)) + e(q'(u)) − N(s(u))|, is checked at
//! samples no further apart than `--check-step-mm` along the tool tip's path and
//! `--check-step-deg` of any rotary axis (a dense check, as for every model that is not a grid
//! map), plus the rounding of the written X, Y, Z words. A piece over `--tolerance-um` is
//! halved, as a straight move is. Rapids are corrected at their end point only.
//!
//! **Feed** (LinuxCNC's rules, `emccanon.cc` and `interp_inverse.cc`, read in its source): the
//! length of a move is its XYZ length when X, Y or Z moves (the rotary axes follow), else
//! √(ΔA² + ΔB² + ΔC²) in degrees. In G94 a move takes length/F. In G93 the interpreter sets the
//! rate max(0.1, length·F) — the move takes 1/F minutes unless that rate is below 0.1 units
//! per minute, where it runs faster. A split move must keep its duration T and its speed along
//! the way: piece k must take t_k = (s_k − s_{k−1})·T, within [`FEED_TOLERANCE`].
//! - G94 (and G95): the pieces keep F when each one's duration length_k/F is within the
//!   tolerance of t_k (the common case: the correction changes a piece's XYZ length by
//!   micrometres). Otherwise — a rotary-only move whose pieces gain X, Y, Z motion from the
//!   correction, which LinuxCNC would run at F mm/min over a few micrometres — every piece gets
//!   its own F_k = length_k/t_k and the program's F is set again after the move. In G95 (per
//!   revolution) this is refused: the duration depends on the spindle speed.
//! - G93: every piece of a split move gets F_k = 1/t_k; if the 0.1 floor would shorten a piece
//!   (a few micrometres of XYZ motion under a long rotary turn), the move is written in G94
//!   with F_k = length_k/t_k and `G93` is set again after it.
//! - A split straight move or linearised arc without rotary motion keeps F in G94/G95 as
//!   before (its XYZ length changes by the correction only).

use super::super::block::Block;
use super::super::bound::norm;
use super::super::code::GCode;
use super::super::format::{format_number, Edit};
use super::super::lexer::{TokenKind, Value};
use super::interp::Motion;
use super::piece::{dist, EmittedEnd, Piece, RotaryMove};
use super::report::{GcodeError, ProblemKind};
use super::rewriter::Rewriter;
use super::words::case;
use crate::pose::Pose;

/// Largest relative change of a piece's duration for which a G94/G95 move keeps its F (1 %).
pub const FEED_TOLERANCE: f64 = 0.01;

fn lerp(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * s)
}

impl Rewriter<'_> {
    /// Writes a move that turns a rotary axis (module docs).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn rotary_move(
        &mut self,
        b: &Block,
        body: &[u8],
        m: Motion,
        uses_modal: bool,
        mv: &RotaryMove,
        words: &[Option<(f64, usize)>; 3],
        out_offsets: [f64; 3],
        absolute: bool,
        scale: f64,
        col: usize,
    ) -> Result<(), GcodeError> {
        self.report.rotary_moves += 1;
        self.rot_move = Some(*mv);
        match (m, mv.c0) {
            (Motion::Linear, Some(c0)) => {
                let start_xyz = self.st.out.map(|o| o.unwrap_or(0.0));
                let mut pieces = std::mem::take(&mut self.pieces);
                pieces.clear();
                let split = self.split_rotary(mv, c0, &mut pieces, col);
                // the view stands at the move's end angles from here on
                self.planner
                    .view
                    .set_rotary(mv.r1)
                    .map_err(|msg| GcodeError::At(self.diag(col, ProblemKind::Correction, msg)))?;
                split?;
                self.emit_pieces(
                    b,
                    body,
                    m,
                    uses_modal,
                    &pieces,
                    words,
                    out_offsets,
                    absolute,
                    scale,
                    false,
                )?;
                self.pieces = pieces;
                let l_xyz = dist(mv.x0, mv.x1) / scale;
                let l_rot = dist(mv.r0, mv.r1);
                self.apply_feed(b, body, start_xyz, Some(mv.r0), (l_xyz, l_rot), scale, col)?;
            }
            _ => {
                // a rapid, or a feed move from an unknown start: its end point only
                if m != Motion::Rapid {
                    self.report.moves_end_point_only += 1;
                }
                let pieces = [Piece {
                    t: mv.x1,
                    c: mv.c1,
                    s: 1.0,
                    rot: Some(mv.r1),
                }];
                self.emit_pieces(
                    b,
                    body,
                    m,
                    uses_modal,
                    &pieces,
                    words,
                    out_offsets,
                    absolute,
                    scale,
                    false,
                )?;
            }
        }
        self.rot_move = None;
        Ok(())
    }

    /// The nominal tool tip at fraction `s` of the move (workpiece frame, mm).
    fn nominal_tip(&self, mv: &RotaryMove, s: f64) -> [f64; 3] {
        match self.planner.view.kinematics() {
            Some(kin) => kin.tool_point(&Pose::new(lerp(mv.x0, mv.x1, s), lerp(mv.r0, mv.r1, s))),
            None => lerp(mv.x0, mv.x1, s),
        }
    }

    /// Length (mm) of the nominal tool tip's path from s0 to s1, from `n` chords.
    fn nominal_length(&self, mv: &RotaryMove, s0: f64, s1: f64, n: usize) -> f64 {
        let mut prev = self.nominal_tip(mv, s0);
        let mut len = 0.0;
        for j in 1..=n {
            let p = self.nominal_tip(mv, s0 + (s1 - s0) * j as f64 / n as f64);
            len += dist(prev, p);
            prev = p;
        }
        len
    }

    /// The end of a piece at fraction `s` (module docs).
    fn rotary_end(&mut self, mv: &RotaryMove, s: f64, col: usize) -> Result<Piece, GcodeError> {
        if s >= 1.0 {
            return Ok(Piece {
                t: mv.x1,
                c: mv.c1,
                s: 1.0,
                rot: Some(mv.r1),
            });
        }
        let r = lerp(mv.r0, mv.r1, s);
        let w = [0, 1, 2].map(|k| {
            if mv.r1[k] == mv.r0[k] {
                mv.r0[k]
            } else {
                mv.written(k, r[k])
            }
        });
        let n = self.nominal_tip(mv, s);
        self.planner
            .view
            .set_rotary(w)
            .map_err(|msg| GcodeError::At(self.diag(col, ProblemKind::Correction, msg)))?;
        let t = self.planner.view.machine_point(n);
        let c = self.correct(t, col)?;
        Ok(Piece {
            t,
            c,
            s,
            rot: Some(w),
        })
    }

    /// A bound (µm) on the tool tip's distance from the nominal one along the piece a → b
    /// (module docs: dense samples plus the rounding of the written X, Y, Z words). NaN when
    /// the model has no value somewhere.
    fn rotary_piece_bound_um(&self, mv: &RotaryMove, a: &Piece, b: &Piece) -> f64 {
        let Some(kin) = self.planner.view.kinematics() else {
            return f64::NAN;
        };
        let model = self.planner.view.model();
        let pa = [0, 1, 2].map(|i| a.t[i] + a.c[i]);
        let pb = [0, 1, 2].map(|i| b.t[i] + b.c[i]);
        let (wa, wb) = (a.rot.unwrap_or(mv.r0), b.rot.unwrap_or(mv.r1));
        let len = self.nominal_length(mv, a.s, b.s, 8);
        let turn = (0..3).map(|k| (wb[k] - wa[k]).abs()).fold(0.0, f64::max);
        let n = ((len / self.opt.check_step_mm)
            .ceil()
            .max((turn / self.opt.check_step_deg).ceil()) as usize)
            .clamp(4, 1_000_000);
        let mut worst = 0.0f64;
        for j in 0..=n {
            let u = j as f64 / n as f64;
            let q = Pose::new(lerp(pa, pb, u), lerp(wa, wb, u));
            let e = model.pose_error(&q).position_um;
            let ideal = kin.tool_point(&q);
            let nominal = self.nominal_tip(mv, a.s + (b.s - a.s) * u);
            // |P₀(q'(u)) + e(q'(u)) − N(s(u))|
            let d = norm([0, 1, 2].map(|i| (ideal[i] - nominal[i]) * 1e3 + e[i]));
            if d.is_nan() {
                return f64::NAN;
            }
            worst = worst.max(d);
        }
        worst + self.rounding_now_um()
    }

    /// Cuts a rotary move into pieces within `--tolerance-um` (module docs); pushes the ends.
    fn split_rotary(
        &mut self,
        mv: &RotaryMove,
        c0: [f64; 3],
        pieces: &mut Vec<Piece>,
        col: usize,
    ) -> Result<(), GcodeError> {
        let tol = self.opt.tolerance_um;
        if c0 == [0.0; 3] && mv.c1 == [0.0; 3] {
            // nothing to correct at the ends: the move stays whole when the model is flat along it
            let whole = self.rotary_end(mv, 1.0, col)?;
            let start = Piece {
                t: mv.x0,
                c: c0,
                s: 0.0,
                rot: Some(mv.r0),
            };
            let bound = self.rotary_piece_bound_um(mv, &start, &whole);
            if bound.is_nan() {
                return Err(self.no_model_value(col));
            }
            if bound <= tol {
                pieces.push(whole);
                return Ok(());
            }
        }
        let len = self.nominal_length(mv, 0.0, 1.0, 64);
        let n0 = ((len / self.opt.max_segment_mm).ceil() as usize).max(1);
        if n0 > self.opt.max_pieces_per_move {
            return Err(self.too_many(col));
        }
        let mut prev = Piece {
            t: mv.x0,
            c: c0,
            s: 0.0,
            rot: Some(mv.r0),
        };
        let mut stack: Vec<(Piece, Piece)> = Vec::new();
        for k in 1..=n0 {
            let s1 = if k == n0 { 1.0 } else { k as f64 / n0 as f64 };
            let end = self.rotary_end(mv, s1, col)?;
            stack.push((prev, end));
            while let Some((a, b)) = stack.pop() {
                let bound = self.rotary_piece_bound_um(mv, &a, &b);
                if bound.is_nan() {
                    return Err(self.no_model_value(col));
                }
                if bound <= tol {
                    pieces.push(b);
                    if pieces.len() > self.opt.max_pieces_per_move {
                        return Err(self.too_many(col));
                    }
                } else if b.s - a.s < 1e-9 {
                    return Err(GcodeError::At(self.diag(
                        col,
                        ProblemKind::Correction,
                        format!(
                            "the path cannot be kept within --tolerance-um {tol}: {bound:.3} um on a piece of 1e-9 of the move (is the error model continuous here?)"
                        ),
                    )));
                } else {
                    let mid = self.rotary_end(mv, 0.5 * (a.s + b.s), col)?;
                    stack.push((mid, b));
                    stack.push((a, mid));
                }
            }
            prev = end;
        }
        Ok(())
    }

    /// Rewrites the F words of the lines of the move just written ([`Self::ends`]) so that it
    /// keeps its duration and its speed along the way (module docs). `start_xyz`/`start_rot`:
    /// the written axes at its start (`start_rot` is `Some` for a move that turns a rotary
    /// axis); `nominal`: the programmed move's XYZ length (program units) and rotary length
    /// (deg).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply_feed(
        &mut self,
        b: &Block,
        body: &[u8],
        start_xyz: [f64; 3],
        start_rot: Option<[f64; 3]>,
        nominal: (f64, f64),
        scale: f64,
        col: usize,
    ) -> Result<(), GcodeError> {
        let _ = body;
        let n = self.ends.len();
        if !self.st.inverse_time && start_rot.is_none() {
            // G94/G95 straight moves and arcs without rotary motion keep their F
            return Ok(());
        }
        let lower = self.lower;
        // LinuxCNC's length of a move: XYZ if X, Y or Z moves, else the rotary one
        let (l_xyz, l_rot) = nominal;
        let l_nominal = if l_xyz > 0.0 { l_xyz } else { l_rot };
        if l_nominal.is_nan() || l_nominal <= 0.0 {
            return Ok(());
        }
        let r0 = start_rot.unwrap_or([0.0; 3]);
        let mut lengths = Vec::with_capacity(n);
        let (mut prev_xyz, mut prev_rot) = (start_xyz, r0);
        for e in &self.ends {
            let rot = e.rot.unwrap_or(prev_rot);
            let lx = dist(prev_xyz, e.xyz) / scale;
            lengths.push(if lx > 0.0 { lx } else { dist(prev_rot, rot) });
            prev_xyz = e.xyz;
            prev_rot = rot;
        }
        let share =
            |ends: &[EmittedEnd], i: usize| ends[i].s - if i == 0 { 0.0 } else { ends[i - 1].s };
        let within = |t: f64, want: f64| (t - want).abs() <= FEED_TOLERANCE * want;
        if self.st.inverse_time {
            let Some(Value::Number(f)) = b.word(b'F').map(|w| w.value) else {
                // refused in `block` (G93 needs F on every feed move); kept safe here
                return Err(GcodeError::At(self.diag(
                    col,
                    ProblemKind::Unsupported,
                    "inverse-time feed (G93) without an F word".into(),
                )));
            };
            // the move's duration as LinuxCNC runs it: rate = max(0.1, L·F) (interp_inverse.cc)
            let t_nominal = l_nominal / g93_rate(l_nominal, f);
            let want: Vec<f64> = (0..n).map(|i| share(&self.ends, i) * t_nominal).collect();
            // F_k = 1/t_k, unless the 0.1 floor of the rate would shorten a piece
            let fits =
                (0..n).all(|i| within(lengths[i] / g93_rate(lengths[i], 1.0 / want[i]), want[i]));
            if fits && n <= 1 {
                // one piece in G93 takes 1/F whatever its length: the F word stays
                return Ok(());
            }
            if fits {
                let texts: Vec<String> = want.iter().map(|t| feed_text(1.0 / t)).collect();
                self.write_feeds(b, &texts, lower);
                self.report.feeds_rewritten += 1;
                return Ok(());
            }
            // per-minute feeds for this move, inverse time again after it
            let texts: Vec<String> = (0..n).map(|i| feed_text(lengths[i] / want[i])).collect();
            self.write_feeds(b, &texts, lower);
            self.switch_feed_mode(b, GCode::G93, "G94", lower);
            self.extra_lines.push(case("G93", lower));
            self.report.feeds_rewritten += 1;
            return Ok(());
        }
        let Some(feed) = self.st.feed.filter(|f| *f > 0.0) else {
            return Err(GcodeError::At(self.diag(
                col,
                ProblemKind::Unsupported,
                "a feed move turning a rotary axis with no feed rate set (F)".into(),
            )));
        };
        let t_nominal = l_nominal / feed;
        let want: Vec<f64> = (0..n).map(|i| share(&self.ends, i) * t_nominal).collect();
        if (0..n).all(|i| within(lengths[i] / feed, want[i])) {
            return Ok(());
        }
        if self.st.feed_per_rev {
            return Err(GcodeError::At(self.diag(
                col,
                ProblemKind::Unsupported,
                "feed per revolution (G95) on a rotary move whose compensated pieces would change its duration: write it in G93 or G94".into(),
            )));
        }
        // each piece its own feed (mm/min over its XYZ length, or deg/min when only rotary
        // axes move), the program's feed again after the move
        let texts: Vec<String> = (0..n).map(|i| feed_text(lengths[i] / want[i])).collect();
        self.write_feeds(b, &texts, lower);
        self.extra_lines
            .push(format!("{}{}", case("F", lower), feed_text(feed)));
        self.report.feeds_rewritten += 1;
        Ok(())
    }

    /// Replaces the block's feed-mode word `code` (G93/G94) by `to`, or puts `to` first.
    fn switch_feed_mode(&mut self, b: &Block, code: GCode, to: &str, lower: bool) {
        match b.has_g(code) {
            Some(tok) => {
                let span = self.tokens[tok].span.clone();
                self.edits.push(Edit {
                    span,
                    text: case(to, lower),
                    order: 0,
                });
            }
            None => {
                let tok = b.first_word.unwrap_or(0);
                let pos = self.tokens.get(tok).map(|t| t.span.start).unwrap_or(0);
                self.edits.push(Edit {
                    span: pos..pos,
                    text: format!("{}{}", case(to, lower), self.sep_for_line()),
                    order: 0,
                });
            }
        }
    }

    /// Puts `texts[i]` as the F value of the move's i-th written line.
    fn write_feeds(&mut self, b: &Block, texts: &[String], lower: bool) {
        for (i, text) in texts.iter().enumerate() {
            match self.ends[i].line {
                None => match b.word(b'F') {
                    Some(w) => {
                        let span = self.tokens[w.token].value_span.clone();
                        self.edits.push(Edit {
                            span,
                            text: text.clone(),
                            order: 0,
                        });
                    }
                    None => {
                        let pos = self
                            .tokens
                            .iter()
                            .rev()
                            .find(|t| matches!(t.kind, TokenKind::Word { .. }))
                            .map(|t| t.span.end)
                            .unwrap_or(0);
                        self.edits.push(Edit {
                            span: pos..pos,
                            text: format!("{}{}{text}", self.sep_for_line(), case("F", lower)),
                            order: 9,
                        });
                    }
                },
                Some(k) => {
                    let line = &mut self.extra_lines[k];
                    line.push(' ');
                    line.push_str(&case("F", lower));
                    line.push_str(text);
                }
            }
        }
    }
}

/// The feed rate (program units or degrees per minute) LinuxCNC's interpreter sets for an
/// inverse-time move of length `l` and F word `f`: max(0.1, l·f) (`interp_inverse.cc`).
fn g93_rate(l: f64, f: f64) -> f64 {
    (l * f).max(0.1)
}

/// An F value with six significant digits (at most nine decimals).
fn feed_text(v: f64) -> String {
    let decimals = (5.0 - v.abs().log10().floor()).clamp(0.0, 9.0) as usize;
    let mut s = String::new();
    format_number(v, decimals, &mut s);
    s
}
