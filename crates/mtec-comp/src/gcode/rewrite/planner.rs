//! The planner's numbers: the correction at a target ([`correction_mm`]), the bound of a
//! piece's path error ([`PathBound`]) and the splitting of a straight move until every piece is
//! within `--tolerance-um`, the bound of an arc kept whole. [`Planner`] owns what they work
//! on (the model seen at the rotary axes' angles, the bound's caches, the splitting's work
//! list); [`At`] is where the block is and what it reports to. It writes no text and changes no
//! modal state: `plan` (the motion block) and `rotary_move` call it, `emit` never does.

// axis loops index several per-axis arrays at once (target, correction, bounds)
#![allow(clippy::needless_range_loop)]

use super::super::arc::Arc;
use super::super::bound::{norm, MoveEnd, PathBound};
use super::super::rotary::RotaryView;
use super::super::solve::{correction_mm, SolveError};
use super::options::{rounding_in_effect_um, RewriteOptions, Units};
use super::piece::{dist, Piece};
use super::report::{Diagnostic, GcodeError, OutsidePoint, ProblemKind, RewriteReport};
use crate::ErrorModel;

/// A point this far outside the model's box (mm) counts as outside (rounding of written words
/// and of the solve stays inside).
const OUTSIDE_MODEL_TOL_MM: f64 = 1e-3;

/// The planner: the model seen at the rotary axes' current angles and what bounding and
/// splitting a move reuse from one move to the next.
pub(super) struct Planner<'a> {
    /// The model seen at the rotary axes' current angles, in machine axes (identical to the
    /// model when it has no rotary axes).
    pub(super) view: RotaryView<'a>,
    /// Bounds the path error of each output piece (exact for grid maps).
    bound: PathBound,
    /// Work list of the move splitting, kept to avoid an allocation per move.
    split_stack: Vec<(f64, [f64; 3], f64, [f64; 3])>,
    /// The model's box ([`ErrorModel::domain_mm`]).
    domain: Option<[[f64; 2]; 3]>,
    /// The last piece end [`Planner::piece_bound_um`] computed, with its target, correction
    /// and rotary angles (bits): the next piece starts there (one model evaluation saved per
    /// piece of a program of short moves).
    last_end: Option<([[u64; 3]; 3], MoveEnd)>,
}

/// Where a planning step is and what it answers to: the options, the units in effect (for the
/// rounding of written words), the block's line and column (for its errors) and the report
/// (largest correction, points outside the model).
pub(super) struct At<'s> {
    pub(super) opt: &'s RewriteOptions,
    pub(super) units: Option<Units>,
    pub(super) line: usize,
    pub(super) col: usize,
    pub(super) report: &'s mut RewriteReport,
}

impl At<'_> {
    /// The error of this block.
    pub(super) fn error(&self, kind: ProblemKind, message: String) -> GcodeError {
        GcodeError::At(Diagnostic {
            line: self.line,
            column: self.col,
            kind,
            message,
        })
    }

    /// Half a unit of the last written digit on three axes in the units in effect, µm.
    pub(super) fn rounding_um(&self) -> f64 {
        rounding_in_effect_um(self.opt, self.units)
    }

    pub(super) fn no_model_value(&self) -> GcodeError {
        self.error(
            ProblemKind::Correction,
            "the error model has no finite value along this move (a map with outside = refuse, and the move leaves its grid?)".into(),
        )
    }

    pub(super) fn too_many(&self) -> GcodeError {
        self.error(
            ProblemKind::Correction,
            format!(
                "the move would need more than {} pieces: the error model changes too fast for --tolerance-um",
                self.opt.max_pieces_per_move
            ),
        )
    }
}

impl<'a> Planner<'a> {
    pub(super) fn new(model: &'a dyn ErrorModel, opt: &RewriteOptions) -> Self {
        Planner {
            view: RotaryView::new(model),
            bound: PathBound::new(opt.check_step_mm),
            split_stack: Vec::new(),
            domain: model.domain_mm(),
            last_end: None,
        }
    }

    /// A bound (µm) on the tool's distance from the nominal arc when the arc is written as an
    /// arc with its start corrected by `c0` and its end by `c1`: the centre moves with `c0`, so
    /// the path error is at most twice the model's variation over the arc (once along the
    /// way, once through the end radius), plus the solve residuals and the rounding of the end
    /// point and the centre.
    pub(super) fn arc_bound_um(&mut self, arc: &Arc, c0: [f64; 3], c1: [f64; 3], at: &At) -> f64 {
        let (mut lo, mut hi) = arc_box(arc);
        let margin = norm(c0).max(norm(c1));
        for i in 0..3 {
            lo[i] -= margin;
            hi[i] += margin;
        }
        let r = arc.r_start.max(arc.r_end);
        let n_normal = arc.end[arc.plane.normal] - arc.start[arc.plane.normal];
        let length = (arc.sweep.abs() * r).hypot(n_normal);
        let n = ((length / at.opt.check_step_mm).ceil() as usize).clamp(16, 1_000_000);
        let mut samples = (0..=n).map(|k| {
            let p = arc.point(k as f64 / n as f64);
            [0, 1, 2].map(|i| p[i] + c0[i])
        });
        let v = self.bound.variation_um(&self.view, lo, hi, &mut samples);
        let (a, b) = (
            PathBound::end(&self.view, arc.start, c0),
            PathBound::end(&self.view, arc.end, c1),
        );
        2.0 * v + a.residual_um + b.residual_um + 2.0 * at.rounding_um()
    }

