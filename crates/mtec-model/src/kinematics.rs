//! Forward kinematics of a machine with error motions, and the volumetric error of the tool tip
//! relative to the workpiece, in two independent formalisms (HTM multi-body products and
//! product of exponentials), each exact and first-order.
//!
//! # Conventions (decisions written down)
//! - **Commanded positions** follow ISO 841: a linear axis command `q` moves the tool by `+q`
//!   relative to the workpiece. A tool-side carriage therefore moves `+q·u`, a workpiece-side
//!   carriage (a table) moves `−q·u`. A rotary command `θ` turns the component the axis carries
//!   by `+θ` about its nominal direction (right hand), on either side (the ballbar literature's
//!   table rotation).
//! - **Error elements are error motions of the moving component** relative to the component it
//!   rides on, along/about the positive machine axes (ISO 230-1 component errors; the
//!   literature's δx(C) of a rotary table is `EXC`). On a workpiece-side axis the tool therefore
//!   sees the opposite: a positive `EXX` of a table-carrying X moves the table +X, so the tool
//!   moves −X relative to the workpiece.
//! - **Where an angular error acts**: about the carriage reference point `centre_mm` of the axis
//!   (default the machine zero), carried along with the ideal motion.
//! - **Order of ideal and error motion**: `error_frame = "moving"` (default) multiplies the error
//!   after the ideal motion, T = M(q)·E(q): the error is expressed in the moving frame, where a
//!   laser or level on the carriage measures it. `"reference"` multiplies it before, T = E(q)·M(q):
//!   the error expressed in the parent frame. For a linear axis the two differ exactly by the
//!   lever arm of the ideal translation: E_ref(δ, ε)·M(q) = M(q)·E_mov(δ + (R(ε) − I)·q·u, ε)
//!   (to first order δ + ε × q·u), which the tests check.
//! - **Squareness** (`EC0Y`, `EB0Z`, `EA0Z`) rotates the direction of the axis' ideal motion
//!   only (X is the reference): Y moves along R(EC0Y about Z)·ŷ. It does not tilt the axes it
//!   carries. First order: a position-dependent translation q·(ε₀ × u); `EC0Y` > 0 gives
//!   Ex = −EC0Y·y for a tool-side Y.
//! - **Rotary location errors** (`EX0C`, `EY0C`, `EA0C`, `EB0C`) displace and tilt the axis line
//!   before the rotation: T = Trans(c)·L₀·Rot(θ)·E(θ)·Trans(−c).
//! - The exact error transform is E = Trans(δ)·Rz(εz)·Ry(εy)·Rx(εx); first order R ≈ I + [ε]×.
//!
//! The tool tip relative to the workpiece reference point:
//!   P = Trans(−o_w) · A_w1⁻¹ ··· A_wn⁻¹ · A_t1 ··· A_tm · t
//! with A the physical transform of each axis from its parent to its carriage, w1 the axis that
//! carries the workpiece, t the tool offset. The volumetric error is P_actual − P_ideal.

use crate::element::{Axis, ErrorElement};
use crate::errors::ErrorSet;
use crate::function::{ErrorFunction, Temperatures};
use crate::htm::{rotation_vector, Htm};
use crate::machine::{ErrorFrame, Machine};
use crate::poe::{adjoint, exp6, Twist};
use nalgebra::{Matrix3, Vector3};

/// Which formalism computes the chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Formalism {
    /// Homogeneous transformation matrices multiplied body by body.
    Htm,
    /// Product of exponentials of space-frame twists (screw theory).
    Poe,
}

/// Exact rigid-body transforms, or the linearised (small-error) model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    Exact,
    FirstOrder,
}

/// The volumetric error of the tool tip relative to the workpiece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Volumetric {
    /// [Ex, Ey, Ez] in µm.
    pub position_um: [f64; 3],
    /// Orientation error of the tool relative to the workpiece as a rotation vector [about X, Y, Z], µrad.
    pub orientation_urad: [f64; 3],
}

