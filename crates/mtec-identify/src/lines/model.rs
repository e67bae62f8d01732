//! The linear observation model of a line design: parameters (polynomial coefficients of every
//! error function, squareness constants, straightness alignment slopes) and the design matrix
//! built from the first-order kinematics.
//!
//! Parameterisation (the conventions of `mtec-sim`'s truth, written down in the crate docs):
//! with x = (2q − q_min − q_max)/L the axis position mapped to [−1, 1] over its travel of
//! length L, and φ_p(x) = P_p(x) − (−1)^p the Legendre polynomial P_p shifted to be zero at the
//! origin (see [`super::basis`]),
//! - positioning and angular error motions: f(q) = Σ_{p=1..N} c_p φ_p(x) (zero at the origin);
//!   a positioning error may add the pitch pair c_s ψ_s + c_c ψ_c of its screw lead;
//! - straightness: f(q) = Σ_{p=2..N} c_p φ_p(x): zero at the origin and with a zero
//!   least-squares slope over the travel (P_p ⟂ x for p ≥ 2), i.e. measured from its
//!   least-squares reference line, as ISO 230-1 defines straightness. The slope of a
//!   reference line is a squareness (the angle between two reference lines), or for X, which
//!   defines the frame, nothing.
//!
//!   Why the reference line and not "no slope at the origin" (the first convention used here):
//!   a straightness channel's alignment slope hides every linear trend, so with a zero slope
//!   at the origin the trend of a straightness *over the travel* is extrapolated from its
//!   fitted curvature. A curvature error of 0.1 µm (noise, or a screw-lead ripple sampled at
//!   29 mm) then tilts the whole function by about 1 µm at the far end, the diagonal turns that
//!   into a squareness error, and the pair rotates the predicted volume: on `vmc-9line` the
//!   volumetric RMS fell from 0.84 to 0.45 µm (median of 12 seeds, one run) with this basis.
//! - squareness `EC0Y`, `EB0Z`, `EA0Z`: a constant;
//! - one alignment slope a (µrad) per straightness channel: reading += a·d·1e-3, d the distance
//!   (mm) from the channel's reference point.
//!
//! A reading of channel u at point k (reference point 0) is modelled as
//!   r_k = u · (J(q_k)·f(q_k) − J(q_0)·f(q_0)) + a·d_k·1e-3 + noise,
//! with J the first-order Jacobian of [`VolumetricModel::first_order_jacobian`] (µm per µm or
//! µrad of each element): one row of the design matrix per reading.

use super::basis;
use super::data::{dot, ChannelKind, LineData};
use super::spline::Spline;
use mtec_model::{three_axis_elements, Axis, ErrorElement, Machine, VolumetricModel};
use nalgebra::{DMatrix, DVector};

/// The role of an element in the parameterisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ElementKind {
    Positioning,
    Straightness,
    Angular,
    Squareness,
}

/// One element's columns of the design matrix.
#[derive(Debug, Clone)]
pub struct Block {
    pub element: ErrorElement,
    pub kind: ElementKind,
    /// Index of the element's axis in the pose vector.
    pub pose_index: usize,
    /// Travel [min, max] of the axis.
    pub travel: [f64; 2],
    /// Legendre orders p of the columns, φ_p of [`basis`] (0 for a squareness constant).
    pub orders: Vec<i32>,
    /// Cubic B-spline columns with knots from the data, instead of Legendre orders (`orders`
    /// is then empty), see [`super::spline`].
    pub spline: Option<Spline>,
    /// Smoothing penalty λ of a smoothing spline (`spline` then holds its knots), see
    /// [`penalty_rows`].
    pub penalty: Option<f64>,
    /// Screw lead (mm) of a positioning element with a pitch-error pair (two more columns).
    pub period_mm: Option<f64>,
    /// Columns `first_col .. first_col + n_cols()`.
    pub first_col: usize,
    /// True if the element's axis carries the tool (angular errors then act through the tool offset only).
    pub tool_side: bool,
}

