//! The streaming rewriter: reads a program line by line, tracks the modal state, and writes each
//! line either byte for byte or with only the changed words edited, plus the lines of split moves.

// axis loops index several per-axis arrays at once (target, correction, offsets, words)
#![allow(clippy::needless_range_loop)]

use super::arc::{self, Arc, Plane};
use super::block::{Block, Issue};
use super::bound::{norm, PathBound};
use super::code::GCode;
use super::expr::{system_parameters_written_by, LineValues, Params};
use super::format::{apply_edits, decimal_value, format_number, to_decimal, write_decimal, Edit};
use super::lexer::{lex_line, Token, TokenKind, Value};
use super::modal;
use super::offsets::{work_system_index, Offsets};
use super::rotary::RotaryView;
use super::solve::{correction_mm, SolveError};
use rotary_move::{EmittedEnd, RotaryMove, ROTARY_DECIMALS};

mod rotary_move;
use crate::ErrorModel;
pub use rotary_move::FEED_TOLERANCE;
use std::collections::BTreeMap;
use std::io::{BufRead, Write};

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

/// A point this far outside the model's box (mm) counts as outside (rounding of written words
/// and of the solve stays inside).
const OUTSIDE_MODEL_TOL_MM: f64 = 1e-3;

/// Warnings kept in the report; the rest are only counted.
pub const MAX_WARNINGS_KEPT: usize = 100;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Rapid,
    Linear,
    Cw,
    Ccw,
    /// G80: no motion mode; axis words alone are an error.
    Cancelled,
    /// After an unsupported motion code (canned cycle, probing, …) or poisoning.
    Unknown,
}

impl Motion {
    fn code(self) -> &'static str {
        match self {
            Motion::Rapid => "G0",
            Motion::Linear => "G1",
            Motion::Cw => "G2",
            Motion::Ccw => "G3",
            _ => "",
        }
    }
}

/// The coordinate offsets the controller holds, mm, per axis (`None` = not known).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Frame {
    /// G54 … G59.3 (set from `--offsets`, then by G10 L2 / L20).
    work: [[Option<f64>; 3]; 9],
    /// The G92 offset (G92, G52 set it; G92.1, G92.2 zero it). It applies in every work system,
    /// in addition to the work offset; G53 moves ignore it (LinuxCNC's `rs274`).
    g92: [Option<f64>; 3],
}

impl Frame {
    fn work_of(&self, system: usize) -> Option<[f64; 3]> {
        let w = self.work.get(system)?;
        Some([w[0]?, w[1]?, w[2]?])
    }
}

/// Index into [`State::frames`]: the offsets as the original program sets them.
const PROG: usize = 0;
/// Index into [`State::frames`]: the offsets as the rewritten program sets them.
const OUT: usize = 1;

/// Why a block is refused: the token to report (its column) and the message.
type Refusal = (Option<usize>, String);

/// What a G10 / G92 / G52 block does to the offsets, computed before it is applied.
#[derive(Debug, Clone)]
struct OffsetChange {
    frames: [Frame; 2],
    tool: Option<(u32, f64)>,
}

/// Modal state of the program as the controller would see it; `None` = not known.
#[derive(Debug, Clone)]
struct State {
    /// Where the program's commands put the tool, machine frame, mm.
    prog: [Option<f64>; 3],
    /// Where the rewritten program's commands put the axes, machine frame, mm (as rounded).
    out: [Option<f64>; 3],
    units: Option<Units>,
    absolute: Option<bool>,
    arc_absolute: Option<bool>,
    plane: Option<Plane>,
    work: Option<usize>,
    tool_length_mm: Option<f64>,
    selected_tool: Option<u32>,
    current_tool: Option<u32>,
    motion: Motion,
    out_motion: Motion,
    cutter_comp: bool,
    inverse_time: bool,
    /// G95 (units per revolution) in effect.
    feed_per_rev: bool,
    /// The last F value the program set (its units: per minute, per revolution or inverse
    /// time, as the mode it was given in).
    feed: Option<f64>,
    /// Machine angles (deg) of A, B, C where the program's commands put them (`None`: not
    /// known). The rewritten program puts them at the same angles at the end of every move.
    rot: [Option<f64>; 3],
    /// Coordinate offsets as the original program sets them ([`PROG`]) and as the rewritten
    /// program does ([`OUT`]). They differ only where an offset is set from the current
    /// position (G92, G10 L20): the rewritten program stands at the corrected position there,
    /// so the controller derives a different offset from the same words.
    frames: [Frame; 2],
    /// The tool table's lengths, mm (from `--offsets` / `--tool-table`, then G10 L1).
    tools: BTreeMap<u32, f64>,
}

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

/// The end of one output piece of a move.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Piece {
    /// The target in machine axes (mm) at the piece's rotary angles.
    t: [f64; 3],
    /// The correction (mm): the axes are commanded to `t + c`.
    c: [f64; 3],
    /// The fraction of the original move's duration at the piece's end (1 for the last).
    s: f64,
    /// The rotary axes' machine angles (deg) written at the piece's end, for a move that turns
    /// a rotary axis.
    rot: Option<[f64; 3]>,
}

impl Piece {
    fn new(t: [f64; 3], c: [f64; 3], s: f64) -> Piece {
        Piece { t, c, s, rot: None }
    }
}

