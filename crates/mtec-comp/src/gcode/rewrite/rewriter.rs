//! The driver: the [`Rewriter`] reads lines, evaluates parameters and hands each block to the
//! interpreter (`interp`, the [`State`] it owns), the planning of its move (`plan`,
//! `rotary_move`, with the [`Planner`] it owns for the numbers) and the emitter (`emit`); those
//! three are `impl Rewriter` blocks. It holds the per-line buffers they share. The types every part names (options, report, pieces, rotary moves, word text) live in
//! leaf modules below all of them, so no module of the rewriter uses another in a cycle.

use super::super::block::{Block, Issue};
use super::super::code::GCode;
use super::super::expr::{for_each_system_parameter_range, LineValues, Params};
use super::super::format::Edit;
use super::super::lexer::{lex_line, Token, TokenKind, Value};
use super::interp::{Interpreted, Motion, State};
use super::options::{rounding_in_effect_um, BlockDelete, OnUnsupported, RewriteOptions, Units};
use super::piece::{EmittedEnd, Piece, RotaryMove};
use super::planner::{At, Planner};
use super::report::{Diagnostic, GcodeError, ProblemKind, RewriteReport, MAX_WARNINGS_KEPT};
use crate::ErrorModel;
use std::io::{BufRead, Write};

/// Added to the refusal of a construct [`Rewriter::flattening_resolves`] names: what to do.
const FLATTEN_HINT: &str = "LinuxCNC's interpreter resolves this: add --flatten-with rs274 to run the program through it first and compensate the moves it makes (see compensate gcode --help)";

/// Most emptied edit texts kept for reuse (a line corrects at most a few words).
const MAX_SPARE_TEXTS: usize = 16;

pub(super) struct Rewriter<'a> {
    pub(super) opt: &'a RewriteOptions,
    pub(super) st: State,
    pub(super) report: RewriteReport,
    pub(super) line_no: usize,
    pub(super) tokens: Vec<Token>,
    pub(super) edits: Vec<Edit>,
    /// The emptied texts of the last line's edits, reused for the next line's corrected words
    /// (an allocation and a free per word otherwise).
    pub(super) spare_texts: Vec<String>,
    pub(super) extra_lines: Vec<String>,
    pub(super) out_buf: Vec<u8>,
    pub(super) tape_started: bool,
    pub(super) tape_ended: bool,
    /// An M2 or M30 has been read: LinuxCNC reads no further line (a `%` after it is fine).
    pub(super) program_ended: bool,
    pub(super) seen_content: bool,
    /// The current line writes its letters in lower case (new words follow it).
    pub(super) lower: bool,
    /// The motion of the current block was written (by `emit_pieces` or as an uncorrected rapid).
    pub(super) emitted: bool,
    /// The pieces of the current move (reused).
    pub(super) pieces: Vec<Piece>,
    /// The current block's words (buffers reused from line to line); boxed so that lending it
    /// out for a line moves a pointer, not its ~0.7 kB.
    pub(super) block: Option<Box<Block>>,
    /// Corrections, path-error bounds and splitting (`planner`).
    pub(super) planner: Planner<'a>,
    /// The current block moves in machine coordinates (G53).
    pub(super) g53: bool,
    /// The current move's original-program offsets less the rewritten program's, mm: a word
    /// copied unchanged lands this much off in the rewritten program.
    pub(super) shift: [f64; 3],
    /// Numbered and named parameters as LinuxCNC sets them (literal values only).
    pub(super) params: Params,
    /// The rotary move being written, if the current move turns a rotary axis.
    pub(super) rot_move: Option<RotaryMove>,
    /// The output lines of the current move (for its feed words).
    pub(super) ends: Vec<EmittedEnd>,
    /// The current line's evaluated words and assignments.
    pub(super) line_values: LineValues,
    /// A line's parameters could not be evaluated (pass-through mode): from then on parameter
    /// values are not known and computed words are unsupported.
    pub(super) params_lost: bool,
    /// LinuxCNC's naive-CAM tolerance in effect, mm, and the line of the G64 that set it
    /// (`G64 P p Q q`: q, else p; 0 after G61/G61.1 or `G64` alone).
    pub(super) naive_cam: Option<(f64, usize)>,
    /// The naive-CAM warning was given (once per program).
    pub(super) naive_cam_warned: bool,
    /// The program has stated its units (G20/G21) and its distance mode (G90/G91).
    pub(super) modes_stated: [bool; 2],
    /// The warning that a move came before them was given (once per program).
    pub(super) modes_warned: bool,
    /// The M codes outside LinuxCNC's table already warned about (once per code).
    pub(super) unknown_m_warned: Vec<u32>,
}

