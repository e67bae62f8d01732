//! G-code rewriting: the commanded points of an NC program corrected so the machine cuts true.
//!
//! The method (SPEC §1 C, "the ideal NC program is reconstructed by adding the reversed error to
//! each commanded position"): for every commanded point `t` the rewritten program commands
//! `p = t + c` where `p + e(p) = t` ([`solve`]). Feed moves are split until a bound of the
//! tool's distance from the programmed path ([`bound`]: exact for grid maps) is within
//! `--tolerance-um` on every piece, arcs are linearised when that bound does not hold for the
//! arc kept whole, rapids are corrected at their end points only.
//!
//! Design decisions (the spec is silent on these):
//! - **Our own lexer** ([`lexer`]): each line's text is kept; only the words that change are
//!   edited, so comments, line numbers, unknown words, spacing, letter case and line endings
//!   (LF or CRLF, a missing last newline, bytes inside comments) survive as they were.
//! - **Zero model ⇒ byte-identical output.** A word whose correction is exactly zero keeps its
//!   text, no axis word is added when the output position does not change, and the
//!   `--max-segment-mm` split only applies to moves with a non-zero correction.
//! - **Provenance header, written lazily**: the comment naming the model and the knobs is
//!   written just before the first line that changes. A program the model leaves untouched
//!   (a zero model) therefore stays byte-identical, and in a compensated program the comment
//!   still precedes every corrected line. (A `%` first line stays first.)
//! - **Split pieces**: the original line becomes the first piece (so its other words — F, S,
//!   M3, G91, its line number and comments — act first, as the controller orders a block), the
//!   other pieces follow as new `G1` lines without line numbers (`G53 G1` for a G53 move). A
//!   piece is accepted when its path bound (solve residuals at its ends + the model's
//!   departure from its chord + the rounding of the written words) is within `--tolerance-um`;
//!   otherwise it is halved. The last piece ends exactly at the original target plus its
//!   correction. Full circles written without axis words (`G3 I-50`, a modal `I-50`) are moves
//!   like any other.
//! - **Arcs**: kept as arcs (the end point, the centre of G90.1 arcs, and an R arc rewritten
//!   in centre form, since keeping R moves the centre) when twice the model's variation over
//!   the arc plus residuals and rounding is within the tolerance; otherwise replaced by chords
//!   of sagitta ≤ `--chord-tolerance-um`, each split like a feed move. A block relying on the
//!   modal G2/G3 after a linearised arc gets its G2/G3 word back.
//! - **Rounding**: changed words are written with 4 decimals in mm and 5 in inch (configurable);
//!   positions are tracked as the rounded output commands, so incremental (G91) programs do
//!   not drift.
//! - **Parameters and expressions** with literal values are evaluated as LinuxCNC does
//!   ([`expr`]); two codes of one modal group are refused as LinuxCNC refuses them ([`modal`]).
//! - **Unsupported constructs** (parameters that cannot be evaluated, O-word subroutines and
//!   control flow, canned cycles, G41/G42, G93, G92.3, G10 other than L1/L2/L20 or with a
//!   rotation, rotary or polar axis words, M98/M99, block delete on motion) are refused naming `line:column`, or with
//!   [`OnUnsupported::PassThroughWithWarning`] copied unchanged with a warning; everything the
//!   construct may have changed is then treated as unknown until the program sets it again.
//!   Most of them can go through [`flatten`] first: LinuxCNC's interpreter runs the program and
//!   its moves are written as a plain program (`compensate gcode --flatten-with rs274`).
//! - **Offsets set by the program** (G10 L1/L2/L20, G92, G52, G92.1, G92.2 with literal values)
//!   are modal state, with LinuxCNC's meaning (see `rewrite/interp.rs`, `offset_change`, and
//!   docs/formats.md, "Offsets the program sets").
//! - **Positions not yet known** (the first moves of a program, after G28/G30): rapids are
//!   copied uncorrected; feed moves to a known end point from an unknown start are corrected at
//!   their end point only; arcs from an unknown start are unsupported. The move to a G28/G30
//!   reference point (a controller parameter) is copied with a warning; an intermediate point
//!   that moves is unsupported. A G80 beside G0–G3 in one block is ignored, as LinuxCNC does.
//! - Lines after a closing `%` tape mark are copied untouched (the controller never reads them).
//!   A `%` that is neither the first line (blank lines before it allowed) nor after M2/M30 is
//!   refused as LinuxCNC refuses it ("Bad character '%' used").
//! - **Units and start**: before the first G20/G21 the units are `default_units` (mm unless
//!   told); the machine position at program start is unknown unless `start_position_mm` is
//!   given (a lathe program never states Y: give the fixed Y there).
//! - **Errors**: a correction that does not converge, is not finite, or exceeds
//!   `max_correction_um` always stops the run (whatever `--on-unsupported` says), naming
//!   `line:column` of the block.
//!
//! Robustness (issue 10): `tests/gcode_properties.rs` checks the invariants on generated
//! programs and on arbitrary bytes in CI; the cargo-fuzz target `fuzz/fuzz_targets/gcode_rewrite.rs`
//! checks the same without a time bound:
//! `cd fuzz && cargo +nightly fuzz run gcode_rewrite corpus/gcode_rewrite seeds/gcode_rewrite -- -max_total_time=600 -max_len=4096`.
//!
//! Speed (one core, `cargo bench -p mtec-comp --bench gcode`, 200 k short moves, load 2.6–3.4):
//! pass-through 1.76 M lines/s, compensation 1.06 M lines/s with a polynomial model and
//! 0.72 M lines/s with a 25×25×3 trilinear map (the exact path bound included); memory stays at
//! a few MB whatever the file size.

pub mod arc;
pub mod block;
pub mod bound;
pub mod canon;
pub mod code;
pub mod expr;
pub mod flatten;
pub mod format;
pub mod lexer;
pub mod line_numbers;
pub mod modal;
pub mod offsets;
pub mod rewrite;
pub mod rotary;
pub mod runtime_params;
pub mod solve;
pub mod start_probe;
pub mod tooltable;

pub use code::GCode;
pub use offsets::{Offsets, OffsetsFile};
pub use rewrite::{
    default_decimals, header_comment, rewrite, BlockDelete, Diagnostic, GcodeError, OnUnsupported,
    OutsidePoint, ProblemKind, RewriteOptions, RewriteReport, Units,
};
pub use solve::{correction_mm, SolveError};
