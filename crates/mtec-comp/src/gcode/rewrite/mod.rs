//! The streaming rewriter: reads a program line by line, tracks the modal state, and writes each
//! line either byte for byte or with only the changed words edited, plus the lines of split moves.
//!
//! This module is the driver and the public API ([`rewrite`], [`RewriteOptions`],
//! [`RewriteReport`], the errors): it reads lines, evaluates parameters, and hands each block
//! in turn to
//! - `interp`: the modal state machine (modes, offsets, tool, positions known or not) and
//!   the constructs it cannot follow; it writes no text;
//! - `plan`: a motion block turned into corrected pieces (targets, corrections, splitting to
//!   the path-error bound, arcs), with `rotary_move` for moves that turn a rotary axis;
//! - `emit`: the pieces written as edits of the line and added lines (rounding, case,
//!   separators), the header comment, the line length limit.
//!
//! It holds the per-line buffers the three share (`Rewriter`).

use super::block::Block;
use super::bound::PathBound;
use super::code::GCode;
use super::expr::{system_parameters_written_by, LineValues, Params};
use super::format::Edit;
use super::lexer::{lex_line, Token, TokenKind, Value};
use super::offsets::Offsets;
use super::rotary::RotaryView;
use crate::ErrorModel;
use interp::{Interpreted, Motion, State};
use plan::Piece;
use rotary_move::{EmittedEnd, RotaryMove};
use std::io::{BufRead, Write};

mod emit;
mod interp;
mod plan;
mod rotary_move;

pub use emit::header_comment;
pub use rotary_move::FEED_TOLERANCE;

/// What to do with a construct that cannot be compensated safely.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OnUnsupported {
    /// Stop with an error naming the line and column (the default).
    #[default]
    Refuse,
    /// Copy the line unchanged, record a warning, and stop compensating whatever the construct
    /// may have changed (positions, modes) until the program sets it again explicitly.
    PassThroughWithWarning,
}

/// The operator's block-delete switch (`--block-delete`): what a block starting with `/` does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BlockDelete {
    /// Not given: a `/` block that moves or changes a mode is unsupported (whether it runs
    /// depends on the switch).
    #[default]
    Unknown,
    /// Switch on: the controller skips `/` blocks; they are copied and not interpreted.
    On,
    /// Switch off: `/` blocks run like any other block.
    Off,
}

/// Length units of the program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Units {
    Mm,
    Inch,
}

impl Units {
    fn mm_per_unit(self) -> f64 {
        match self {
            Units::Mm => 1.0,
            Units::Inch => 25.4,
        }
    }
}

/// The knobs of the rewriter (every one has a CLI flag of the same name).
#[derive(Debug, Clone)]
pub struct RewriteOptions {
    /// Largest change of the correction along one output piece, µm (`--tolerance-um`).
    pub tolerance_um: f64,
    /// Longest output piece of a compensated feed move, mm (`--max-segment-mm`).
    pub max_segment_mm: f64,
    /// Largest sagitta of a chord when an arc is linearised, µm (`--chord-tolerance-um`).
    pub chord_tolerance_um: f64,
    /// Corrections larger than this are refused, µm (`--max-correction-um`).
    pub max_correction_um: f64,
    pub on_unsupported: OnUnsupported,
    /// Digits after the point of rewritten words in mm and in inch programs.
    pub decimals_mm: usize,
    pub decimals_inch: usize,
    /// Units in effect before the program's first G20/G21 (the controller's power-on default).
    pub default_units: Units,
    pub offsets: Offsets,
    /// A single move split into more pieces than this is an error (a runaway model).
    pub max_pieces_per_move: usize,
    /// Machine position (mm) at program start, when known (e.g. the home position; on a lathe
    /// the Y position that programs never state). `None`: unknown until programmed.
    pub start_position_mm: Option<[f64; 3]>,
    /// Sample spacing (mm) of the dense path check for models that are not grid maps
    /// (`--check-step-mm`); grid maps are bounded exactly (see [`super::bound`]).
    pub check_step_mm: f64,
    /// Longest line the target controller reads (`--max-line-chars`; LinuxCNC: 251). A
    /// rewritten or added line longer than this is refused; the header comment is shortened.
    pub max_line_chars: usize,
    /// The operator's block-delete switch (`--block-delete on|off`).
    pub block_delete: BlockDelete,
    /// Machine angles (deg) of the rotary axes A, B, C at program start, when known
    /// (`--start-rotary-deg`). `None`: unknown until programmed.
    pub start_rotary_deg: Option<[f64; 3]>,
    /// Largest turn (deg) of any rotary axis between two samples of the dense path check of a
    /// move that turns a rotary axis (`--check-step-deg`).
    pub check_step_deg: f64,
}