impl<'a> Rewriter<'a> {
    fn new(model: &'a dyn ErrorModel, opt: &'a RewriteOptions) -> Self {
        Rewriter {
            opt,
            st: State {
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
                selected_tool: None,
                current_tool: None,
                motion: Motion::Cancelled,
                out_motion: Motion::Cancelled,
                cutter_comp: false,
                inverse_time: false,
                feed_per_rev: false,
                feed: None,
                rot: opt
                    .start_rotary_deg
                    .map(|r| r.map(Some))
                    .unwrap_or([None; 3]),
                frames: {
                    let mut f = Frame {
                        work: [[None; 3]; 9],
                        // the controller's persisted G92 offset is assumed zero at start
                        g92: [Some(0.0); 3],
                    };
                    for i in 0..9 {
                        if let Some(w) = opt.offsets.work(i) {
                            f.work[i] = w.map(Some);
                        }
                    }
                    [f, f]
                },
                tools: opt.offsets.tool_length_mm.clone(),
            },
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

    fn poison_all(&mut self) {
        let st = &mut self.st;
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
        // the line may have set offsets or the tool table (G10, G92, G52, a subprogram…)
        for f in st.frames.iter_mut() {
            f.work = [[None; 3]; 9];
            f.g92 = [None; 3];
        }
        st.tools.clear();
    }

    fn write_verbatim<W: Write>(
        &mut self,
        body: &[u8],
        ending: &[u8],
        output: &mut W,
    ) -> Result<(), GcodeError> {
        output.write_all(body)?;
        output.write_all(ending)?;
        self.report.lines_written += 1;
        Ok(())
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
            self.poison_all();
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
                    self.poison_all();
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
        let bom = self.line_no == 1 && body.starts_with(b"\xEF\xBB\xBF");
        if !self.report.header_written {
            self.report.header_written = true;
            if bom {
                // the byte-order mark stays the first bytes of the file
                output.write_all(b"\xEF\xBB\xBF")?;
            }
            let header = header_comment(self.view.model(), self.opt);
            output.write_all(header.as_bytes())?;
            output.write_all(if ending.is_empty() { b"\n" } else { ending })?;
            self.report.lines_written += 1;
        }
        self.out_buf.clear();
        let mut edits = std::mem::take(&mut self.edits);
        apply_edits(body, &mut edits, &mut self.out_buf);
        self.edits = edits;
        if bom {
            self.out_buf.drain(..3); // no edit touches the mark: the lexer starts after it
        }
        let longest_added = self.extra_lines.iter().map(|l| l.len()).max().unwrap_or(0);
        let edited = self.out_buf.len();
        if (edited > self.opt.max_line_chars && edited > body.len())
            || longest_added > self.opt.max_line_chars
        {
            return Err(GcodeError::At(self.diag(
                1,
                ProblemKind::Correction,
                format!(
                    "the rewritten line would be {} characters, over the controller's limit of {} (--max-line-chars; LinuxCNC refuses longer lines): shorten its comments",
                    edited.max(longest_added),
                    self.opt.max_line_chars
                ),
            )));
        }
        let sep: &[u8] = if ending.is_empty() { b"\n" } else { ending };
        for l in &self.extra_lines {
            self.out_buf.extend_from_slice(sep);
            self.out_buf.extend_from_slice(l.as_bytes());
        }
        self.out_buf.extend_from_slice(ending);
        output.write_all(&self.out_buf)?;
        self.report.lines_written += 1 + self.extra_lines.len();
        self.report.lines_added += self.extra_lines.len();
        Ok(())
    }

    /// Interprets one block; fills `edits` / `extra_lines`. Returns false when the line is to be
    /// passed through unchanged because of an unsupported construct (already warned).
    fn block(&mut self, b: &Block, body: &[u8]) -> Result<bool, GcodeError> {
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
        if b.block_delete && self.opt.block_delete == BlockDelete::Unknown {
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
        for &(code, tok) in &b.g {
            use GCode::*;
            match code {
                G0 => motion_word = Some((Motion::Rapid, tok)),
                G1 => motion_word = Some((Motion::Linear, tok)),
                G2 => motion_word = Some((Motion::Cw, tok)),
                G3 => motion_word = Some((Motion::Ccw, tok)),
                G80 => motion_word = Some((Motion::Cancelled, tok)),
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
                // G92.1 and G92.2 zero the G92 offset (they differ only in parameters 5211-5219)
                G92_1 | G92_2 => g92_reset = true,
                G92_3 => issues.push(Issue {
                    token: Some(tok),
                    message: "G92.3 restores the G92 offset from parameters 5211-5219, whose values are not known here; use G52 or G92 with literal values".into(),
                    poisons_all: true,
                }),
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
        }

        // a G2/G3 block with centre words and no axis words is a full circle (LinuxCNC
        // executes `G3 I-50`, and a line `I-50` in modal G2): it moves like any other arc
        let arc_words = [b'I', b'J', b'K'].iter().any(|&l| b.word(l).is_some());
        let mode_now = motion_word.map(|(m, _)| m).unwrap_or(self.st.motion);
        let has_axis = has_axis
            || (arc_words
                && axis_consumer.is_none()
                && matches!(mode_now, Motion::Cw | Motion::Ccw));

        // --- modal state changes, in the controller's order of execution ------------------
        let st = &mut self.st;
        if b.has_g(GCode::G93).is_some() {
            st.inverse_time = true;
            st.feed_per_rev = false;
        }
        if b.has_g(GCode::G94).is_some() || b.has_g(GCode::G95).is_some() {
            st.inverse_time = false;
            st.feed_per_rev = b.has_g(GCode::G95).is_some();
        }
        if let Some(f) = b.word(b'F') {
            st.feed = match f.value {
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
        for &(code, tok) in &b.g {
            use GCode::*;
            match code {
                G17 => st.plane = Some(arc::XY),
                G18 => st.plane = Some(arc::ZX),
                G19 => st.plane = Some(arc::YZ),
                G20 => st.units = Some(Units::Inch),
                G21 => st.units = Some(Units::Mm),
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
                    if st.tool_length_mm.is_none() {
                        let what = match tool {
                            Some(t) => format!("tool {t} has no length in the offsets file (--offsets, [tool_lengths_mm])"),
                            None => "the tool is not known (no H word and no T… M6 before)".into(),
                        };
                        issues.push(Issue {
                            token: Some(tok),
                            message: format!("G43: {what}"),
                            poisons_all: false,
                        });
                    }
                }
                G49 => st.tool_length_mm = Some(0.0),
                G54 | G55 | G56 | G57 | G58 | G59 | G59_1 | G59_2 | G59_3 => {
                    st.work = work_system_index(code);
                    if let Some(i) = st.work.filter(|&i| st.frames[PROG].work_of(i).is_none()) {
                        st.work = None;
                        issues.push(Issue {
                            token: Some(tok),
                            message: format!(
                                "{} is selected but its offset is not known: give it in the offsets file (--offsets, [work_offsets_mm] {} = [x, y, z]) or set all three axes with G10 L2 first; taking it as zero would compensate the wrong place",
                                code,
                                super::offsets::WORK_SYSTEMS[i]
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
            match self.offset_change(b, code) {
                Ok(c) => offset_change = Some(c),
                Err((tok, message)) => issues.push(Issue {
                    token: tok,
                    message,
                    poisons_all: true,
                }),
            }
        }
        let st = &mut self.st;

        // --- what the axis words mean ------------------------------------------------------
        let mut motion = None;
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
            // the word a refusal points at, when it is not the first axis word
            let mut why_tok: Option<usize> = None;
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
            if why.is_none() {
                let rotary = self.view.rotary_axes();
                let moved_rotary = [b'A', b'B', b'C']
                    .into_iter()
                    .enumerate()
                    .find(|&(_, l)| b.word(l).is_some());
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
                        why = Some(match self.view.kinematics() {
                            Some(kin) => format!(
                                "axis {} moves but the model's machine (chain `{}`) has no {} axis",
                                l as char,
                                kin.chain(),
                                l as char
                            ),
                            None => format!(
                                "axis {} moves but the error model has no rotary axes (a kinematic model, `mtec.kinematic-model/1`, of a chain with {} compensates it)",
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
        }
        if let Some((m, _)) = motion_word {
            st.motion = m;
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
                self.poison_all();
            } else {
                for (a, l) in axis_letters.iter().enumerate() {
                    if b.word(*l).is_some()
                        || (has_axis && matches!(motion, Some(Motion::Cw | Motion::Ccw)))
                    {
                        self.st.prog[a] = None;
                        self.st.out[a] = None;
                    }
                }
                for (k, l) in [b'A', b'B', b'C'].into_iter().enumerate() {
                    if b.word(l).is_some() {
                        self.st.rot[k] = None;
                    }
                }
                if motion_word.is_some() {
                    self.st.out_motion = self.st.motion;
                }
            }
            self.after_block(b);
            return Ok(edited);
        }

        // --- G10 / G92 / G52: new offsets (the line is copied) --------------------------------
        if let Some(c) = offset_change {
            self.st.frames = c.frames;
            if let Some((t, len)) = c.tool {
                self.st.tools.insert(t, len);
            }
            self.after_block(b);
            return Ok(true);
        }

        // --- G28 / G30: reference-point moves leave the axes at a position we do not know ----
        if let Some(code) = axis_consumer {
            debug_assert!(code == GCode::G28 || code == GCode::G30);
            // the rotary axes may go to their reference positions too
            self.st.rot = [None; 3];
            for (a, l) in axis_letters.iter().enumerate() {
                if !has_axis || b.word(*l).is_some() {
                    self.st.prog[a] = None;
                    self.st.out[a] = None;
                }
            }
            if motion_word.is_some() {
                self.st.out_motion = self.st.motion;
            }
            self.after_block(b);
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
        self.after_block(b);
        Ok(true)
    }

    /// Program stops M2/M30 reset modes as LinuxCNC does.
    fn after_block(&mut self, b: &Block) {
        if b.has_m(2).is_some() || b.has_m(30).is_some() {
            let st = &mut self.st;
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
    fn offset_mm(&self, axis: usize, g53: bool, frame: usize) -> Option<f64> {
        if g53 {
            return Some(0.0);
        }
        let f = &self.st.frames[frame];
        let w = f.work[self.st.work?][axis]? + f.g92[axis]?;
        Some(if axis == 2 {
            w + self.st.tool_length_mm?
        } else {
            w
        })
    }

    /// The offsets after a G10 (L1, L2, L20), G92 or G52 block, with LinuxCNC's meaning
    /// (checked with its `rs274`): values in the block's units, absolute also in G91, axes not
    /// given keep their offset; G92 and G10 L20 set an offset so that the current position
    /// becomes the given value. Err: the token to report and why the block is refused.
    fn offset_change(&self, b: &Block, code: GCode) -> Result<OffsetChange, Refusal> {
        let st = &self.st;
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
        if self.view.kinematics().is_some() {
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
                    "{name} sets an offset from the current position, which is not known here for {} (program an absolute move first; the work offset, G92 offset and tool length in effect must be known too)",
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

    fn decimals(&self) -> usize {
        match self.st.units {
            Some(Units::Inch) => self.opt.decimals_inch,
            _ => self.opt.decimals_mm,
        }
    }

    fn motion_block(
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
        self.g53 = g53;
        let scale = units.mm_per_unit();
        // program coordinates → machine: `offsets` as the original program has set them (its
        // targets), `out_offsets` as the rewritten program has (its written words)
        let mut offsets = [0.0; 3];
        let mut out_offsets = [0.0; 3];
        for a in 0..3 {
            match (self.offset_mm(a, g53, PROG), self.offset_mm(a, g53, OUT)) {
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
                                super::offsets::WORK_SYSTEMS[i]
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
        let rot_axes = self.view.rotary_axes();
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
        if let Some(kin) = self.view.kinematics() {
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
        if let Err(msg) = self.view.set_rotary(rot_target) {
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
        let c_start = if start_known {
            Some([0, 1, 2].map(|a| self.st.out[a].unwrap_or(0.0) - self.st.prog[a].unwrap_or(0.0)))
        } else {
            None
        };
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

        match (m, c_start) {
            (Motion::Linear, Some(c0)) => {
                let start_xyz = self.st.out.map(|o| o.unwrap_or(0.0));
                let mut pieces = std::mem::take(&mut self.pieces);
                pieces.clear();
                self.split_linear(start_p, target, c0, c_end, (0.0, 1.0), &mut pieces, col)?;
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
            (Motion::Cw | Motion::Ccw, Some(c0)) => {
                let arc = match self.arc_of(
                    b,
                    start_p,
                    target,
                    m == Motion::Cw,
                    absolute,
                    scale,
                    offsets,
                ) {
                    Ok(a) => a,
                    Err(msg) => {
                        let d = self.diag(col, ProblemKind::Syntax, msg);
                        self.unsupported(d)?;
                        for a in 0..3 {
                            self.st.prog[a] = None;
                            self.st.out[a] = None;
                        }
                        return Ok(());
                    }
                };
                // kept as an arc when the bound of its path error allows it (NaN: linearised,
                // where the pieces report the missing model value)
                let keep = self.arc_bound_um(&arc, c0, c_end) <= self.opt.tolerance_um;
                if keep {
                    let moved = c0 != [0.0; 3] || c_end != [0.0; 3];
                    if let Some(rw) = b.word(b'R').filter(|_| moved) {
                        // R kept with a corrected end point moves the centre, badly so near
                        // 180°: the corrected arc is written in centre form instead
                        self.r_to_center(&arc, rw.token, start_p, c0, out_offsets, scale);
                    } else if self.st.arc_absolute == Some(true) {
                        // endpoints move with the correction; the centre moves with the start's
                        for (a, l) in [b'I', b'J', b'K'].iter().enumerate() {
                            if let Some(w) = b.word(*l) {
                                // and the written word is read with the rewritten program's offsets
                                let shift = c0[a] + self.shift[a];
                                if shift != 0.0 {
                                    let Value::Number(v) = w.value else { continue };
                                    let d = self.decimals();
                                    let (r, n) = rounded(v + shift / scale, d);
                                    let span = self.tokens[w.token].value_span.clone();
                                    if r != v {
                                        let mut s = String::new();
                                        write_rounded(v + shift / scale, d, n, &mut s);
                                        self.edits.push(Edit {
                                            span,
                                            text: s,
                                            order: 0,
                                        });
                                    }
                                }
                            }
                        }
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
                        self.split_linear(prev, v, c_prev, cv, s_range, &mut pieces, col)?;
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
            _ => {
                // rapids and feed moves from an unknown start: end point only
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

    /// A bound (µm) on the tool's distance from the nominal arc when the arc is written as an
    /// arc with its start corrected by `c0` and its end by `c1`: the centre moves with `c0`, so
    /// the path error is at most twice the model's variation over the arc (once along the
    /// way, once through the end radius), plus the solve residuals and the rounding of the end
    /// point and the centre.
    fn arc_bound_um(&mut self, arc: &Arc, c0: [f64; 3], c1: [f64; 3]) -> f64 {
        let (mut lo, mut hi) = arc_box(arc);
        let margin = norm(c0).max(norm(c1));
        for i in 0..3 {
            lo[i] -= margin;
            hi[i] += margin;
        }
        let r = arc.r_start.max(arc.r_end);
        let n_normal = arc.end[arc.plane.normal] - arc.start[arc.plane.normal];
        let length = (arc.sweep.abs() * r).hypot(n_normal);
        let n = ((length / self.opt.check_step_mm).ceil() as usize).clamp(16, 1_000_000);
        let mut samples = (0..=n).map(|k| {
            let p = arc.point(k as f64 / n as f64);
            [0, 1, 2].map(|i| p[i] + c0[i])
        });
        let v = self.bound.variation_um(&self.view, lo, hi, &mut samples);
        let (a, b) = (
            PathBound::end(&self.view, arc.start, c0),
            PathBound::end(&self.view, arc.end, c1),
        );
        2.0 * v + a.residual_um + b.residual_um + 2.0 * self.rounding_now_um()
    }

    /// Replaces the R word of an arc kept as an arc by its centre offsets (I, J, K of the
    /// plane), centre = nominal centre moved with the start's correction `c0`.
    #[allow(clippy::too_many_arguments)]
    fn r_to_center(
        &mut self,
        arc: &Arc,
        r_token: usize,
        start: [f64; 3],
        c0: [f64; 3],
        offsets: [f64; 3],
        scale: f64,
    ) {
        let lower = self.lower;
        let sep = self.sep_for_line();
        let d = self.decimals();
        let absolute_center = self.st.arc_absolute == Some(true);
        let mut text = String::new();
        for (k, axis) in [arc.plane.first, arc.plane.second].into_iter().enumerate() {
            let v = if absolute_center {
                (arc.center[k] + c0[axis] - offsets[axis]) / scale
            } else {
                // incremental: from the written start (start + c0) to the centre + c0
                (arc.center[k] - start[axis]) / scale
            };
            if k > 0 {
                text.push_str(sep);
            }
            text.push(case_letter([b'I', b'J', b'K'][axis], lower) as char);
            let (_, n) = rounded(v, d);
            write_rounded(v, d, n, &mut text);
        }
        let span = self.tokens[r_token].span.clone();
        self.edits.push(Edit {
            span,
            text,
            order: 0,
        });
    }

    /// The correction at a target (mm), with the error located at the block.
    fn correct(&mut self, target: [f64; 3], col: usize) -> Result<[f64; 3], GcodeError> {
        match correction_mm(&self.view, target, self.opt.max_correction_um) {
            Ok(c) => {
                let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * 1e3;
                if n > self.report.max_correction_um {
                    self.report.max_correction_um = n;
                }
                self.note_if_outside_model(target, col);
                Ok(c)
            }
            Err(e) => {
                let msg = match e {
                    SolveError::NotFinite { .. }
                    | SolveError::NotConverged { .. }
                    | SolveError::TooLarge { .. } => {
                        format!(
                            "{e} (target [{:.4}, {:.4}, {:.4}] mm, machine frame)",
                            target[0], target[1], target[2]
                        )
                    }
                };
                Err(GcodeError::At(self.diag(col, ProblemKind::Correction, msg)))
            }
        }
    }

    /// Counts `target` when it lies outside the model's box (the first one with its place).
    fn note_if_outside_model(&mut self, target: [f64; 3], col: usize) {
        let Some(domain_mm) = self.domain else {
            return;
        };
        let outside = (0..3).any(|a| {
            target[a] < domain_mm[a][0] - OUTSIDE_MODEL_TOL_MM
                || target[a] > domain_mm[a][1] + OUTSIDE_MODEL_TOL_MM
        });
        if outside {
            self.report.points_outside_model += 1;
            if self.report.first_outside_model.is_none() {
                self.report.first_outside_model = Some(OutsidePoint {
                    line: self.line_no,
                    column: col,
                    point_mm: target,
                    domain_mm,
                });
            }
        }
    }

    /// Half a unit of the last written digit on three axes, µm (see [`rounding_um`]).
    fn rounding_now_um(&self) -> f64 {
        match self.st.units {
            Some(Units::Inch) => rounding_um(self.opt.decimals_inch, Units::Inch),
            _ => rounding_um(self.opt.decimals_mm, Units::Mm),
        }
    }

    /// A bound (µm) on the tool's distance from the nominal segment ta→tb while the axes move
    /// straight from ta + ca to tb + cb: the solve residuals at the ends, the model's departure
    /// from its chord between them ([`PathBound`]) and the rounding of the written words.
    fn piece_bound_um(&mut self, ta: [f64; 3], ca: [f64; 3], tb: [f64; 3], cb: [f64; 3]) -> f64 {
        let (a, b) = (
            PathBound::end(&self.view, ta, ca),
            PathBound::end(&self.view, tb, cb),
        );
        self.bound
            .chord_departure_um(&self.view, a.p, b.p, a.e, b.e)
            + a.residual_um.max(b.residual_um)
            + self.rounding_now_um()
    }

    fn no_model_value(&self, col: usize) -> GcodeError {
        GcodeError::At(self.diag(
            col,
            ProblemKind::Correction,
            "the error model has no finite value along this move (a map with outside = refuse, and the move leaves its grid?)".into(),
        ))
    }

    #[allow(clippy::too_many_arguments)]
    /// Splits the straight move a→b into pieces whose path error, bounded by
    /// [`Self::piece_bound_um`], is at most `--tolerance-um`; no piece of a compensated move is
    /// longer than `max_segment_mm`. Pushes (target, correction) of each piece's end; the last
    /// is exactly (b, c_b).
    fn split_linear(
        &mut self,
        a: [f64; 3],
        b: [f64; 3],
        c_a: [f64; 3],
        c_b: [f64; 3],
        s_range: (f64, f64),
        pieces: &mut Vec<Piece>,
        col: usize,
    ) -> Result<(), GcodeError> {
        let tol = self.opt.tolerance_um;
        let len = dist(a, b);
        let lerp = |t: f64| -> [f64; 3] {
            if t >= 1.0 {
                b
            } else {
                [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
            }
        };
        let zero = [0.0; 3];
        if c_a == zero && c_b == zero {
            // nothing to correct at the ends: the move stays whole when the model is flat along it
            let bound = self.piece_bound_um(a, c_a, b, c_b);
            if bound.is_nan() {
                return Err(self.no_model_value(col));
            }
            if bound <= tol {
                pieces.push(Piece::new(b, c_b, s_range.1));
                return Ok(());
            }
        }
        let n0 = ((len / self.opt.max_segment_mm).ceil() as usize).max(1);
        if n0 > self.opt.max_pieces_per_move {
            return Err(self.too_many(col));
        }
        let mut t_prev = 0.0;
        let mut c_prev = c_a;
        for k in 1..=n0 {
            let t1 = if k == n0 { 1.0 } else { k as f64 / n0 as f64 };
            let c1 = if k == n0 {
                c_b
            } else {
                self.correct(lerp(t1), col)?
            };
            // depth-first bisection of [t_prev, t1], left half first
            let mut stack = std::mem::take(&mut self.split_stack);
            stack.clear();
            stack.push((t_prev, c_prev, t1, c1));
            while let Some((t0, c0, t1, c1)) = stack.pop() {
                let bound = self.piece_bound_um(lerp(t0), c0, lerp(t1), c1);
                if bound.is_nan() {
                    self.split_stack = stack;
                    return Err(self.no_model_value(col));
                }
                if bound <= tol {
                    let s = s_range.0 + (s_range.1 - s_range.0) * t1;
                    pieces.push(Piece::new(
                        lerp(t1),
                        c1,
                        if t1 >= 1.0 { s_range.1 } else { s },
                    ));
                    if pieces.len() > self.opt.max_pieces_per_move {
                        self.split_stack = stack;
                        return Err(self.too_many(col));
                    }
                } else if (t1 - t0) * len < 1e-6 {
                    self.split_stack = stack;
                    return Err(GcodeError::At(self.diag(
                        col,
                        ProblemKind::Correction,
                        format!(
                            "the path cannot be kept within --tolerance-um {tol}: {bound:.3} um on a piece shorter than 1 nm (is the error model continuous here?)"
                        ),
                    )));
                } else {
                    let tm = 0.5 * (t0 + t1);
                    let cm = self.correct(lerp(tm), col)?;
                    stack.push((tm, cm, t1, c1));
                    stack.push((t0, c0, tm, cm));
                }
            }
            self.split_stack = stack;
            t_prev = t1;
            c_prev = c1;
        }
        Ok(())
    }

    fn too_many(&self, col: usize) -> GcodeError {
        GcodeError::At(self.diag(
            col,
            ProblemKind::Correction,
            format!(
                "the move would need more than {} pieces: the error model changes too fast for --tolerance-um",
                self.opt.max_pieces_per_move
            ),
        ))
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
        Arc::from_center(start, end, center, plane, clockwise, turns)
    }

    /// Makes sure a block that relies on the modal motion mode still moves the way the program
    /// means, when earlier rewriting changed the mode of the output (an arc turned into G1s).
    fn restore_motion_word(&mut self, b: &Block, m: Motion, uses_modal: bool) {
        if uses_modal && self.st.out_motion != m && !m.code().is_empty() {
            let tok = b.first_word.unwrap_or(0);
            let pos = self.tokens.get(tok).map(|t| t.span.start).unwrap_or(0);
            let text = format!("{}{}", case(m.code(), self.lower(b)), self.sep_for(b));
            self.edits.push(Edit {
                span: pos..pos,
                text,
                order: 0,
            });
        }
        self.st.out_motion = m;
    }

    fn lower(&self, _b: &Block) -> bool {
        self.lower
    }

    fn sep_for(&self, b: &Block) -> &'static str {
        let _ = b;
        self.sep_for_line()
    }

    /// " " when the current line separates its words with blanks, "" otherwise.
    fn sep_for_line(&self) -> &'static str {
        let spaced = self
            .tokens
            .windows(2)
            .any(|w| w[1].span.start > w[0].span.end);
        if spaced {
            " "
        } else {
            ""
        }
    }

    /// Writes the pieces of one move: the first on the original line (its words edited), the
    /// others as new `G1` lines. `linearised` arcs lose their G2/G3, I, J, K, R and P words.
    #[allow(clippy::too_many_arguments)]
    fn emit_pieces(
        &mut self,
        b: &Block,
        body: &[u8],
        m: Motion,
        uses_modal: bool,
        pieces: &[Piece],
        words: &[Option<(f64, usize)>; 3],
        offsets: [f64; 3],
        absolute: bool,
        scale: f64,
        linearised: bool,
    ) -> Result<(), GcodeError> {
        let _ = body;
        self.emitted = true;
        let lower = self.lower(b);
        let sep = self.sep_for(b);
        let decimals = self.decimals();
        // --- the original line = first piece -------------------------------------------------
        if linearised {
            for l in [b'I', b'J', b'K', b'R', b'P'] {
                if let Some(w) = b.word(l) {
                    let span = self.removal_span(body, self.tokens[w.token].span.clone());
                    self.edits.push(Edit {
                        span,
                        text: String::new(),
                        order: 0,
                    });
                }
            }
            let g1 = case("G1", lower);
            match b.g.iter().find(|(c, _)| matches!(c, GCode::G2 | GCode::G3)) {
                Some(&(_, tok)) if !uses_modal => {
                    let span = self.tokens[tok].span.clone();
                    self.edits.push(Edit {
                        span,
                        text: g1,
                        order: 0,
                    });
                }
                _ => {
                    if self.st.out_motion != Motion::Linear {
                        let tok = b.first_word.unwrap_or(0);
                        let pos = self.tokens[tok].span.start;
                        self.edits.push(Edit {
                            span: pos..pos,
                            text: format!("{g1}{sep}"),
                            order: 0,
                        });
                    }
                }
            }
            self.st.out_motion = Motion::Linear;
        } else {
            self.restore_motion_word(b, m, uses_modal);
        }
        let edits_before = self.edits.len();
        let insert_at = [b'X', b'Y', b'Z']
            .iter()
            .filter_map(|&l| b.word(l))
            .map(|w| self.tokens[w.token].span.end)
            .max()
            .or_else(|| {
                // no axis word (a full circle): after the line's last word, before a comment
                self.tokens
                    .iter()
                    .rev()
                    .find(|t| matches!(t.kind, TokenKind::Word { .. }))
                    .map(|t| t.span.end)
            })
            .unwrap_or(0);
        let Piece { t: t0, c: c0, .. } = pieces[0];
        let last = pieces.len() == 1;
        for a in 0..3 {
            let want = t0[a] + c0[a];
            let out_prev = self.st.out[a];
            let letter = [b'X', b'Y', b'Z'][a];
            match words[a] {
                Some((v, tok)) => {
                    let span = self.tokens[tok].value_span.clone();
                    // exact shortcut: the final piece with the same correction as before keeps its text
                    let delta = if absolute {
                        c0[a] + self.shift[a]
                    } else {
                        c0[a] - (out_prev.unwrap_or(0.0) - self.st.prog[a].unwrap_or(0.0))
                    };
                    if last && delta == 0.0 {
                        self.st.out[a] = if absolute {
                            Some(v * scale + offsets[a])
                        } else {
                            out_prev.map(|o| o + v * scale)
                        };
                        continue;
                    }
                    let w = if absolute {
                        (want - offsets[a]) / scale
                    } else {
                        (want - out_prev.unwrap_or(0.0)) / scale
                    };
                    let (r, n) = rounded(w, decimals);
                    if r != v {
                        let mut s = String::new();
                        write_rounded(w, decimals, n, &mut s);
                        self.edits.push(Edit {
                            span,
                            text: s,
                            order: 0,
                        });
                    }
                    self.st.out[a] = if absolute {
                        Some(r * scale + offsets[a])
                    } else {
                        out_prev.map(|o| o + r * scale)
                    };
                }
                None => {
                    if let Some(text) =
                        self.new_word(a, want, offsets[a], absolute, scale, decimals)
                    {
                        self.edits.push(Edit {
                            span: insert_at..insert_at,
                            text: format!("{sep}{}{text}", case_letter(letter, lower) as char),
                            order: 1 + a as u8,
                        });
                    }
                }
            }
        }
        if let Some(mv) = self.rot_move.filter(|_| pieces.len() > 1) {
            // a split rotary move: its first piece ends at the first piece's angles
            for k in 0..3 {
                let Some((v, tok)) = mv.words[k] else {
                    continue;
                };
                if mv.r1[k] == mv.r0[k] {
                    continue;
                }
                let n = mv.written_count(k, pieces[0].rot.unwrap_or(mv.r1)[k]);
                if decimal_value(n, ROTARY_DECIMALS) != v {
                    let mut text = String::new();
                    write_decimal(n, ROTARY_DECIMALS, &mut text);
                    let span = self.tokens[tok].value_span.clone();
                    self.edits.push(Edit {
                        span,
                        text,
                        order: 0,
                    });
                }
            }
        }
        self.ends.clear();
        self.ends.push(EmittedEnd {
            line: None,
            s: pieces[0].s,
            xyz: self.st.out.map(|o| o.unwrap_or(0.0)),
            rot: pieces[0].rot,
        });
        if self.edits.len() > edits_before || pieces.len() > 1 || linearised {
            self.report.moves_compensated += 1;
        }
        // --- the other pieces as new lines -----------------------------------------------
        for (i, &Piece { t, c, s, rot }) in pieces.iter().enumerate().skip(1) {
            // G53 is not modal: every piece of a machine-coordinate move repeats it
            let mut line = case(if self.g53 { "G53 G1" } else { "G1" }, lower);
            let mut moved = false;
            for a in 0..3 {
                if let Some(text) =
                    self.new_word(a, t[a] + c[a], offsets[a], absolute, scale, decimals)
                {
                    line.push(' ');
                    line.push(case_letter([b'X', b'Y', b'Z'][a], lower) as char);
                    line.push_str(&text);
                    moved = true;
                }
            }
            if let (Some(mv), Some(w)) = (self.rot_move, rot) {
                let prev = pieces[i - 1].rot.unwrap_or(mv.r0);
                let last = i + 1 == pieces.len();
                for k in 0..3 {
                    if mv.r1[k] == mv.r0[k] || (w[k] == prev[k] && !last) {
                        continue;
                    }
                    let text = if last {
                        mv.last_word_text(k, &self.tokens, body, prev[k])
                    } else {
                        Some(mv.word_text(k, w[k], prev[k]))
                    };
                    if let Some(text) = text {
                        line.push(' ');
                        line.push(case_letter([b'A', b'B', b'C'][k], lower) as char);
                        line.push_str(&text);
                        moved = true;
                    }
                }
            }
            if moved {
                self.ends.push(EmittedEnd {
                    line: Some(self.extra_lines.len()),
                    s,
                    xyz: self.st.out.map(|o| o.unwrap_or(0.0)),
                    rot,
                });
                self.extra_lines.push(line);
            } else if let Some(e) = self.ends.last_mut() {
                // nothing written: the previous line's move takes this piece's time too
                e.s = s;
            }
            self.st.out_motion = Motion::Linear;
        }
        Ok(())
    }

    /// The value text of a word moving axis `a` to `want_mm` (machine frame), or None when the
    /// rounded command would not change; updates the output position.
    fn new_word(
        &mut self,
        a: usize,
        want_mm: f64,
        offset: f64,
        absolute: bool,
        scale: f64,
        decimals: usize,
    ) -> Option<String> {
        let prev = self.st.out[a];
        if prev == Some(want_mm) {
            return None;
        }
        let mut s = String::new();
        if absolute {
            let w = (want_mm - offset) / scale;
            let (r, n) = rounded(w, decimals);
            if let Some(p) = prev {
                // unchanged after rounding: no word
                let (rp, _) = rounded((p - offset) / scale, decimals);
                if rp == r {
                    return None;
                }
            }
            write_rounded(w, decimals, n, &mut s);
            self.st.out[a] = Some(r * scale + offset);
        } else {
            let p = prev?;
            let w = (want_mm - p) / scale;
            let (r, n) = rounded(w, decimals);
            if r == 0.0 {
                return None;
            }
            write_rounded(w, decimals, n, &mut s);
            self.st.out[a] = Some(p + r * scale);
        }
        Some(s)
    }

    /// The span to delete for a removed word: with the blanks before it, or (when it starts
    /// the line) with the blanks after it, so no double or leading blank is left.
    fn removal_span(&self, body: &[u8], span: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let blank = |c: u8| c == b' ' || c == b'\t';
        let mut s = span.start;
        while s > 0 && blank(body[s - 1]) {
            s -= 1;
        }
        if s > 0 {
            return s..span.end;
        }
        let mut e = span.end;
        while e < body.len() && blank(body[e]) {
            e += 1;
        }
        span.start..e
    }
}

/// An axis-aligned box (mm) holding every point of the arc: its end points and, at both radii,
/// the in-plane extremes (multiples of 90°) its sweep passes.
fn arc_box(arc: &Arc) -> ([f64; 3], [f64; 3]) {
    let mut lo = [0.0; 3];
    let mut hi = [0.0; 3];
    for i in 0..3 {
        lo[i] = arc.start[i].min(arc.end[i]);
        hi[i] = arc.start[i].max(arc.end[i]);
    }
    let (f, s) = (arc.plane.first, arc.plane.second);
    let (a0, a1) = if arc.sweep >= 0.0 {
        (arc.theta_start, arc.theta_start + arc.sweep)
    } else {
        (arc.theta_start + arc.sweep, arc.theta_start)
    };
    let half_pi = std::f64::consts::FRAC_PI_2;
    let mut k = (a0 / half_pi).ceil();
    let mut angles = vec![a0, a1];
    while k * half_pi <= a1 && angles.len() < 12 {
        angles.push(k * half_pi);
        k += 1.0;
    }
    for th in angles {
        for r in [arc.r_start, arc.r_end] {
            let p = [arc.center[0] + r * th.cos(), arc.center[1] + r * th.sin()];
            lo[f] = lo[f].min(p[0]);
            hi[f] = hi[f].max(p[0]);
            lo[s] = lo[s].min(p[1]);
            hi[s] = hi[s].max(p[1]);
        }
    }
    (lo, hi)
}

/// Length (mm) of an arc as LinuxCNC's interpreter measures it for inverse-time feeds
/// (`find_arc_length`): the helix over the start radius, √((r·|θ|)² + Δnormal²).
fn arc_length(arc: &Arc) -> f64 {
    let n = arc.plane.normal;
    (arc.r_start * arc.sweep.abs()).hypot(arc.end[n] - arc.start[n])
}

/// `v` rounded to `decimals` digits: the value the written word stands for, and its count.
fn rounded(v: f64, decimals: usize) -> (f64, Option<i64>) {
    match to_decimal(v, decimals) {
        Some(n) => (decimal_value(n, decimals), Some(n)),
        None => (v, None),
    }
}

fn write_rounded(v: f64, decimals: usize, n: Option<i64>, out: &mut String) {
    match n {
        Some(n) => write_decimal(n, decimals, out),
        None => format_number(v, decimals, out),
    }
}

fn case(code: &str, lower: bool) -> String {
    if lower {
        code.to_ascii_lowercase()
    } else {
        code.to_string()
    }
}

fn case_letter(l: u8, lower: bool) -> u8 {
    if lower {
        l.to_ascii_lowercase()
    } else {
        l
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The provenance comment written before the first rewritten line.
pub fn header_comment(model: &dyn ErrorModel, opt: &RewriteOptions) -> String {
    let describe: String = model
        .describe()
        .chars()
        .map(|c| match c {
            '(' => '[',
            ')' => ']',
            '\n' | '\r' => ' ',
            c if c.is_ascii() => c,
            _ => '?',
        })
        .collect();
    let knobs = format!(
        "; tolerance {} um, max segment {} mm, chord tolerance {} um)",
        opt.tolerance_um, opt.max_segment_mm, opt.chord_tolerance_um
    );
    let head = format!(
        "(mtec compensate gcode {}: lines below corrected with model: ",
        env!("CARGO_PKG_VERSION")
    );
    // the whole comment stays within the controller's line length: the model's description
    // is shortened (with "...") when it would not fit
    let room = opt
        .max_line_chars
        .saturating_sub(head.len() + knobs.len())
        .max(8);
    let describe = if describe.len() > room {
        format!("{}...", &describe[..room - 3])
    } else {
        describe
    };
    format!("{head}{describe}{knobs}")
}
