//! The streaming rewriter: reads a program line by line, tracks the modal state, and writes each
//! line either byte for byte or with only the changed words edited, plus the lines of split moves.
//!
//! This module is the public API ([`rewrite`], [`RewriteOptions`],
//! [`RewriteReport`], the errors): it reads lines, evaluates parameters, and hands each block
//! in turn to
//! - `interp`: the modal state machine (modes, offsets, tool, positions known or not) and
//!   the constructs it cannot follow; it writes no text;
//! - `plan`: a motion block turned into corrected pieces (targets, corrections, splitting to
//!   the path-error bound, arcs), with `rotary_move` for moves that turn a rotary axis;
//! - `emit`: the pieces written as edits of the line and added lines (rounding, case,
//!   separators), the header comment, the line length limit.
//!
//! Separate types: the interpreter's `State` (`interp`), the `Planner` (`planner`: corrections,
//! path-error bounds, splitting; it owns the model's view and writes no text) and the driver
//! `Rewriter` (`rewriter`: the line loop, the per-line buffers, and the `Planner` and `State` it
//! owns). The orchestration of a motion block (`plan`, `rotary_move`) and the emitter (`emit`)
//! are still `impl Rewriter` blocks: the emitter moves the output position that lives in
//! `State`. The types they all name are in leaf modules: `options` (the knobs), `report`
//! (counts, diagnostics, errors), `piece` (the pieces of a move, rotary moves, written ends)
//! and `words` (rounding and letter case of written words). The modules form layers: leaves,
//! `interp` and `planner`, `rewriter`, then `plan` / `rotary_move` / `emit` (which name the
//! driver's type, never the other way round); this file only declares them and re-exports.

use crate::ErrorModel;
use rewriter::Rewriter;
use std::io::{BufRead, Write};

mod block_checks;
mod emit;
mod interp;
mod motion;
mod options;
mod piece;
mod plan;
mod planner;
mod report;
mod rewriter;
mod rotary_move;
mod words;

pub use emit::header_comment;
pub use options::{
    default_decimals, rounding_um, BlockDelete, OnUnsupported, RewriteOptions, Units,
    LINUXCNC_MAX_LINE_CHARS,
};
pub use report::{
    Diagnostic, GcodeError, OutsidePoint, ProblemKind, RewriteReport, MAX_WARNINGS_KEPT,
};
pub use rotary_move::FEED_TOLERANCE;

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