impl Default for RewriteOptions {
    fn default() -> Self {
        RewriteOptions {
            tolerance_um: 0.5,
            max_segment_mm: 10.0,
            chord_tolerance_um: 0.5,
            max_correction_um: 500.0,
            on_unsupported: OnUnsupported::Refuse,
            decimals_mm: 4,
            decimals_inch: 5,
            default_units: Units::Mm,
            offsets: Offsets::default(),
            max_pieces_per_move: 100_000,
            start_position_mm: None,
            check_step_mm: 0.5,
            max_line_chars: LINUXCNC_MAX_LINE_CHARS,
            block_delete: BlockDelete::Unknown,
            start_rotary_deg: None,
            check_step_deg: 0.5,
        }
    }
}

impl RewriteOptions {
    /// Checks that the numbers make sense; the message names the option.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |v: f64, name: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be a positive number, not {v}"))
            }
        };
        pos(self.tolerance_um, "--tolerance-um")?;
        pos(self.chord_tolerance_um, "--chord-tolerance-um")?;
        pos(self.max_correction_um, "--max-correction-um")?;
        if self.max_segment_mm.is_nan() || self.max_segment_mm <= 0.0 {
            return Err(format!(
                "--max-segment-mm must be positive, not {}",
                self.max_segment_mm
            ));
        }
        pos(self.check_step_mm, "--check-step-mm")?;
        pos(self.check_step_deg, "--check-step-deg")?;
        if let Some(r) = self.start_rotary_deg {
            if !r.iter().all(|v| v.is_finite()) {
                return Err("--start-rotary-deg must be three finite angles".into());
            }
        }
        if self.decimals_mm > 9 || self.decimals_inch > 9 {
            return Err("--decimals must be at most 9".into());
        }
        // rounding a written word moves the command by up to half a unit of its last digit on
        // each axis; that must leave room for the correction's own path error
        for (d, units, flag) in [
            (self.decimals_mm, Units::Mm, "--decimals-mm"),
            (self.decimals_inch, Units::Inch, "--decimals-inch"),
        ] {
            let r = rounding_um(d, units);
            if r > self.tolerance_um / 2.0 {
                let need = (0..=9)
                    .find(|&k| rounding_um(k, units) <= self.tolerance_um / 2.0)
                    .map(|k| format!("use {flag} {k} or more"))
                    .unwrap_or_else(|| "raise --tolerance-um".into());
                return Err(format!(
                    "{flag} {d} rounds every corrected word by up to {r:.3} um (half a unit of the last digit, on three axes), more than half of --tolerance-um {}: the correction would be lost in rounding; {need}",
                    self.tolerance_um
                ));
            }
        }
        if self.max_line_chars < 80 {
            return Err(format!(
                "--max-line-chars {} is too short for a rewritten block (at least 80)",
                self.max_line_chars
            ));
        }
        Ok(())
    }
}

/// LinuxCNC's interpreter refuses longer lines ("Command too long"): rs274 of LinuxCNC 2.9
/// accepts 252 characters and refuses 253, a CR counting as one, so 251 is safe with either
/// line ending (measured; its LINELEN of 255 includes the terminators).
pub const LINUXCNC_MAX_LINE_CHARS: usize = 251;

/// Largest distance (µm) a written position moves when its words are rounded to `decimals`
/// digits: half a unit of the last digit on each of three axes, √3·½·10⁻ᵈ program units.
pub fn rounding_um(decimals: usize, units: Units) -> f64 {
    3f64.sqrt() * 0.5 * 10f64.powi(-(decimals as i32)) * units.mm_per_unit() * 1e3
}