/// One factor of the chain product.
#[derive(Debug, Clone, Copy)]
enum Factor {
    /// A fixed translation (carriage centres, tool offset, workpiece origin).
    Shift(Vector3<f64>),
    /// Ideal prismatic motion along unit `u` by `amount` mm.
    Prismatic(Vector3<f64>, f64),
    /// Ideal rotation about unit `u` through the local origin by `angle` rad.
    Revolute(Vector3<f64>, f64),
    /// Error motion of the axis at chain slot `slot` (inverse on the workpiece side).
    Motion { slot: usize, inverse: bool },
    /// Location error of the rotary axis at `slot`.
    Location { slot: usize, inverse: bool },
    /// Squareness of the linear axis at `slot`: translation `amount`·(R(ε₀)·u − u).
    Squareness {
        slot: usize,
        u: Vector3<f64>,
        amount: f64,
        inverse: bool,
    },
}

/// Per-slot error values at a pose, in model units (mm, rad).
#[derive(Debug, Clone, Copy, Default)]
struct SlotValues {
    motion_delta: Vector3<f64>,
    motion_eps: Vector3<f64>,
    loc_delta: Vector3<f64>,
    loc_eps: Vector3<f64>,
}

/// One axis of the chain with its error functions resolved (no map look-ups per evaluation).
#[derive(Debug, Clone)]
struct Slot {
    axis: Axis,
    pose_index: usize,
    workpiece_side: bool,
    centre: Vector3<f64>,
    motion: [Option<ErrorFunction>; 6],
    location: [Option<ErrorFunction>; 6],
}

/// At most six axes in a chain (X Y Z A B C each once).
const MAX_SLOTS: usize = 6;
/// Two shifts + at most four factors per axis, plus the workpiece origin and the tool offset.
const MAX_FACTORS: usize = 2 + 6 * MAX_SLOTS;

/// A machine with an error set, ready for fast repeated evaluation.
#[derive(Debug, Clone)]
pub struct VolumetricModel {
    machine: Machine,
    /// No rotary axis: the ideal chain is translations only (fast first-order path).
    linear_only: bool,
    /// The chain's factors at q = 1 with the pose index that scales each (usize::MAX: fixed).
    template: Vec<(Factor, usize)>,
    /// Slots in product order: workpiece side from W toward F, then tool side from F toward T.
    slots: Vec<Slot>,
}

impl VolumetricModel {
    /// Compiles a machine and an error set (elements of axes not in the chain are ignored).
    pub fn new(machine: &Machine, errors: &ErrorSet) -> VolumetricModel {
        let mut slots = Vec::new();
        let sides = machine
            .chain
            .workpiece_side
            .iter()
            .map(|a| (*a, true))
            .chain(machine.chain.tool_side.iter().map(|a| (*a, false)));
        for (axis, wp) in sides {
            let c = machine.specs[&axis].centre_mm;
            let f = |loc: bool, d: Axis| {
                errors
                    .get(&ErrorElement {
                        direction: d,
                        axis,
                        location: loc,
                    })
                    .cloned()
            };
            slots.push(Slot {
                axis,
                pose_index: machine.axis_index(axis).expect("chain axes are pose axes"),
                workpiece_side: wp,
                centre: Vector3::new(c[0], c[1], c[2]),
                motion: Axis::ALL.map(|d| f(false, d)),
                location: Axis::ALL.map(|d| f(true, d)),
            });
        }
        let linear_only = slots.iter().all(|s| !s.axis.is_rotary());
        let mut vm = VolumetricModel {
            machine: machine.clone(),
            linear_only,
            slots,
            template: vec![],
        };
        // every pose-dependent amount is linear in its axis position with no offset, so the
        // factors at q = 1 are a template that one multiplication per factor turns into any pose
        let ones = vec![1.0; machine.axes.len()];
        let mut buf = [Factor::Shift(Vector3::zeros()); MAX_FACTORS];
        let n = vm.build_factors_into(&ones, &mut buf);
        let pose_of_slot: Vec<usize> = vm.slots.iter().map(|s| s.pose_index).collect();
        let mut ideal_seen = 0;
        vm.template = buf[..n]
            .iter()
            .map(|f| match *f {
                // the ideal factors appear in slot order, one per slot
                Factor::Prismatic(..) | Factor::Revolute(..) => {
                    ideal_seen += 1;
                    (*f, pose_of_slot[ideal_seen - 1])
                }
                Factor::Squareness { slot, .. } => (*f, pose_of_slot[slot]),
                _ => (*f, usize::MAX),
            })
            .collect();
        vm
    }