impl<'a> Rewriter<'a> {
    pub(super) fn new(model: &'a dyn ErrorModel, opt: &'a RewriteOptions) -> Self {
        Rewriter {
            opt,
            st: State::new(opt),
            report: RewriteReport::default(),
            line_no: 0,
            tokens: Vec::new(),
            edits: Vec::new(),
            spare_texts: Vec::new(),
            extra_lines: Vec::new(),
            out_buf: Vec::new(),
            tape_started: false,
            tape_ended: false,
            program_ended: false,
            seen_content: false,
            lower: false,
            emitted: false,
            g53: false,
            shift: [0.0; 3],
            params: Params::new(),
            rot_move: None,
            ends: Vec::new(),
            line_values: LineValues::default(),
            params_lost: false,
            naive_cam: None,
            naive_cam_warned: false,
            modes_stated: [false; 2],
            modes_warned: false,
            unknown_m_warned: Vec::new(),
            block: None,
            planner: Planner::new(model, opt),
            pieces: Vec::new(),
        }
    }

    pub(super) fn run<R: BufRead, W: Write>(
        &mut self,
        mut input: R,
        mut output: W,
    ) -> Result<(), GcodeError> {
        let mut buf = Vec::with_capacity(256);
        loop {
            buf.clear();
            let n = input.read_until(b'\n', &mut buf)?;
            if n == 0 {
                break;
            }
            self.line_no += 1;
            self.report.lines_read += 1;
            let mut body_end = buf.len();
            if buf[body_end - 1] == b'\n' {
                body_end -= 1;
                if body_end > 0 && buf[body_end - 1] == b'\r' {
                    body_end -= 1;
                }
            }
            let (body, ending) = buf.split_at(body_end);
            self.line(body, ending, &mut output)?;
        }
        if !self.program_ended && !self.tape_ended && self.report.lines_read > 0 {
            // rs274: "File ended with no percent sign or program end"; every move has run by
            // then, so the output is the same program, but the user should know
            let d = self.diag(
                1,
                ProblemKind::Controller,
                "the program has no end (M2, M30 or a closing %): LinuxCNC runs every line and then stops with an error (\"File ended with no percent sign or program end\"); add M2".into(),
            );
            self.warn(d);
        }
        output.flush()?;
        Ok(())
    }

    pub(super) fn diag(&self, column: usize, kind: ProblemKind, message: String) -> Diagnostic {
        Diagnostic {
            line: self.line_no,
            column,
            kind,
            message,
        }
    }

    pub(super) fn column_of(&self, token: Option<usize>) -> usize {
        token
            .and_then(|t| self.tokens.get(t))
            .map(|t| t.span.start + 1)
            .unwrap_or(1)
    }

    /// True when the refused construct at `token` is one LinuxCNC's interpreter turns into plain
    /// moves, so that `--flatten-with rs274` compensates the program: O-words, parameter
    /// assignments, words it could not evaluate here, polar coordinates, cutter compensation,
    /// the drilling and boring cycles, G92.3. Not a rotary or U/V/W axis, a missing tool length
    /// or work offset, or a block LinuxCNC itself refuses: flattening does not change those.
    fn flattening_resolves(&self, token: Option<usize>) -> bool {
        use GCode::*;
        let Some(t) = token.and_then(|t| self.tokens.get(t)) else {
            return false;
        };
        match t.kind {
            TokenKind::OWord { .. } | TokenKind::Assignment { .. } => true,
            TokenKind::Word {
                value: Value::Computed,
                ..
            } => true,
            TokenKind::Word {
                letter: b'@' | b'^',
                ..
            } => true,
            TokenKind::Word {
                letter: b'G',
                value: Value::Number(v),
            } => super::super::code::tenths_of(v).is_some_and(|g| {
                matches!(
                    GCode::from_tenths(g),
                    G41 | G41_1
                        | G42
                        | G42_1
                        | G73
                        | G81
                        | G82
                        | G83
                        | G84
                        | G85
                        | G86
                        | G87
                        | G88
                        | G89
                        | G92_3
                )
            }),
            _ => false,
        }
    }

