//! Identifiability of a line design: numerical rank of the column-scaled design matrix (SVD),
//! the elements its null space touches, and the rule that decides which of a confounded group
//! is not identified.
//!
//! Method: the columns of A are scaled to unit norm (so that µm, µrad and polynomial powers
//! compare), A = QR once (Householder), and the singular values of A_S = Q·R_S for any column
//! subset S are those of the small R_S (Golub & Van Loan §5.4.5: R-SVD). A singular value below
//! `RANK_TOL`·σ_max counts as zero. One SVD of R gives the null space N; dropping an element's
//! columns B leaves the null space {v ∈ N : v_B = 0}, found from N alone. While it is not empty:
//! 1. N = the right singular vectors of the zero singular values (the null space);
//! 2. the *weight* of an element is ‖N restricted to its columns‖²: how much of the null space
//!    lives in its coefficients; elements with weight > 1e-6 are *touched*;
//! 3. of the touched elements, drop the one first in this order (ties: larger weight, then
//!    ISO order): angular error motion of a tool-side axis (at a single tool offset it acts
//!    through a fixed lever and is indistinguishable from a translation of the same axis),
//!    angular error motion of a workpiece-side axis, straightness, squareness, positioning;
//! 4. record what it is confounded with: the elements (and alignment slopes) that carry weight
//!    in the null-space directions that concentrate on the dropped element's columns (the
//!    eigenvectors of N_B·N_Bᵀ with non-zero eigenvalue).
//!
//! A dropped element is reported by name and gets no number; the elements it was confounded
//! with then absorb its effect at the measured poses (e.g. `EXZ` absorbs L·`EBZ` for the tool
//! length L of the measurement), so predictions are valid at the measured tool offset only.

use super::model::{Block, ElementKind, Layout};
use mtec_model::ErrorElement;
use nalgebra::{DMatrix, DVector, SymmetricEigen, SVD};

/// A singular value below this fraction of the largest counts as zero.
pub const RANK_TOL: f64 = 1e-9;
/// Null-space weight above which an element or slope counts as involved.
const TOUCH_TOL: f64 = 1e-6;

/// An element the design cannot determine.
#[derive(Debug, Clone, PartialEq)]
pub struct Dropped {
    pub element: ErrorElement,
    /// Elements that take up its effect (its confounding partners among the kept ones).
    pub confounded_with: Vec<ErrorElement>,
    /// True when a straightness alignment slope is part of the confounding combination.
    pub with_alignment: bool,
    /// True when it does not reach any reading at all (zero columns).
    pub zero_sensitivity: bool,
}

/// The column-scaled, QR-factorised design with the rank analysis done.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// Column norms of A (1 for zero columns): parameter = scaled parameter / scale.
    pub scale: DVector<f64>,
    /// R of the scaled non-zero columns A_c·diag(1/scale) = QR (k × k).
    pub r: DMatrix<f64>,
    /// Q_keptᵀy: the readings rotated by the kept design's orthogonal factor (k_kept).
    pub qty: DVector<f64>,
    /// Singular values of the full scaled design, descending.
    pub singular_values: Vec<f64>,
    /// Numerical rank of the full design (zero columns count as deficient).
    pub rank: usize,
    /// Columns (original indices) kept after dropping unidentifiable elements.
    pub active: Vec<usize>,
    /// Dropped elements, in the order they were dropped.
    pub dropped: Vec<Dropped>,
    /// Upper-triangular R of the kept (full-rank, column-scaled) design.
    pub kept_r: DMatrix<f64>,
    /// Singular values of the kept design, descending.
    pub kept_singular_values: Vec<f64>,
}

impl Analysis {
    /// Condition number σ_max/σ_min of the kept (full-rank, column-scaled) design.
    pub fn condition_number(&self) -> f64 {
        let s = &self.kept_singular_values;
        match (s.first(), s.last()) {
            (Some(a), Some(b)) if *b > 0.0 => a / b,
            _ => f64::INFINITY,
        }
    }
}

/// Drop order of an element (higher: dropped first).
pub fn drop_priority(b: &Block) -> u8 {
    match (b.kind, b.tool_side) {
        (ElementKind::Angular, true) => 4,
        (ElementKind::Angular, false) => 3,
        (ElementKind::Straightness, _) => 2,
        (ElementKind::Squareness, _) => 1,
        (ElementKind::Positioning, _) => 0,
    }
}