/// What kind of problem stopped the rewrite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ProblemKind {
    /// The line cannot be read (lexer error, two X words, …).
    Syntax,
    /// A construct the rewriter does not compensate (`--on-unsupported`).
    Unsupported,
    /// The correction could not be computed (non-convergence, too large, non-finite).
    Correction,
}

/// A located problem: line and column are 1-based.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Diagnostic {
    pub line: usize,
    pub column: usize,
    pub kind: ProblemKind,
    pub message: String,
}

impl std::fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.message)
    }
}

/// Why a rewrite failed.
#[derive(Debug, thiserror::Error)]
pub enum GcodeError {
    #[error("{0}")]
    At(Diagnostic),
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// What a rewrite did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RewriteReport {
    pub lines_read: usize,
    pub lines_written: usize,
    /// Motion blocks whose end point (or path) was corrected.
    pub moves_compensated: usize,
    /// Lines added by splitting moves and linearising arcs.
    pub lines_added: usize,
    pub arcs_linearised: usize,
    /// Rapid moves left uncompensated because an axis position was not yet known.
    pub rapids_not_compensated: usize,
    /// Feed moves compensated at their end point only (their start position was not known).
    pub moves_end_point_only: usize,
    pub max_correction_um: f64,
    /// The first warnings (at most [`MAX_WARNINGS_KEPT`]) and how many there were in all.
    pub warnings: Vec<Diagnostic>,
    pub warnings_total: usize,
    pub header_written: bool,
    /// Moves that turn a rotary axis (compensated along the joint path).
    pub rotary_moves: usize,
    /// Moves whose F words were rewritten to keep their duration.
    pub feeds_rewritten: usize,
    /// Corrected points outside the model's box ([`ErrorModel::domain_mm`]), where a grid map
    /// is clamped or extrapolated and a fit is beyond its data.
    pub points_outside_model: usize,
    /// The first of them.
    pub first_outside_model: Option<OutsidePoint>,
}

/// A corrected point outside the model's box.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct OutsidePoint {
    pub line: usize,
    pub column: usize,
    /// The point, machine frame (mm).
    pub point_mm: [f64; 3],
    /// The model's box (mm).
    pub domain_mm: [[f64; 2]; 3],
}

/// Warnings kept in the report; the rest are only counted.
pub const MAX_WARNINGS_KEPT: usize = 100;

/// Rewrites a program from `input` to `output`, line by line (memory does not grow with the
/// file). `name` is only used in the header comment.
pub fn rewrite<R: BufRead, W: Write>(
    input: R,
    output: W,
    model: &dyn ErrorModel,
    options: &RewriteOptions,
) -> Result<RewriteReport, GcodeError> {
    let mut rw = Rewriter::new(model, options);
    rw.run(input, output)?;
    Ok(rw.report)
}

struct Rewriter<'a> {
    opt: &'a RewriteOptions,
    st: State,
    report: RewriteReport,
    line_no: usize,
    tokens: Vec<Token>,
    edits: Vec<Edit>,
    extra_lines: Vec<String>,
    out_buf: Vec<u8>,
    tape_started: bool,
    tape_ended: bool,
    seen_content: bool,
    /// The current line writes its letters in lower case (new words follow it).
    lower: bool,
    /// The motion of the current block was written (by `emit_pieces` or as an uncorrected rapid).
    emitted: bool,
    /// The pieces of the current move (reused).
    pieces: Vec<Piece>,
    /// The current block's words (buffers reused from line to line).
    block: Block,
    /// Work list of the move splitting, kept to avoid an allocation per move.
    split_stack: Vec<(f64, [f64; 3], f64, [f64; 3])>,
    /// Bounds the path error of each output piece (exact for grid maps).
    bound: PathBound,
    /// The model seen at the rotary axes' current angles, in machine axes (identical to the
    /// model when it has no rotary axes).
    view: RotaryView<'a>,
    /// The model's box ([`ErrorModel::domain_mm`]).
    domain: Option<[[f64; 2]; 3]>,
    /// The current block moves in machine coordinates (G53).
    g53: bool,
    /// The current move's original-program offsets less the rewritten program's, mm: a word
    /// copied unchanged lands this much off in the rewritten program.
    shift: [f64; 3],
    /// Numbered and named parameters as LinuxCNC sets them (literal values only).
    params: Params,
    /// The rotary move being written, if the current move turns a rotary axis.
    rot_move: Option<RotaryMove>,
    /// The output lines of the current move (for its feed words).
    ends: Vec<EmittedEnd>,
    /// The current line's evaluated words and assignments.
    line_values: LineValues,
    /// A line's parameters could not be evaluated (pass-through mode): from then on parameter
    /// values are not known and computed words are unsupported.
    params_lost: bool,
}