    /// Refuses, or records a warning and returns Ok (the caller passes the line through).
    pub(super) fn unsupported(&mut self, d: Diagnostic) -> Result<(), GcodeError> {
        match self.opt.on_unsupported {
            OnUnsupported::Refuse => Err(GcodeError::At(d)),
            OnUnsupported::PassThroughWithWarning => {
                self.warn(d);
                Ok(())
            }
        }
    }

    /// Counts a warning and keeps it among the first [`MAX_WARNINGS_KEPT`].
    pub(super) fn warn(&mut self, d: Diagnostic) {
        self.report.warnings_total += 1;
        if self.report.warnings.len() < MAX_WARNINGS_KEPT {
            self.report.warnings.push(d);
        }
    }

    /// G64 P… Q…, G61, G61.1: LinuxCNC's naive-CAM tolerance (emccanon.cc `linkable`): in G64
    /// with a tolerance above 0, consecutive straight feeds whose points all lie within it of
    /// the line from the first start to the last end are sent as that one line. `G64 P p`
    /// without Q sets it to p (rs274 prints `SET_NAIVECAM_TOLERANCE(p)`).
    fn follow_path_control(&mut self, b: &Block) {
        if b.has_g(GCode::G61).or(b.has_g(GCode::G61_1)).is_some() {
            self.naive_cam = None;
        }
        if b.has_g(GCode::G64).is_some() {
            let number = |l: u8| match b.word(l).map(|w| w.value) {
                Some(Value::Number(v)) if v.is_finite() => Some(v),
                _ => None,
            };
            let mm = self.st.units.map_or(1.0, |u| u.mm_per_unit());
            let q = number(b'Q').or(number(b'P')).unwrap_or(0.0) * mm;
            self.naive_cam = (q > 0.0).then_some((q, self.line_no));
        }
    }

    /// Warns (once) at the first move that comes before the program states its units or its
    /// distance mode: they are taken as `--default-units` and G90, LinuxCNC's start-up modes,
    /// but the controller keeps the modes the previous program or an MDI command left.
    fn warn_assumed_modes(&mut self, b: &Block, moves: bool) {
        use GCode::*;
        self.modes_stated[0] |= b.has_g(G20).or(b.has_g(G21)).is_some();
        self.modes_stated[1] |= b.has_g(G90).or(b.has_g(G91)).is_some();
        if !moves || self.modes_warned || self.modes_stated == [true; 2] {
            return;
        }
        self.modes_warned = true;
        let units = match self.opt.default_units {
            Units::Mm => "G21 (mm, --default-units)",
            Units::Inch => "G20 (inch, --default-units)",
        };
        let missing = match self.modes_stated {
            [false, false] => format!("its units and distance mode: taken as {units} and G90"),
            [false, true] => format!("its units: taken as {units}"),
            _ => "its distance mode: taken as G90".to_string(),
        };
        let d = self.diag(
            self.column_of(b.first_word),
            ProblemKind::Controller,
            format!("this move comes before the program states {missing}, LinuxCNC's start-up modes; the controller keeps the modes the previous program or an MDI command left, and the program and its compensation run differently in others: state them before the first move (e.g. G21 G90)"),
        );
        self.warn(d);
    }

    /// Warns (once per code) of an M code outside LinuxCNC's table (M0–M9, M19, M30, M48–M53,
    /// M60–M73, user M100–M199; M98/M99 are refused elsewhere): the block is copied unchanged
    /// and mtec compensates as if the code moved no axis, but LinuxCNC stops at it ("Unknown m
    /// code used") unless the machine's INI remaps it, and a remap or another control's code (a
    /// Centroid M25 sends Z home) may move the machine where the rewrite does not follow.
    fn warn_unknown_m_codes(&mut self, b: &Block) {
        for &(code, token) in &b.m {
            if matches!(code, 98 | 99)
                || crate::gcode::modal::m_group(code).is_some()
                || self.unknown_m_warned.contains(&code)
            {
                continue;
            }
            self.unknown_m_warned.push(code);
            let d = self.diag(
                self.column_of(Some(token)),
                ProblemKind::Controller,
                format!("M{code} is not a LinuxCNC M code: LinuxCNC stops here (\"Unknown m code used\") unless the machine's INI remaps it; the block is copied unchanged and the moves after it are compensated as if M{code} moved no axis. If it moves the machine (a remap, or another control's code such as a Centroid M25 that sends Z home), the first move after it starts elsewhere than the rewrite assumed: follow it with an absolute rapid naming every axis (G90 G0 X… Y… Z…) before the next feed move"),
            );
            self.warn(d);
        }
    }