fn sorted_desc(v: &DVector<f64>) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&i, &j| v[j].total_cmp(&v[i]));
    idx
}

/// Scales, factorises and analyses a design. Elements that reach no reading (all-zero columns)
/// are dropped first; the rest needs more readings than columns, else `Err((readings, columns))`.
pub fn analyse(
    a: &DMatrix<f64>,
    y: &DVector<f64>,
    layout: &Layout,
) -> Result<Analysis, (usize, usize)> {
    analyse_with(a, y, layout, None)
}

/// As [`analyse`]; with `known`, the elements to drop are taken from a previous analysis of the
/// same columns (row weights do not change a rank) and no rank search is done: only the kept
/// design is factorised, by Householder QR like every other design here (never through the Gram
/// matrix AᵀA, whose condition number is the square of the design's); its singular values are
/// then left empty.
pub fn analyse_with(
    a: &DMatrix<f64>,
    y: &DVector<f64>,
    layout: &Layout,
    known: Option<&[Dropped]>,
) -> Result<Analysis, (usize, usize)> {
    let n = a.ncols();
    let zero_col = |c: usize| a.column(c).iter().all(|v| *v == 0.0);
    let mut dropped = Vec::new();
    for b in &layout.blocks {
        if !b.cols().is_empty() && b.cols().all(zero_col) {
            dropped.push(Dropped {
                element: b.element,
                confounded_with: vec![],
                with_alignment: false,
                zero_sensitivity: true,
            });
        }
    }
    if let Some(known) = known {
        // an element known to reach no reading stays dropped even where other rows (the
        // penalty rows of a smoothing spline, which are no readings) make its columns non-zero
        let known: Vec<Dropped> = known
            .iter()
            .filter(|d| !dropped.iter().any(|x| x.element == d.element))
            .cloned()
            .collect();
        dropped.extend(known);
    }
    let is_dropped = |c: usize| {
        dropped.iter().any(|d| {
            layout
                .block(&d.element)
                .is_some_and(|b| b.cols().contains(&c))
        })
    };
    // the columns that enter the factorisation, by original index
    let cols: Vec<usize> = (0..n).filter(|&c| !is_dropped(c)).collect();
    if a.nrows() <= cols.len() {
        return Err((a.nrows(), cols.len()));
    }
    let scale = DVector::from_iterator(
        n,
        a.column_iter().map(|c| {
            let s = c.norm();
            if s > 0.0 {
                s
            } else {
                1.0
            }
        }),
    );
    let mut scaled = a.select_columns(cols.iter());
    for (j, mut c) in scaled.column_iter_mut().enumerate() {
        c /= scale[cols[j]];
    }
    let k = cols.len();
    let qr = scaled.qr();
    let mut qty = y.clone();
    qr.q_tr_mul(&mut qty);
    let qty = qty.rows(0, k).into_owned();
    let r = qr.r();
    if known.is_some() {
        return Ok(Analysis {
            scale,
            r: r.clone(),
            qty,
            singular_values: vec![],
            rank: k,
            active: cols,
            dropped,
            kept_r: r,
            kept_singular_values: vec![],
        });
    }

    // one SVD of R gives the singular values and the null space N of the whole design
    let svd = SVD::new(r.clone(), false, true);
    let order = sorted_desc(&svd.singular_values);
    let smax = svd.singular_values[order[0]];
    let tol = RANK_TOL * smax;
    let rank = order
        .iter()
        .filter(|&&i| svd.singular_values[i] > tol)
        .count();
    // zero columns of never-reached elements are zero singular values of the full design
    let mut singular_values: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
    singular_values.resize(n, 0.0);
    let v_t = svd.v_t.as_ref().expect("V requested");
    let null: Vec<usize> = order[rank..].to_vec();
    let mut nmat = DMatrix::from_fn(null.len(), k, |i, j| v_t[(null[i], j)]);
    // `active` holds positions into `cols`; dropping a block B leaves the null space
    // {v ∈ N : v_B = 0}, computed from N without decomposing A again
    let mut active: Vec<usize> = (0..k).collect();
    while nmat.nrows() > 0 {
        let original: Vec<usize> = active.iter().map(|&p| cols[p]).collect();
        let Some(d) = choose_drop(&nmat, &original, layout) else {
            break;
        };
        let bc = layout
            .block(&d.element)
            .expect("dropped element has a block")
            .cols();
        let in_b: Vec<usize> = (0..active.len())
            .filter(|&j| bc.contains(&cols[active[j]]))
            .collect();
        let keep: Vec<usize> = (0..active.len())
            .filter(|&j| !bc.contains(&cols[active[j]]))
            .collect();
        // combinations c with N_Bᵀ c = 0: the null space of N_Bᵀ (small SVD)
        let nb = nmat.select_columns(in_b.iter());
        let inner = SVD::new(nb.clone() * nb.transpose(), true, false);
        let u = inner.u.as_ref().expect("U requested");
        let comb: Vec<usize> = (0..inner.singular_values.len())
            .filter(|&i| inner.singular_values[i] <= 1e-12)
            .collect();
        let rest = nmat.select_columns(keep.iter());
        let mut next = DMatrix::zeros(comb.len(), keep.len());
        for (r_i, &i) in comb.iter().enumerate() {
            let row = u.column(i).transpose() * &rest;
            next.row_mut(r_i).copy_from(&row);
        }
        // re-orthonormalise the surviving null vectors (rows)
        nmat = if next.nrows() > 0 {
            let q = next.transpose().qr().q();
            q.transpose()
        } else {
            next
        };
        active = keep.iter().map(|&j| active[j]).collect();
        dropped.push(d);
    }
    // Qᵀy of the kept design: the kept columns of R are re-triangularised by a small QR
    let qr2 = r.select_columns(active.iter()).qr();
    let mut qty2 = qty.clone();
    qr2.q_tr_mul(&mut qty2);
    let kept_r = qr2.r();
    let kept_singular_values = {
        let mut sv: Vec<f64> = kept_r.singular_values().iter().copied().collect();
        sv.sort_by(|a, b| b.total_cmp(a));
        sv
    };
    Ok(Analysis {
        scale,
        r,
        qty: qty2.rows(0, active.len()).into_owned(),
        singular_values,
        rank,
        active: active.iter().map(|&p| cols[p]).collect(),
        dropped,
        kept_r,
        kept_singular_values,
    })
}

