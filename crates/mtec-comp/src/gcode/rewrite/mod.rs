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
//! `rewriter` holds the driver loop and the per-line buffers the three share (`Rewriter`); the
//! types they all name are in leaf modules below them: `options` (the knobs), `report` (counts,
//! diagnostics, errors), `piece` (the pieces of a move, rotary moves, written ends) and `words`
//! (rounding and letter case of written words). The modules form layers: leaves, `interp`,
//! `rewriter`, then `plan` / `rotary_move` / `emit` (whose `impl Rewriter` blocks name the
//! driver's type, never the other way round); this file only declares them and re-exports.

use crate::ErrorModel;
use rewriter::Rewriter;
use std::io::{BufRead, Write};

mod emit;
mod interp;
mod options;
mod piece;
mod plan;
mod report;
mod rewriter;
mod rotary_move;
mod words;

pub use emit::header_comment;
pub use options::{
    rounding_um, BlockDelete, OnUnsupported, RewriteOptions, Units, LINUXCNC_MAX_LINE_CHARS,
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