impl Block {
    /// The axis position mapped to x ∈ [−1, 1] over the travel.
    pub fn x(&self, q: f64) -> f64 {
        (2.0 * q - self.travel[0] - self.travel[1]) / (self.travel[1] - self.travel[0])
    }
    /// Basis values at axis position q (µm or µrad of the element per unit coefficient):
    /// φ_p(x) for each order, then the pitch pair.
    pub fn basis(&self, q_axis: f64) -> impl Iterator<Item = f64> + '_ {
        let x = self.x(q_axis);
        let n = self.orders.iter().copied().max().unwrap_or(0).max(0) as usize;
        let p_all = basis::legendre_all(n, x);
        let pitch = self
            .period_mm
            .map(|per| basis::pitch_pair(q_axis - self.travel[0], per));
        let constant = self.kind == ElementKind::Squareness;
        self.orders
            .iter()
            .map(move |&p| {
                if constant {
                    1.0
                } else {
                    // φ_p = P_p(x) − (−1)^p
                    p_all[p as usize] - basis::at_minus_one(p as usize)
                }
            })
            .chain(self.spline.iter().flat_map(move |s| s.columns(q_axis)))
            .chain(pitch.into_iter().flatten())
    }
    /// The polynomial part of the coefficients `theta[cols]` as (power of s, coefficient)
    /// terms, s = (q − q_min)/L (the pitch pair, if any, is not included).
    pub fn power_terms(&self, coeffs: &[f64]) -> Vec<(i32, f64)> {
        if self.kind == ElementKind::Squareness {
            return vec![(0, coeffs[0])];
        }
        basis::legendre_to_power_terms(&self.orders, &coeffs[..self.orders.len()])
    }
    /// Number of columns.
    pub fn n_cols(&self) -> usize {
        self.orders.len()
            + self.spline.as_ref().map_or(0, Spline::n_cols)
            + if self.period_mm.is_some() { 2 } else { 0 }
    }
    /// The column range.
    pub fn cols(&self) -> std::ops::Range<usize> {
        self.first_col..self.first_col + self.n_cols()
    }
    /// The function's basis.
    pub fn basis_choice(&self) -> Basis {
        match (&self.spline, self.penalty) {
            (Some(_), Some(l)) => Basis::Smooth((2.0 * l.log10()).round() as i32),
            (Some(s), None) => Basis::Spline(s.interior.len()),
            (None, _) => Basis::Legendre(self.degree()),
        }
    }
    /// The highest Legendre order (the polynomial degree; 3 for a spline, 0 for a constant).
    pub fn degree(&self) -> usize {
        if self.spline.is_some() {
            return 3;
        }
        self.orders.iter().copied().max().unwrap_or(0).max(0) as usize
    }
}

/// The basis of an error function: Legendre polynomials of a degree, or cubic B-splines with
/// a number of interior knots placed at the quantiles of the measured positions. Written as
/// the degree (a number, as before splines existed) or as `"spline:K"`; a smoothing spline
/// (cubic B-splines with [`SMOOTH_KNOTS`] interior knots and the penalty λ = 10^e on the
/// curvature, [`penalty_rows`]) as `"smooth:λ"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    Legendre(usize),
    Spline(usize),
    /// The penalty λ = 10^(e/2) in half decades e.
    Smooth(i32),
}

/// Interior knots of a smoothing spline (at most; fewer when the measured positions of the axis
/// cannot carry them): about one per measured step of a 21-point line, so that the penalty, not
/// the knots, decides how far the function bends (Eilers & Marx 1996: many knots, then a
/// penalty).
pub const SMOOTH_KNOTS: usize = 16;

impl serde::Serialize for Basis {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            Basis::Legendre(d) => s.serialize_u64(d as u64),
            Basis::Spline(k) => s.serialize_str(&format!("spline:{k}")),
            Basis::Smooth(_) => {
                s.serialize_str(&format!("smooth:{:.1e}", self.penalty().unwrap_or(0.0)))
            }
        }
    }
}

