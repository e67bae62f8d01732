//! What a rewrite reports: the counts of [`RewriteReport`], the located problems
//! ([`Diagnostic`], [`ProblemKind`]) and the error that stops it ([`GcodeError`]). A leaf: it
//! uses no other module of the rewriter.

/// What kind of problem stopped the rewrite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ProblemKind {
    /// The line cannot be read (lexer error, two X words, …).
    Syntax,
    /// A construct the rewriter does not compensate (`--on-unsupported`).
    Unsupported,
    /// The correction could not be computed (non-convergence, too large, non-finite).
    Correction,
    /// The line is compensated, but the controller may not run it as written (a warning only).
    Controller,
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
    /// Corrected points outside the model's box ([`crate::ErrorModel::domain_mm`]), where a grid map
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