    /// The machine.
    pub fn machine(&self) -> &Machine {
        &self.machine
    }

    /// Volumetric error at pose `q` (pose order: `machine.axes`, mm and deg).
    pub fn error(&self, q: &[f64], formalism: Formalism, order: Order) -> Volumetric {
        self.error_with(q, None, formalism, order)
    }

    /// Volumetric error at pose `q` with thermal terms evaluated at `temps`.
    pub fn error_with(
        &self,
        q: &[f64],
        temps: Option<&Temperatures>,
        formalism: Formalism,
        order: Order,
    ) -> Volumetric {
        let mut values = [SlotValues::default(); MAX_SLOTS];
        self.values_into(q, temps, &mut values);
        let values = &values[..self.slots.len()];
        if self.linear_only && formalism == Formalism::Htm && order == Order::FirstOrder {
            // the hot path: straight from the template, no factor buffer
            return translation_chain_first_order(
                self.template.iter().rev().map(|(f, idx)| {
                    if *idx == usize::MAX {
                        *f
                    } else {
                        scale_amount(f, q[*idx])
                    }
                }),
                values,
            );
        }
        let mut buf = [Factor::Shift(Vector3::zeros()); MAX_FACTORS];
        let n = self.factors_into(q, &mut buf);
        let factors = &buf[..n];
        match (formalism, order) {
            (Formalism::Htm, Order::Exact) => htm_exact(factors, values),
            (Formalism::Htm, Order::FirstOrder) => htm_first_order(factors, values),
            (Formalism::Poe, Order::Exact) => poe_exact(factors, values),
            (Formalism::Poe, Order::FirstOrder) => poe_first_order(factors, values),
        }
    }

    /// The exact tool frame relative to the workpiece reference point at pose `q` (pose order
    /// `machine.axes`, mm and deg): the chain product P of the module docs, with the error
    /// motions (`actual`) or without them (the ideal chain). Its translation is the tool tip
    /// (mm), its rotation maps tool-frame directions into the workpiece frame (the tool axis is
    /// `r·ẑ`). Allocates nothing.
    pub fn tool_frame(&self, q: &[f64], actual: bool) -> Htm {
        let mut buf = [Factor::Shift(Vector3::zeros()); MAX_FACTORS];
        let n = self.factors_into(q, &mut buf);
        let factors = &buf[..n];
        if !actual {
            return ideal_product(factors);
        }
        let mut values = [SlotValues::default(); MAX_SLOTS];
        self.values_into(q, None, &mut values);
        let values = &values[..self.slots.len()];
        factors
            .iter()
            .fold(Htm::identity(), |acc, f| acc * local_exact(f, values))
    }

    /// True when some rotary axis of the chain sits on the tool side (a head).
    pub fn has_tool_side_rotary(&self) -> bool {
        self.slots
            .iter()
            .any(|s| s.axis.is_rotary() && !s.workpiece_side)
    }

    /// The ideal (error-free) tool tip relative to the workpiece reference point, mm.
    pub fn ideal_tool_point(&self, q: &[f64]) -> [f64; 3] {
        let t = ideal_product(&self.factors(q));
        [t.p.x, t.p.y, t.p.z]
    }