impl Basis {
    /// Number of coefficients (of a positioning or angular function): the model's size.
    pub fn size(&self) -> usize {
        match *self {
            Basis::Legendre(d) => d,
            Basis::Spline(k) => k + 3,
            // for parsimony only: a smoothing spline ranks above every polynomial and spline,
            // a smaller penalty above a larger one
            Basis::Smooth(e) => (100 - e) as usize,
        }
    }
    /// The smoothing penalty λ of a smoothing spline.
    pub fn penalty(&self) -> Option<f64> {
        match *self {
            Basis::Smooth(e) => Some(10f64.powf(e as f64 / 2.0)),
            _ => None,
        }
    }
}

impl std::fmt::Display for Basis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Basis::Legendre(d) => write!(f, "{d}"),
            Basis::Spline(k) => write!(f, "cubic spline with {k} interior knots"),
            Basis::Smooth(_) => write!(
                f,
                "smoothing spline, penalty {:.1e}",
                self.penalty().unwrap_or(0.0)
            ),
        }
    }
}

/// Lowest and highest polynomial degree of an error function.
pub const MIN_DEGREE: usize = 2;
pub const MAX_DEGREE: usize = 12;

/// Parameter layout: element blocks, then one alignment slope per straightness channel.
#[derive(Debug, Clone)]
pub struct Layout {
    pub blocks: Vec<Block>,
    /// (channel index, column) of each alignment slope.
    pub slopes: Vec<(usize, usize)>,
    pub n_cols: usize,
}

/// Why a design cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("line identification needs a machine with exactly the linear axes X, Y, Z (this one has {0})")]
    NotThreeAxis(String),
    #[error("polynomial degree must be between 2 and 12 (got {0})")]
    Degree(usize),
    #[error("a cubic spline with {0} interior knots has a function with no measured position of {1}'s axis in its support")]
    Knots(usize, String),
    #[error("line `{line}` point {point} ({x}, {y}, {z}) is outside the travel of axis {axis} [{lo}, {hi}]")]
    OutsideTravel {
        line: String,
        point: usize,
        x: f64,
        y: f64,
        z: f64,
        axis: char,
        lo: f64,
        hi: f64,
    },
}

/// The classification of a three-axis element.
pub fn element_kind(e: &ErrorElement) -> ElementKind {
    if e.location {
        ElementKind::Squareness
    } else if e.is_angular() {
        ElementKind::Angular
    } else if e.direction == e.axis {
        ElementKind::Positioning
    } else {
        ElementKind::Straightness
    }
}

impl Layout {
    /// The layout for a machine, one polynomial degree for every element and the channels of
    /// a data set; no pitch-error pair.
    pub fn new(machine: &Machine, degree: usize, data: &LineData) -> Result<Layout, ModelError> {
        Layout::with_degrees(machine, data, &|_| degree, false)
    }

    /// The layout with a degree per element (`degree_of`) and, with `pitch`, a pitch-error pair
    /// on the positioning element of every axis whose machine file gives `period_mm`.
    pub fn with_degrees(
        machine: &Machine,
        data: &LineData,
        degree_of: &dyn Fn(&ErrorElement) -> usize,
        pitch: bool,
    ) -> Result<Layout, ModelError> {
        Layout::with_bases(machine, data, &|e| Basis::Legendre(degree_of(e)), pitch)
    }