    /// Warns (once) that the pieces just written may be merged back into one line by the
    /// naive-CAM detector: the path between them is then within its tolerance, not within
    /// `--tolerance-um`.
    fn warn_naive_cam(&mut self, token: Option<usize>) {
        let Some((q, g64_line)) = self.naive_cam.filter(|_| !self.naive_cam_warned) else {
            return;
        };
        self.naive_cam_warned = true;
        let d = self.diag(
            self.column_of(token),
            ProblemKind::Controller,
            format!(
                "this move is written as several straight pieces to follow the model within {} um, but the G64 of line {g64_line} sets LinuxCNC's naive-CAM tolerance to {:.4} mm (Q, or P without Q), and LinuxCNC runs consecutive straight feeds that lie within it of one line as that line: the pieces can be merged, leaving the path between their ends off by up to the model's departure from a straight line. Add Q0 to that G64 (G64 P… Q0) or use G61 to keep them (the same holds for a G64 P/Q in the controller's start-up code)",
                self.opt.tolerance_um, q
            ),
        );
        self.warn(d);
    }

    /// The planner and where the current block is, for one planning step at column `col`.
    pub(super) fn at(&mut self, col: usize) -> (&mut Planner<'a>, At<'_>) {
        let at = At {
            opt: self.opt,
            units: self.st.units,
            line: self.line_no,
            col,
            report: &mut self.report,
        };
        (&mut self.planner, at)
    }

    /// The correction at a target (mm), with the error located at the block.
    pub(super) fn correct(&mut self, target: [f64; 3], col: usize) -> Result<[f64; 3], GcodeError> {
        let (planner, mut at) = self.at(col);
        planner.correct(target, &mut at)
    }

    /// Half a unit of the last written digit on three axes in the units in effect, µm.
    pub(super) fn rounding_now_um(&self) -> f64 {
        rounding_in_effect_um(self.opt, self.st.units)
    }

    pub(super) fn no_model_value(&mut self, col: usize) -> GcodeError {
        self.at(col).1.no_model_value()
    }

    pub(super) fn too_many(&mut self, col: usize) -> GcodeError {
        self.at(col).1.too_many()
    }