    /// The correction at a target (mm), with the error located at the block.
    pub(super) fn correct(&self, target: [f64; 3], at: &mut At) -> Result<[f64; 3], GcodeError> {
        match correction_mm(&self.view, target, at.opt.max_correction_um) {
            Ok(c) => {
                let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * 1e3;
                if n > at.report.max_correction_um {
                    at.report.max_correction_um = n;
                }
                self.note_if_outside_model(target, at);
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
                Err(at.error(ProblemKind::Correction, msg))
            }
        }
    }

    /// Counts `target` when it lies outside the model's box (the first one with its place).
    fn note_if_outside_model(&self, target: [f64; 3], at: &mut At) {
        let Some(domain_mm) = self.domain else {
            return;
        };
        let outside = (0..3).any(|a| {
            target[a] < domain_mm[a][0] - OUTSIDE_MODEL_TOL_MM
                || target[a] > domain_mm[a][1] + OUTSIDE_MODEL_TOL_MM
        });
        if outside {
            at.report.points_outside_model += 1;
            if at.report.first_outside_model.is_none() {
                at.report.first_outside_model = Some(OutsidePoint {
                    line: at.line,
                    column: at.col,
                    point_mm: target,
                    domain_mm,
                });
            }
        }
    }

    /// A bound (µm) on the tool's distance from the nominal segment ta→tb while the axes move
    /// straight from ta + ca to tb + cb: the solve residuals at the ends, the model's departure
    /// from its chord between them ([`PathBound`]) and the rounding of the written words.
    pub(super) fn piece_bound_um(
        &mut self,
        ta: [f64; 3],
        ca: [f64; 3],
        tb: [f64; 3],
        cb: [f64; 3],
        at: &At,
    ) -> f64 {
        let (a, b) = (self.end(ta, ca), self.end(tb, cb));
        self.bound
            .chord_departure_um(&self.view, a.p, b.p, a.e, b.e)
            + a.residual_um.max(b.residual_um)
            + at.rounding_um()
    }

    /// [`PathBound::end`] of target `t` corrected by `c` in the current view, computed again
    /// only when `t`, `c` or the rotary angles differ (in any bit) from the last end's. The
    /// model is borrowed unchanged for the whole rewrite, so the same point gives the same
    /// value: the cache changes no result.
    fn end(&mut self, t: [f64; 3], c: [f64; 3]) -> MoveEnd {
        let key = [t, c, self.view.rotary_deg()].map(|v| v.map(f64::to_bits));
        if let Some((k, e)) = self.last_end {
            // an OR of XORs (no early exit, no memcmp call)
            let differ = k
                .iter()
                .flatten()
                .zip(key.iter().flatten())
                .fold(0, |acc, (a, b)| acc | (a ^ b));
            if differ == 0 {
                return e;
            }
        }
        let e = PathBound::end(&self.view, t, c);
        self.last_end = Some((key, e));
        e
    }

    #[allow(clippy::too_many_arguments)]
    /// Splits the straight move a→b into pieces whose path error, bounded by
    /// [`Self::piece_bound_um`], is at most `--tolerance-um`; no piece of a compensated move is
    /// longer than `max_segment_mm`. Pushes (target, correction) of each piece's end; the last
    /// is exactly (b, c_b).
    pub(super) fn split_linear(
        &mut self,
        a: [f64; 3],
        b: [f64; 3],
        c_a: [f64; 3],
        c_b: [f64; 3],
        s_range: (f64, f64),
        pieces: &mut Vec<Piece>,
        at: &mut At,
    ) -> Result<(), GcodeError> {
        let tol = at.opt.tolerance_um;
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
            let bound = self.piece_bound_um(a, c_a, b, c_b, at);
            if bound.is_nan() {
                return Err(at.no_model_value());
            }
            if bound <= tol {
                pieces.push(Piece::new(b, c_b, s_range.1));
                return Ok(());
            }
        }
        let n0 = ((len / at.opt.max_segment_mm).ceil() as usize).max(1);
        if n0 > at.opt.max_pieces_per_move {
            return Err(at.too_many());
        }
        let mut t_prev = 0.0;
        let mut c_prev = c_a;
        for k in 1..=n0 {
            let t1 = if k == n0 { 1.0 } else { k as f64 / n0 as f64 };
            let c1 = if k == n0 {
                c_b
            } else {
                self.correct(lerp(t1), at)?
            };
            // depth-first bisection of [t_prev, t1], left half first
            let mut stack = std::mem::take(&mut self.split_stack);
            stack.clear();
            stack.push((t_prev, c_prev, t1, c1));
            while let Some((t0, c0, t1, c1)) = stack.pop() {
                let bound = self.piece_bound_um(lerp(t0), c0, lerp(t1), c1, at);
                if bound.is_nan() {
                    self.split_stack = stack;
                    return Err(at.no_model_value());
                }
                if bound <= tol {
                    let s = s_range.0 + (s_range.1 - s_range.0) * t1;
                    pieces.push(Piece::new(
                        lerp(t1),
                        c1,
                        if t1 >= 1.0 { s_range.1 } else { s },
                    ));
                    if pieces.len() > at.opt.max_pieces_per_move {
                        self.split_stack = stack;
                        return Err(at.too_many());
                    }
                } else if (t1 - t0) * len < 1e-6 {
                    self.split_stack = stack;
                    return Err(at.error(
                        ProblemKind::Correction,
                        format!(
                            "the path cannot be kept within --tolerance-um {tol}: {bound:.3} um on a piece shorter than 1 nm (is the error model continuous here?)"
                        ),
                    ));
                } else {
                    let tm = 0.5 * (t0 + t1);
                    let cm = self.correct(lerp(tm), at)?;
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