    /// The layout with a basis per element (`basis_of`), pitch pairs as [`Layout::with_degrees`].
    pub fn with_bases(
        machine: &Machine,
        data: &LineData,
        basis_of: &dyn Fn(&ErrorElement) -> Basis,
        pitch: bool,
    ) -> Result<Layout, ModelError> {
        check_machine(machine)?;
        let positions = super::data::measured_positions(data);
        let mut blocks = Vec::new();
        let mut col = 0;
        for element in three_axis_elements() {
            let kind = element_kind(&element);
            let (degree, spline) = match (kind, basis_of(&element)) {
                (ElementKind::Squareness, _) => (0, None),
                (_, Basis::Legendre(d)) => (d, None),
                (_, Basis::Spline(k)) => {
                    let s = Spline::new(
                        &positions[element.axis.index()],
                        machine.travel(element.axis),
                        k,
                        kind == ElementKind::Straightness,
                    )
                    .ok_or(ModelError::Knots(k, element.name()))?;
                    (0, Some(s))
                }
                (_, Basis::Smooth(_)) => {
                    // as many knots as the axis' measured positions carry, up to SMOOTH_KNOTS
                    let s = (1..=SMOOTH_KNOTS)
                        .rev()
                        .find_map(|k| {
                            Spline::new(
                                &positions[element.axis.index()],
                                machine.travel(element.axis),
                                k,
                                kind == ElementKind::Straightness,
                            )
                        })
                        .ok_or(ModelError::Knots(1, element.name()))?;
                    (0, Some(s))
                }
            };
            let penalty = match kind {
                ElementKind::Squareness => None,
                _ => basis_of(&element).penalty(),
            };
            if kind != ElementKind::Squareness
                && spline.is_none()
                && !(MIN_DEGREE..=MAX_DEGREE).contains(&degree)
            {
                return Err(ModelError::Degree(degree));
            }
            let orders: Vec<i32> = match kind {
                _ if spline.is_some() => Vec::new(),
                ElementKind::Squareness => vec![0],
                ElementKind::Straightness => (2..=degree as i32).collect(),
                _ => (1..=degree as i32).collect(),
            };
            let period_mm = match kind {
                ElementKind::Positioning if pitch => machine.specs[&element.axis].period_mm,
                _ => None,
            };
            let block = Block {
                element,
                kind,
                pose_index: machine.axis_index(element.axis).unwrap_or(0),
                travel: machine.travel(element.axis),
                orders,
                spline,
                penalty,
                period_mm,
                first_col: col,
                tool_side: machine.chain.tool_side.contains(&element.axis),
            };
            col += block.n_cols();
            blocks.push(block);
        }
        let mut slopes = Vec::new();
        for (i, c) in data.channels.iter().enumerate() {
            if c.kind == ChannelKind::Straightness {
                slopes.push((i, col));
                col += 1;
            }
        }
        Ok(Layout {
            blocks,
            slopes,
            n_cols: col,
        })
    }

    /// The block of an element.
    pub fn block(&self, e: &ErrorElement) -> Option<&Block> {
        self.blocks.iter().find(|b| b.element == *e)
    }
}

/// Refuses machines that are not X, Y, Z linear.
pub fn check_machine(machine: &Machine) -> Result<(), ModelError> {
    if machine.axes != [Axis::X, Axis::Y, Axis::Z] {
        return Err(ModelError::NotThreeAxis(
            machine.axes.iter().map(|a| a.letter()).collect(),
        ));
    }
    Ok(())
}