    fn line<W: Write>(
        &mut self,
        body: &[u8],
        ending: &[u8],
        output: &mut W,
    ) -> Result<(), GcodeError> {
        if self.tape_ended {
            return self.write_verbatim(body, ending, output);
        }
        let start = if self.line_no == 1 && body.starts_with(b"\xEF\xBB\xBF") {
            3
        } else {
            0
        };
        let mut tokens = std::mem::take(&mut self.tokens);
        let lexed = lex_line(body, start, &mut tokens);
        self.tokens = tokens;
        if let Err(e) = lexed {
            let d = self.diag(e.column, ProblemKind::Syntax, e.message);
            self.unsupported(d)?;
            self.st.poison_all();
            return self.write_verbatim(body, ending, output);
        }
        // a `/` block with the switch on is skipped by the controller: copied, not interpreted
        if self.opt.block_delete == BlockDelete::On
            && self
                .tokens
                .first()
                .is_some_and(|t| t.kind == TokenKind::BlockDelete)
        {
            return self.write_verbatim(body, ending, output);
        }
        // parameters and expressions: every word is read with the values from before the line
        // (LinuxCNC's rule); a computed word becomes its number, assignments apply after it
        let computes = self.tokens.iter().any(|t| {
            matches!(
                t.kind,
                TokenKind::Assignment { .. }
                    | TokenKind::Word {
                        value: Value::Computed,
                        ..
                    }
            )
        });
        let mut evaluated = false;
        if computes && !self.params_lost {
            let mut lv = std::mem::take(&mut self.line_values);
            match self.params.eval_line(body, &self.tokens, &mut lv) {
                Ok(()) => {
                    for (i, t) in self.tokens.iter_mut().enumerate() {
                        if let TokenKind::Word { value, .. } = &mut t.kind {
                            if *value == Value::Computed {
                                if let Some(v) = lv.word(i) {
                                    *value = Value::Number(v);
                                }
                            }
                        }
                    }
                    evaluated = true;
                }
                Err(e) => {
                    let d = self.diag(e.column, ProblemKind::Unsupported, e.message);
                    self.line_values = lv;
                    self.unsupported(d)?;
                    // the parameters this line sets are not known from here on
                    self.params_lost = true;
                    self.st.poison_all();
                    return self.write_verbatim(body, ending, output);
                }
            }
            self.line_values = lv;
        }
        let mut block = self.block.take().unwrap_or_default();
        block.read_into(&self.tokens, body);
        let r = self.line_block(&block, body, ending, output);
        if r.is_ok() && evaluated {
            let lv = std::mem::take(&mut self.line_values);
            self.params.commit(&lv);
            self.line_values = lv;
        }
        if r.is_ok() && !self.params_lost {
            let moved = [b'X', b'Y', b'Z', b'A', b'B', b'C', b'U', b'V', b'W']
                .iter()
                .any(|&l| block.word(l).is_some());
            let params = &mut self.params;
            for_each_system_parameter_range(&block.g, &block.m, moved, |range| {
                params.forget_numbered(range)
            });
        }
        self.block = Some(block);
        r
    }

    fn line_block<W: Write>(
        &mut self,
        block: &Block,
        body: &[u8],
        ending: &[u8],
        output: &mut W,
    ) -> Result<(), GcodeError> {
        self.lower = self
            .tokens
            .iter()
            .find(|t| matches!(t.kind, TokenKind::Word { .. }))
            .map(|t| body[t.span.start].is_ascii_lowercase())
            .unwrap_or(false);
        if block.percent {
            if !self.seen_content {
                self.tape_started = true;
            } else if self.tape_started {
                self.tape_ended = true;
            } else if !self.program_ended {
                // LinuxCNC takes `%` as a tape mark only on the program's first line (then the
                // next one ends it); anywhere else it stops with "Bad character '%' used"
                let at = self
                    .tokens
                    .iter()
                    .position(|t| matches!(t.kind, TokenKind::Percent));
                let col = self.column_of(at);
                return Err(GcodeError::At(self.diag(
                    col,
                    ProblemKind::Syntax,
                    "a % tape mark after the program's first line: LinuxCNC reads % only as the first line (then the next % ends the program) and stops here with \"Bad character '%' used\"; a Fanuc control skips everything before it. Remove the lines before it, or this %".into(),
                )));
            }
            self.seen_content = true;
            return self.write_verbatim(body, ending, output);
        }
        if !self.tokens.is_empty() {
            self.seen_content = true;
        }
        self.program_ended |= block.has_m(2).is_some() || block.has_m(30).is_some();
        for edit in self.edits.drain(..) {
            // kept only while the pool is small: a line's edits made by other means than a
            // corrected word would otherwise add to it on every line of a long program
            if self.spare_texts.len() < MAX_SPARE_TEXTS && edit.text.capacity() > 0 {
                let mut text = edit.text;
                text.clear();
                self.spare_texts.push(text);
            }
        }
        self.extra_lines.clear();
        let handled = self.block(block, body)?;
        if !handled || (self.edits.is_empty() && self.extra_lines.is_empty()) {
            return self.write_verbatim(body, ending, output);
        }
        self.write_edited(body, ending, output)
    }