    /// The linear observation model: for every element of the chain's axes, the change of
    /// [Ex, Ey, Ez] (µm) per unit of the element's value (µm or µrad) at pose `q`, to first order.
    /// Elements that do not reach the tool tip at this pose have a zero row.
    pub fn first_order_jacobian(&self, q: &[f64]) -> Vec<(ErrorElement, [f64; 3])> {
        let factors = self.factors(q);
        let lin = linearise(&factors);
        let mut out = Vec::new();
        for (k, f) in factors.iter().enumerate() {
            let (r_before, r_after) = (&lin.r_before[k], &lin.r_after[k]);
            match *f {
                Factor::Motion { slot, inverse } | Factor::Location { slot, inverse } => {
                    let loc = matches!(f, Factor::Location { .. });
                    let s = if inverse { -1.0 } else { 1.0 };
                    let axis = self.slots[slot].axis;
                    for d in Axis::ALL {
                        let el = ErrorElement {
                            direction: d,
                            axis,
                            location: loc,
                        };
                        if loc && ErrorElement::parse(&el.name()).is_err() {
                            continue;
                        }
                        let e = Vector3::from(d.unit());
                        // δ + ε × r, mapped to the workpiece frame (µm per µm, or µm per µrad)
                        let col = if d.is_rotary() {
                            r_before * e.cross(r_after) * 1e-6 * 1e3
                        } else {
                            r_before * e
                        };
                        out.push((el, (col * s).into()));
                    }
                }
                Factor::Squareness {
                    slot,
                    u,
                    amount,
                    inverse,
                } => {
                    let s = if inverse { -1.0 } else { 1.0 };
                    let axis = self.slots[slot].axis;
                    for d in [Axis::A, Axis::B, Axis::C] {
                        let el = ErrorElement::location(d, axis);
                        if ErrorElement::parse(&el.name()).is_err() {
                            continue;
                        }
                        let e = Vector3::from(d.unit());
                        // translation amount·(ε₀ × u): µm per µrad = amount[mm]·1e-6·1e3
                        let col = r_before * e.cross(&u) * amount * 1e-3;
                        out.push((el, (col * s).into()));
                    }
                }
                _ => {}
            }
        }
        out
    }

    fn values_into(
        &self,
        q: &[f64],
        temps: Option<&Temperatures>,
        out: &mut [SlotValues; MAX_SLOTS],
    ) {
        let ev = |f: &Option<ErrorFunction>, x: f64| match (f, temps) {
            (None, _) => 0.0,
            (Some(f), None) => f.value(x),
            (Some(f), Some(t)) => f.value_at(x, t),
        };
        for (k, s) in self.slots.iter().enumerate() {
            let x = q[s.pose_index];
            let m = |i: usize| ev(&s.motion[i], x);
            let l = |i: usize| ev(&s.location[i], x);
            out[k] = SlotValues {
                motion_delta: Vector3::new(m(0), m(1), m(2)) * 1e-3,
                motion_eps: Vector3::new(m(3), m(4), m(5)) * 1e-6,
                loc_delta: Vector3::new(l(0), l(1), l(2)) * 1e-3,
                loc_eps: Vector3::new(l(3), l(4), l(5)) * 1e-6,
            };
        }
    }

    /// Writes the factors at pose `q` into `out` from the template (no allocation).
    fn factors_into(&self, q: &[f64], out: &mut [Factor; MAX_FACTORS]) -> usize {
        for (k, (f, idx)) in self.template.iter().enumerate() {
            out[k] = if *idx == usize::MAX {
                *f
            } else {
                scale_amount(f, q[*idx])
            };
        }
        self.template.len()
    }

    /// The chain as a product of factors at pose `q` (see the module docs for the formula).
    fn factors(&self, q: &[f64]) -> Vec<Factor> {
        let mut buf = [Factor::Shift(Vector3::zeros()); MAX_FACTORS];
        let n = self.factors_into(q, &mut buf);
        buf[..n].to_vec()
    }