/// Positions (within `active`) of a block's columns.
fn positions(active: &[usize], b: &Block) -> Vec<usize> {
    let cols = b.cols();
    active
        .iter()
        .enumerate()
        .filter(|(_, c)| cols.contains(c))
        .map(|(i, _)| i)
        .collect()
}

/// Applies the drop rule to a null space `nmat` (rows: orthonormal null vectors over `active`).
fn choose_drop(nmat: &DMatrix<f64>, active: &[usize], layout: &Layout) -> Option<Dropped> {
    let weight = |pos: &[usize]| -> f64 {
        pos.iter()
            .map(|&j| nmat.column(j).norm_squared())
            .sum::<f64>()
    };
    let mut best: Option<(&Block, Vec<usize>, f64)> = None;
    for b in &layout.blocks {
        let pos = positions(active, b);
        if pos.is_empty() {
            continue;
        }
        let w = weight(&pos);
        if w <= TOUCH_TOL {
            continue;
        }
        let better = match &best {
            None => true,
            Some((bb, _, bw)) => {
                let (p, bp) = (drop_priority(b), drop_priority(bb));
                p > bp || (p == bp && w > *bw * (1.0 + 1e-9))
            }
        };
        if better {
            best = Some((b, pos, w));
        }
    }
    let (b, pos, _) = best?;
    // null directions concentrated on b: eigenvectors of N_B N_Bᵀ with non-zero eigenvalue
    let nb = nmat.select_columns(pos.iter());
    let eig = SymmetricEigen::new(&nb * nb.transpose());
    let mut partners: Vec<ErrorElement> = Vec::new();
    let mut with_alignment = false;
    for (k, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda <= TOUCH_TOL {
            continue;
        }
        let v = nmat.transpose() * eig.eigenvectors.column(k);
        for other in &layout.blocks {
            if other.element == b.element || partners.contains(&other.element) {
                continue;
            }
            let p = positions(active, other);
            if p.iter().map(|&j| v[j] * v[j]).sum::<f64>() > TOUCH_TOL {
                partners.push(other.element);
            }
        }
        for &(_, col) in &layout.slopes {
            if let Some(j) = active.iter().position(|&c| c == col) {
                if v[j] * v[j] > TOUCH_TOL {
                    with_alignment = true;
                }
            }
        }
    }
    partners.sort();
    Some(Dropped {
        element: b.element,
        confounded_with: partners,
        with_alignment,
        zero_sensitivity: false,
    })
}