    /// Interprets one block and has its move planned and written; fills `edits` /
    /// `extra_lines`. Returns false when the line is to be passed through unchanged because of
    /// an unsupported construct (already warned).
    fn block(&mut self, b: &Block, body: &[u8]) -> Result<bool, GcodeError> {
        let kinematic = self.planner.view.kinematics().is_some();
        let Interpreted {
            mut issues,
            motion_word,
            g53,
            axis_consumer,
            has_axis,
            motion,
            axis_words_followed,
            offset_change,
        } = self.st.interpret(b, self.opt.block_delete, kinematic);
        if let Some(m) = motion.filter(|_| axis_words_followed) {
            self.check_compensable(b, m, &mut issues);
        } else if motion.is_none() {
            // a block that moves nothing (or whose axis words G10/G28/G30/G52/G92 take): a
            // stray word LinuxCNC refuses
            let motion_to_be = motion_word.map(|(m, _)| m);
            if let Some((letter, token)) = super::block_checks::unused_word(b, motion_to_be) {
                issues.push(Issue {
                    token: Some(token),
                    message: format!("{letter} word with no code in the block that uses it: LinuxCNC refuses the block (\"{letter} word with no ... to use it\"); remove it"),
                    poisons_all: false,
                });
            }
        }

        // G64/G61 take effect in every block LinuxCNC runs, also one that sets offsets, goes to
        // a reference point or is copied with a warning (found 2026-11-28: `G92 X0 G64 P0.5`
        // left the naive-CAM warning out)
        self.follow_path_control(b);
        self.warn_assumed_modes(b, motion.is_some() && has_axis);
        self.warn_unknown_m_codes(b);

        // --- unsupported: refuse, or warn and pass through ----------------------------------
        if !issues.is_empty() {
            let first = issues
                .iter()
                .min_by_key(|i| self.column_of(i.token))
                .cloned()
                .unwrap_or_else(|| issues[0].clone());
            let message = if self.flattening_resolves(first.token) {
                format!("{}; {FLATTEN_HINT}", first.message)
            } else {
                first.message.clone()
            };
            let d = self.diag(
                self.column_of(first.token),
                ProblemKind::Unsupported,
                message,
            );
            self.unsupported(d)?;
            let mut edited = false;
            if has_axis
                && motion_word.is_none()
                && axis_consumer.is_none()
                && matches!(
                    self.st.motion,
                    Motion::Rapid | Motion::Linear | Motion::Cw | Motion::Ccw
                )
                && self.st.out_motion != self.st.motion
            {
                // the line is copied, but it must still move in the program's mode
                let m = self.st.motion;
                self.restore_motion_word(b, m, true);
                edited = true;
            }
            // a copied line that sets offsets leaves them unknown
            if issues.iter().any(|i| i.poisons_all) || offset_change.is_some() {
                self.st.poison_all();
            } else {
                self.st
                    .copied_unfollowed(b, has_axis, motion, motion_word.is_some());
            }
            self.st.after_block(b);
            return Ok(edited);
        }

        // --- G10 / G92 / G52: new offsets (the line is copied) --------------------------------
        if let Some(c) = offset_change {
            self.st.apply_offsets(*c);
            self.st.after_block(b);
            return Ok(true);
        }

        // --- G28 / G30: reference-point moves leave the axes at a position we do not know ----
        if let Some(code) = axis_consumer {
            debug_assert!(code == GCode::G28 || code == GCode::G30);
            // the reference point is the controller's parameter (#5161-#5166, #5181-#5186):
            // the machine goes there as without compensation, which the user is told
            let d = self.diag(
                self.column_of(b.has_g(code)),
                ProblemKind::Unsupported,
                format!("{code}: the move to the reference point is not compensated (its position is a controller parameter); the axes it sends there are taken as unknown until an absolute move"),
            );
            self.warn(d);
            self.st.reference_move(b, has_axis, motion_word.is_some());
            self.st.after_block(b);
            return Ok(true);
        }

        if let Some(m) = motion {
            self.emitted = false;
            let motion_tok = motion_word.map(|(_, t)| t);
            let linearised = self.report.arcs_linearised;
            self.motion_block(b, body, m, motion_tok, g53)?;
            if !self.extra_lines.is_empty() {
                self.move_stops_after_the_move(b, body);
            }
            let straight_pieces = m == Motion::Linear || self.report.arcs_linearised > linearised;
            if straight_pieces && !self.extra_lines.is_empty() {
                self.warn_naive_cam(motion_tok.or(b.first_word));
            }
            if !self.emitted {
                // copied without compensation: it must still move in the program's mode
                self.restore_motion_word(b, m, motion_tok.is_none());
            }
        } else if motion_word.is_some() {
            self.st.out_motion = self.st.motion;
        }
        self.st.after_block(b);
        Ok(true)
    }
}