    /// Writes the factors into `out` and returns how many there are (no allocation).
    fn build_factors_into(&self, q: &[f64], out: &mut [Factor; MAX_FACTORS]) -> usize {
        let wo = self.machine.workpiece_origin_mm;
        let to = self.machine.tool_offset_mm;
        let reference = self.machine.error_frame == ErrorFrame::Reference;
        let mut n = 0;
        let mut push = |f: Factor| {
            out[n] = f;
            n += 1;
        };
        push(Factor::Shift(-Vector3::new(wo[0], wo[1], wo[2])));
        for (i, s) in self.slots.iter().enumerate() {
            let u = Vector3::from(s.axis.unit());
            let x = q[s.pose_index];
            // A = Trans(c)·[L₀]·M·[S]·E·Trans(−c) (moving) or Trans(c)·[L₀]·E·M·[S]·Trans(−c) (reference)
            let (ideal, square, loc) = if s.axis.is_rotary() {
                (
                    Factor::Revolute(u, x.to_radians()),
                    None,
                    Some(Factor::Location {
                        slot: i,
                        inverse: s.workpiece_side,
                    }),
                )
            } else {
                let amount = if s.workpiece_side { -x } else { x };
                (
                    Factor::Prismatic(u, amount),
                    Some(Factor::Squareness {
                        slot: i,
                        u,
                        amount,
                        inverse: s.workpiece_side,
                    }),
                    None,
                )
            };
            let err = Factor::Motion {
                slot: i,
                inverse: s.workpiece_side,
            };
            let mut body = [Factor::Shift(Vector3::zeros()); 4];
            let mut nb = 0;
            let order: [Option<Factor>; 4] = if reference {
                [loc, Some(err), Some(ideal), square]
            } else {
                [loc, Some(ideal), square, Some(err)]
            };
            for f in order.into_iter().flatten() {
                body[nb] = f;
                nb += 1;
            }
            let body = &mut body[..nb];
            if s.workpiece_side {
                // A⁻¹ = Trans(c)·(body)⁻¹·Trans(−c): reverse the order, invert each factor
                body.reverse();
                for f in body.iter_mut() {
                    *f = match *f {
                        Factor::Prismatic(u, a) => Factor::Prismatic(u, -a),
                        Factor::Revolute(u, a) => Factor::Revolute(u, -a),
                        other => other, // error factors carry `inverse: true` already
                    };
                }
            }
            push(Factor::Shift(s.centre));
            for f in body.iter() {
                push(*f);
            }
            push(Factor::Shift(-s.centre));
        }
        push(Factor::Shift(Vector3::new(to[0], to[1], to[2])));
        n
    }
}

/// A template factor at axis position `x` (its amount is linear in x).
fn scale_amount(f: &Factor, x: f64) -> Factor {
    match *f {
        Factor::Prismatic(u, a) => Factor::Prismatic(u, a * x),
        Factor::Revolute(u, a) => Factor::Revolute(u, a * x),
        Factor::Squareness {
            slot,
            u,
            amount,
            inverse,
        } => Factor::Squareness {
            slot,
            u,
            amount: amount * x,
            inverse,
        },
        other => other,
    }
}

/// The exact local transform of a factor.
fn local_exact(f: &Factor, v: &[SlotValues]) -> Htm {
    match *f {
        Factor::Shift(p) => Htm::translation(p),
        Factor::Prismatic(u, a) => Htm::translation(u * a),
        Factor::Revolute(u, a) => Htm::rotation(u, a),
        Factor::Motion { slot, inverse } => inv_if(
            Htm::error_exact(v[slot].motion_delta, v[slot].motion_eps),
            inverse,
        ),
        Factor::Location { slot, inverse } => inv_if(
            Htm::error_exact(v[slot].loc_delta, v[slot].loc_eps),
            inverse,
        ),
        Factor::Squareness {
            slot,
            u,
            amount,
            inverse,
        } => {
            let r0 = Htm::error_exact(Vector3::zeros(), v[slot].loc_eps).r;
            inv_if(Htm::translation((r0 * u - u) * amount), inverse)
        }
    }
}

fn inv_if(h: Htm, inverse: bool) -> Htm {
    if inverse {
        h.inverse()
    } else {
        h
    }
}

/// The local transform of a factor with all errors zero.
fn local_ideal(f: &Factor) -> Htm {
    match *f {
        Factor::Shift(p) => Htm::translation(p),
        Factor::Prismatic(u, a) => Htm::translation(u * a),
        Factor::Revolute(u, a) => Htm::rotation(u, a),
        _ => Htm::identity(),
    }
}

fn ideal_product(factors: &[Factor]) -> Htm {
    factors
        .iter()
        .fold(Htm::identity(), |acc, f| acc * local_ideal(f))
}

fn difference(actual: &Htm, ideal: &Htm) -> Volumetric {
    let dp = (actual.p - ideal.p) * 1e3;
    let dr = rotation_vector(&(actual.r * ideal.r.transpose())) * 1e6;
    Volumetric {
        position_um: dp.into(),
        orientation_urad: dr.into(),
    }
}