impl<'a> Rewriter<'a> {
    fn new(model: &'a dyn ErrorModel, opt: &'a RewriteOptions) -> Self {
        Rewriter {
            opt,
            st: State::new(opt),
            report: RewriteReport::default(),
            line_no: 0,
            tokens: Vec::new(),
            edits: Vec::new(),
            extra_lines: Vec::new(),
            out_buf: Vec::new(),
            tape_started: false,
            tape_ended: false,
            seen_content: false,
            lower: false,
            emitted: false,
            split_stack: Vec::new(),
            bound: PathBound::new(opt.check_step_mm),
            view: RotaryView::new(model),
            domain: model.domain_mm(),
            g53: false,
            shift: [0.0; 3],
            params: Params::new(),
            rot_move: None,
            ends: Vec::new(),
            line_values: LineValues::default(),
            params_lost: false,
            block: Block::default(),
            pieces: Vec::new(),
        }
    }

    fn run<R: BufRead, W: Write>(&mut self, mut input: R, mut output: W) -> Result<(), GcodeError> {
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
        output.flush()?;
        Ok(())
    }

    fn diag(&self, column: usize, kind: ProblemKind, message: String) -> Diagnostic {
        Diagnostic {
            line: self.line_no,
            column,
            kind,
            message,
        }
    }

    fn column_of(&self, token: Option<usize>) -> usize {
        token
            .and_then(|t| self.tokens.get(t))
            .map(|t| t.span.start + 1)
            .unwrap_or(1)
    }

    /// Refuses, or records a warning and returns Ok (the caller passes the line through).
    fn unsupported(&mut self, d: Diagnostic) -> Result<(), GcodeError> {
        match self.opt.on_unsupported {
            OnUnsupported::Refuse => Err(GcodeError::At(d)),
            OnUnsupported::PassThroughWithWarning => {
                self.report.warnings_total += 1;
                if self.report.warnings.len() < MAX_WARNINGS_KEPT {
                    self.report.warnings.push(d);
                }
                Ok(())
            }
        }
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
        let mut block = std::mem::take(&mut self.block);
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
            for range in system_parameters_written_by(&block.g, &block.m, moved) {
                self.params.forget_numbered(range);
            }
        }
        self.block = block;
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
            }
            self.seen_content = true;
            return self.write_verbatim(body, ending, output);
        }
        if !self.tokens.is_empty() {
            self.seen_content = true;
        }
        self.edits.clear();
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
        let kinematic = self.view.kinematics().is_some();
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
        }

        // --- unsupported: refuse, or warn and pass through ----------------------------------
        if !issues.is_empty() {
            let first = issues
                .iter()
                .min_by_key(|i| self.column_of(i.token))
                .cloned()
                .unwrap_or_else(|| issues[0].clone());
            let d = self.diag(
                self.column_of(first.token),
                ProblemKind::Unsupported,
                first.message.clone(),
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
            self.st.apply_offsets(c);
            self.st.after_block(b);
            return Ok(true);
        }

        // --- G28 / G30: reference-point moves leave the axes at a position we do not know ----
        if let Some(code) = axis_consumer {
            debug_assert!(code == GCode::G28 || code == GCode::G30);
            self.st.reference_move(b, has_axis, motion_word.is_some());
            self.st.after_block(b);
            return Ok(true);
        }

        if let Some(m) = motion {
            self.emitted = false;
            let motion_tok = motion_word.map(|(_, t)| t);
            self.motion_block(b, body, m, motion_tok, g53)?;
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