/// Checks every commanded point lies within the travels (the error functions are defined there only).
pub fn check_travels(machine: &Machine, data: &LineData) -> Result<(), (usize, usize, ModelError)> {
    for (ci, c) in data.channels.iter().enumerate() {
        for (k, p) in c.points_mm.iter().enumerate() {
            for a in [Axis::X, Axis::Y, Axis::Z] {
                let [lo, hi] = machine.travel(a);
                let v = p[a.index()];
                let tol = 1e-9 * (hi - lo);
                if v < lo - tol || v > hi + tol {
                    return Err((
                        ci,
                        k,
                        ModelError::OutsideTravel {
                            line: c.label(),
                            point: k,
                            x: p[0],
                            y: p[1],
                            z: p[2],
                            axis: a.letter(),
                            lo,
                            hi,
                        },
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The Jacobian at a pose as one [Ex, Ey, Ez] row per block (same order as `layout.blocks`).
fn jacobian_by_block(vm: &VolumetricModel, layout: &Layout, q: &[f64]) -> Vec<[f64; 3]> {
    let jac = vm.first_order_jacobian(q);
    layout
        .blocks
        .iter()
        .map(|b| {
            jac.iter()
                .find(|(e, _)| *e == b.element)
                .map_or([0.0; 3], |(_, j)| *j)
        })
        .collect()
}

/// The first-order Jacobian of an X, Y, Z machine as an affine function of the pose.
///
/// With no rotary axis the ideal chain is translations only, so every lever arm, and with it
/// every column of the Jacobian (δ, ε × r, q·(ε₀ × u)), is affine in q: J(q) = J(0) + Σ_i q_i·D_i.
/// Four evaluations of [`VolumetricModel::first_order_jacobian`] give it exactly (to rounding);
/// `tests/lines_reference.rs` checks it against the direct evaluation.
pub struct AffineJacobian {
    j0: Vec<[f64; 3]>,
    d: [Vec<[f64; 3]>; 3],
}

impl AffineJacobian {
    /// Samples the Jacobian at the origin and 100 mm along each axis.
    pub fn new(machine: &Machine, layout: &Layout) -> AffineJacobian {
        let vm = VolumetricModel::new(machine, &mtec_model::ErrorSet::new("design"));
        let j0 = jacobian_by_block(&vm, layout, &[0.0; 3]);
        let d = [0, 1, 2].map(|i| {
            let mut q = [0.0; 3];
            q[i] = 100.0;
            jacobian_by_block(&vm, layout, &q)
                .iter()
                .zip(&j0)
                .map(|(a, b)| [0, 1, 2].map(|k| (a[k] - b[k]) / 100.0))
                .collect()
        });
        AffineJacobian { j0, d }
    }

    /// One [Ex, Ey, Ez] row per block at pose q.
    pub fn at(&self, q: &[f64; 3]) -> Vec<[f64; 3]> {
        (0..self.j0.len())
            .map(|b| {
                [0, 1, 2].map(|k| {
                    self.j0[b][k]
                        + q[0] * self.d[0][b][k]
                        + q[1] * self.d[1][b][k]
                        + q[2] * self.d[2][b][k]
                })
            })
            .collect()
    }
}

/// The Jacobian evaluated directly (for checking [`AffineJacobian`]).
pub fn direct_jacobian(machine: &Machine, layout: &Layout, q: &[f64; 3]) -> Vec<[f64; 3]> {
    let vm = VolumetricModel::new(machine, &mtec_model::ErrorSet::new("design"));
    jacobian_by_block(&vm, layout, q)
}

/// The design matrix (readings × parameters) and the reading vector.
pub fn design_matrix(
    machine: &Machine,
    layout: &Layout,
    data: &LineData,
) -> (DMatrix<f64>, DVector<f64>) {
    let jac = AffineJacobian::new(machine, layout);
    let m = data.n_readings();
    let mut a = DMatrix::<f64>::zeros(m, layout.n_cols);
    let mut y = DVector::<f64>::zeros(m);
    let mut row = 0;
    // Jacobians of the points of the previous channel: channels of one line share points.
    let mut cache: (Vec<[f64; 3]>, Vec<Vec<[f64; 3]>>) = (Vec::new(), Vec::new());
    for (ci, c) in data.channels.iter().enumerate() {
        if cache.0 != c.points_mm {
            cache.1 = c.points_mm.iter().map(|p| jac.at(p)).collect();
            cache.0 = c.points_mm.clone();
        }
        let jacs = &cache.1;
        let q0 = c.points_mm[0];
        let slope_col = layout.slopes.iter().find(|(i, _)| *i == ci).map(|s| s.1);
        for (k, qk) in c.points_mm.iter().enumerate() {
            for (bi, b) in layout.blocks.iter().enumerate() {
                // u·J_e(q) is the reading per unit element value at pose q
                let gk = dot(c.u, jacs[k][bi]);
                let g0 = dot(c.u, jacs[0][bi]);
                if gk == 0.0 && g0 == 0.0 {
                    continue;
                }
                let xk = qk[b.pose_index];
                let x0 = q0[b.pose_index];
                for (j, (bk, b0)) in b.basis(xk).zip(b.basis(x0)).enumerate() {
                    a[(row, b.first_col + j)] = gk * bk - g0 * b0;
                }
            }
            if let Some(sc) = slope_col {
                // alignment slope in µrad: µm per mm of travel × 1e3
                a[(row, sc)] = c.distance_mm(k) * 1e-3;
            }
            y[row] = c.readings_um[k];
            row += 1;
        }
    }
    (a, y)
}

/// The roughness penalty of the smoothing splines as rows to append to the design: for a block
/// with penalty λ, rows R with RᵀR = λ·Ω, Ω_jk = ∫_{−1}^{1} φ_j''(x)·φ_k''(x) dx (x the position
/// mapped to [−1, 1], φ_j the block's spline columns; the pitch pair is not penalised), so that
/// least squares on [A; R] minimises ‖y − Aθ‖² + Σ λ ∫ f''(x)² dx: the penalised regression
/// spline of O'Sullivan (1986, eq. 2.2), the P-spline idea of Eilers & Marx (1996) with the
/// integral instead of coefficient differences (the columns are not plain B-splines: B_0 and,
/// for a straightness, the reference line are taken out). φ'' is linear on each knot interval,
/// so two Gauss points per interval integrate Ω exactly; the quadrature rows are reduced to
/// their R factor (Householder QR). `row_scale` multiplies every row (the row weights of a
/// weighted fit). None if no block is penalised.
pub fn penalty_rows(layout: &Layout, row_scale: f64) -> Option<DMatrix<f64>> {
    let mut blocks: Vec<DMatrix<f64>> = Vec::new();
    for b in &layout.blocks {
        let (Some(lambda), Some(spline)) = (b.penalty, &b.spline) else {
            continue;
        };
        let n = spline.n_cols();
        let [lo, hi] = b.travel;
        let half_len = (hi - lo) / 2.0;
        let mut edges = vec![lo];
        edges.extend(&spline.interior);
        edges.push(hi);
        // d²f/dx² = (L/2)² d²f/dq², by a central difference (exact on a cubic piece)
        let h = 1e-2;
        let second = |q: f64| -> Vec<f64> {
            let (m, c, p): (Vec<f64>, Vec<f64>, Vec<f64>) = (
                b.basis(q - h).take(n).collect(),
                b.basis(q).take(n).collect(),
                b.basis(q + h).take(n).collect(),
            );
            (0..n)
                .map(|j| (m[j] - 2.0 * c[j] + p[j]) / (h * h) * half_len * half_len)
                .collect()
        };
        let g = 1.0 / 3f64.sqrt();
        let mut rows = Vec::new();
        for w in edges.windows(2) {
            let (mid, hw) = ((w[0] + w[1]) / 2.0, (w[1] - w[0]) / 2.0);
            // Gauss–Legendre, 2 points: weight hw (in q) · 1/half_len (dx/dq) each
            let weight = (lambda * hw / half_len).sqrt();
            for t in [-g, g] {
                rows.push(
                    second(mid + t * hw)
                        .into_iter()
                        .map(|v| v * weight)
                        .collect::<Vec<_>>(),
                );
            }
        }
        let quad = DMatrix::from_fn(rows.len(), n, |i, j| rows[i][j]);
        let r = quad.qr().r();
        let mut full = DMatrix::zeros(r.nrows(), layout.n_cols);
        full.view_mut((0, b.first_col), (r.nrows(), n))
            .copy_from(&(r * row_scale));
        blocks.push(full);
    }
    if blocks.is_empty() {
        return None;
    }
    let total: usize = blocks.iter().map(|m| m.nrows()).sum();
    let mut out = DMatrix::zeros(total, layout.n_cols);
    let mut at = 0;
    for m in blocks {
        out.rows_mut(at, m.nrows()).copy_from(&m);
        at += m.nrows();
    }
    Some(out)
}

/// The design with the penalty rows of [`penalty_rows`] appended (readings 0 for them), or the
/// design as it is when nothing is penalised.
pub fn penalised(
    a: DMatrix<f64>,
    y: DVector<f64>,
    layout: &Layout,
    row_scale: f64,
) -> (DMatrix<f64>, DVector<f64>) {
    let Some(p) = penalty_rows(layout, row_scale) else {
        return (a, y);
    };
    let m = a.nrows();
    let mut aa = a.resize_vertically(m + p.nrows(), 0.0);
    aa.rows_mut(m, p.nrows()).copy_from(&p);
    (aa, y.resize_vertically(m + p.nrows(), 0.0))
}