/// Exact HTM: multiply the local transforms body by body.
fn htm_exact(factors: &[Factor], v: &[SlotValues]) -> Volumetric {
    let actual = factors
        .iter()
        .fold(Htm::identity(), |acc, f| acc * local_exact(f, v));
    difference(&actual, &ideal_product(factors))
}

/// Prefix rotations and suffix lever arms of the ideal chain.
struct Linearised {
    /// Rotation of the ideal product before factor k.
    r_before: Vec<Matrix3<f64>>,
    /// Tool point expressed in the frame after factor k (ideal).
    r_after: Vec<Vector3<f64>>,
}

fn linearise(factors: &[Factor]) -> Linearised {
    let n = factors.len();
    let mut r_before = Vec::with_capacity(n);
    let mut acc = Matrix3::identity();
    for f in factors {
        r_before.push(acc);
        acc *= local_ideal(f).r;
    }
    let mut r_after = vec![Vector3::zeros(); n];
    let mut x = Vector3::zeros();
    for k in (0..n).rev() {
        r_after[k] = x;
        x = local_ideal(&factors[k]).point(&x);
    }
    Linearised { r_before, r_after }
}

/// (δ, ε) of an error factor in model units, with the sign of an inverse (first order: E⁻¹ ≈ (−δ, −ε)).
fn small_twist(f: &Factor, v: &[SlotValues]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let (d, e, inv) = match *f {
        Factor::Motion { slot, inverse } => (v[slot].motion_delta, v[slot].motion_eps, inverse),
        Factor::Location { slot, inverse } => (v[slot].loc_delta, v[slot].loc_eps, inverse),
        Factor::Squareness {
            slot,
            u,
            amount,
            inverse,
        } => (
            v[slot].loc_eps.cross(&u) * amount,
            Vector3::zeros(),
            inverse,
        ),
        _ => return None,
    };
    let s = if inv { -1.0 } else { 1.0 };
    Some((d * s, e * s))
}

/// First-order HTM (multi-body linearisation): ΔP = Σ_k R_<k (δ_k + ε_k × r_>k).
fn htm_first_order(factors: &[Factor], v: &[SlotValues]) -> Volumetric {
    let lin = linearise(factors);
    let mut dp = Vector3::zeros();
    let mut dr = Vector3::zeros();
    for (k, f) in factors.iter().enumerate() {
        if let Some((d, e)) = small_twist(f, v) {
            dp += lin.r_before[k] * (d + e.cross(&lin.r_after[k]));
            dr += lin.r_before[k] * e;
        }
    }
    Volumetric {
        position_um: (dp * 1e3).into(),
        orientation_urad: (dr * 1e6).into(),
    }
}

/// First-order HTM for a chain whose ideal factors are translations only (no rotary axis):
/// R_<k = I, so ΔP = Σ_k (δ_k + ε_k × r_>k) with r_>k the sum of the translations after k.
/// `factors_reversed` runs from the tool back to the workpiece.
fn translation_chain_first_order(
    factors_reversed: impl Iterator<Item = Factor>,
    v: &[SlotValues],
) -> Volumetric {
    let mut r_after = Vector3::zeros();
    let mut dp = Vector3::zeros();
    let mut dr = Vector3::zeros();
    for f in factors_reversed {
        match f {
            Factor::Shift(p) => r_after += p,
            Factor::Prismatic(u, a) => r_after += u * a,
            _ => {
                if let Some((d, e)) = small_twist(&f, v) {
                    dp += d + e.cross(&r_after);
                    dr += e;
                }
            }
        }
    }
    Volumetric {
        position_um: (dp * 1e3).into(),
        orientation_urad: (dr * 1e6).into(),
    }
}

/// The local unit twists and parameters of a factor: what it is as a product of exponentials.
fn local_screws(f: &Factor, v: &[SlotValues]) -> Vec<(Twist, f64)> {
    let o = Vector3::zeros();
    // E = Trans(δ)·Rz(εz)·Ry(εy)·Rx(εx) = e^{[x̂]δx} e^{[ŷ]δy} e^{[ẑ]δz} e^{[ω_z]εz} e^{[ω_y]εy} e^{[ω_x]εx}
    let error = |d: Vector3<f64>, e: Vector3<f64>, inverse: bool| {
        let mut s = vec![
            (Twist::prismatic(Vector3::x()), d.x),
            (Twist::prismatic(Vector3::y()), d.y),
            (Twist::prismatic(Vector3::z()), d.z),
            (Twist::revolute(Vector3::z(), o), e.z),
            (Twist::revolute(Vector3::y(), o), e.y),
            (Twist::revolute(Vector3::x(), o), e.x),
        ];
        if inverse {
            // (Π e^{S θ})⁻¹ = Π e^{−S θ} in reverse order
            s.reverse();
            s.iter_mut().for_each(|x| x.1 = -x.1);
        }
        s
    };
    match *f {
        Factor::Shift(_) => vec![],
        Factor::Prismatic(u, a) => vec![(Twist::prismatic(u), a)],
        Factor::Revolute(u, a) => vec![(Twist::revolute(u, o), a)],
        Factor::Motion { slot, inverse } => {
            error(v[slot].motion_delta, v[slot].motion_eps, inverse)
        }
        Factor::Location { slot, inverse } => error(v[slot].loc_delta, v[slot].loc_eps, inverse),
        Factor::Squareness {
            slot,
            u,
            amount,
            inverse,
        } => {
            let r0 = Htm::error_exact(Vector3::zeros(), v[slot].loc_eps).r;
            let w = r0 * u - u;
            let n = w.norm();
            if n == 0.0 {
                return vec![];
            }
            vec![(
                Twist::prismatic(w / n),
                if inverse { -amount * n } else { amount * n },
            )]
        }
    }
}

/// Exact POE: every factor becomes exponentials of space-frame twists S = Ad_{M_k} S_local,
/// with M_k the product of the fixed shifts before it (the home configuration), and
/// T = Π e^{[S]θ} · M (MR eq. 4.14).
fn poe_exact(factors: &[Factor], v: &[SlotValues]) -> Volumetric {
    let mut home = Htm::identity();
    let mut screws = Vec::with_capacity(8 * factors.len());
    let mut ideal_screws = Vec::with_capacity(factors.len());
    for f in factors {
        if let Factor::Shift(p) = f {
            home = home * Htm::translation(*p);
            continue;
        }
        for (s, th) in local_screws(f, v) {
            screws.push((adjoint(&home, &s), th));
        }
        if matches!(f, Factor::Prismatic(..) | Factor::Revolute(..)) {
            for (s, th) in local_screws(f, v) {
                ideal_screws.push((adjoint(&home, &s), th));
            }
        }
    }
    let actual = crate::poe::fk_in_space(&home, &screws);
    let ideal = crate::poe::fk_in_space(&home, &ideal_screws);
    difference(&actual, &ideal)
}

/// First-order POE: the space-Jacobian columns J = Ad_{Π e^{[S]θ} before}(S) of the error
/// screws, times the error values, give the twist of the tool tip: ΔP = Σ (ω_J × P + v_J)·value.
fn poe_first_order(factors: &[Factor], v: &[SlotValues]) -> Volumetric {
    let mut home = Htm::identity();
    let mut g = Htm::identity(); // product of the ideal exponentials so far
    let mut cols: Vec<(Twist, f64)> = Vec::new();
    for f in factors {
        match f {
            Factor::Shift(p) => home = home * Htm::translation(*p),
            Factor::Prismatic(..) | Factor::Revolute(..) => {
                for (s, th) in local_screws(f, v) {
                    g = g * exp6(&adjoint(&home, &s), th);
                }
            }
            _ => {
                // the small error's twist, to first order independent of the order of its six parts
                if let Some((d, e)) = small_twist(f, v) {
                    let local = Twist { w: e, v: d };
                    cols.push((adjoint(&g, &adjoint(&home, &local)), 1.0));
                }
            }
        }
    }
    let p_ideal = (g * home).p;
    let mut dp = Vector3::zeros();
    let mut dr = Vector3::zeros();
    for (j, val) in cols {
        dp += j.point_velocity(&p_ideal) * val;
        dr += j.w * val;
    }
    Volumetric {
        position_um: (dp * 1e3).into(),
        orientation_urad: (dr * 1e6).into(),
    }
}
