//! Poses of every axis (X, Y, Z and the rotary A, B, C): the error model interface extended to
//! rotary axes, the ideal kinematics of a chain, and the command that puts the tool where a
//! programmed pose means it to be.
//!
//! Conventions (the G-code and the real-time paths share them):
//! - A [`Pose`] holds the linear axes in mm and the rotary axes in **degrees** (LinuxCNC's
//!   units for A, B, C words), in the machine's own axis positions (no TCP: a program without
//!   tool centre point control commands the axes, not the tool tip).
//! - The **tool tip** and the **tool axis** are those of the chain product of
//!   `mtec_model::kinematics` (tool tip relative to the workpiece reference point, in the
//!   workpiece frame: the frame that turns with a rotary table); the tool axis is the tool
//!   frame's +Z. [`crate::ErrorModel::pose_error`] gives the actual minus the ideal tool tip
//!   (µm) and the orientation error (µrad, a rotation vector), both in the workpiece frame.
//! - The **corrected command** of a programmed pose q is the pose q' whose actual tool tip
//!   (through the model with its errors) is the ideal tool tip of q: P₀(q') + e(q') = P₀(q), and,
//!   where the chain allows it and it is asked for, whose actual tool axis is q's ideal one. It
//!   is found by Newton's method on the exact (not linearised) chain ([`command_for_pose`]).

pub use crate::chain::{ChainKinematics, Pose, PoseError};
use crate::ErrorModel;
use mtec_model::Htm;
use nalgebra::{Matrix2, SMatrix, SVector, Vector3};
/// Smallest singular value of the tool axis' Jacobian with respect to the two rotary axes
/// (rad per rad) at which the orientation is still corrected. At 0.1 the tool axis is 5.7° or
/// more from the chain's singular pose (the tool parallel to the last rotary axis, where that
/// axis cannot tilt it); nearer to it the rotary commands would have to turn by the
/// orientation error divided by this value, so only the tool tip is corrected there.
pub const MIN_ORIENTATION_SINGULAR_VALUE: f64 = 0.1;
/// Newton's method stops when the tool tip residual is below this (mm) ...
pub const POSITION_TOLERANCE_MM: f64 = 1e-10;
/// ... and the tool axis residual below this (rad).
pub const DIRECTION_TOLERANCE_RAD: f64 = 1e-12;
const MAX_NEWTON: usize = 30;
/// Difference steps of the numerical Jacobian (mm, deg).
const STEP_MM: f64 = 1e-3;
const STEP_DEG: f64 = 1e-3;

/// What [`command_for_pose`] is asked to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseSolveOptions {
    /// Correct the tool axis too, where the chain has two rotary axes, the model knows the
    /// orientation error and the pose is not near the singular one.
    pub orientation: bool,
    /// A linear correction larger than this (µm) is refused.
    pub max_correction_um: f64,
}

impl Default for PoseSolveOptions {
    fn default() -> Self {
        PoseSolveOptions {
            orientation: false,
            max_correction_um: 500.0,
        }
    }
}

/// The corrected command of a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseCommand {
    /// The axes to command.
    pub command: Pose,
    /// |P₀(q') + e(q') − P₀(q)| at the solution, µm.
    pub residual_um: f64,
    /// The angle between the actual tool axis at q' and the ideal one of q, µrad (when the
    /// model knows the orientation error).
    pub orientation_residual_urad: Option<f64>,
    /// Whether the rotary axes were corrected for the tool axis (else they are as given).
    pub orientation_corrected: bool,
    pub iterations: usize,
}

/// Why no command was found.
#[derive(Debug, Clone, PartialEq)]
pub enum PoseSolveError {
    /// The model has no finite value at this pose.
    NotFinite { pose: Pose },
    /// Newton's method did not reach the tolerance.
    NotConverged { residual_um: f64 },
    /// The linear correction exceeds the limit.
    TooLarge { correction_um: f64, max_um: f64 },
    /// The linear axes cannot move the tool tip in every direction at this pose.
    Singular,
}

impl std::fmt::Display for PoseSolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PoseSolveError::NotFinite { pose } => {
                write!(
                f,
                "the error model has no finite value at X{:.4} Y{:.4} Z{:.4} A{:.4} B{:.4} C{:.4}",
                pose.linear_mm[0], pose.linear_mm[1], pose.linear_mm[2],
                pose.rotary_deg[0], pose.rotary_deg[1], pose.rotary_deg[2]
            )
            }
            PoseSolveError::NotConverged { residual_um } => write!(
                f,
                "the corrected command did not converge (tool tip residual {residual_um:.3e} um)"
            ),
            PoseSolveError::TooLarge {
                correction_um,
                max_um,
            } => write!(
                f,
                "correction of {correction_um:.1} um exceeds --max-correction-um {max_um}"
            ),
            PoseSolveError::Singular => write!(
                f,
                "the linear axes cannot move the tool tip in every direction at this pose"
            ),
        }
    }
}

impl std::error::Error for PoseSolveError {}

/// The residual of the corrected-command equations at `q`: tool tip (mm) and, with `dir`, the
/// actual tool axis projected on two unit vectors normal to the wanted one.
struct Equations<'a> {
    model: &'a dyn ErrorModel,
    kin: &'a ChainKinematics,
    target: Vector3<f64>,
    /// (e1, e2) normal to the wanted tool axis.
    dir: Option<(Vector3<f64>, Vector3<f64>)>,
}

impl Equations<'_> {
    fn eval(&self, q: &Pose) -> Option<SVector<f64, 5>> {
        let frame = self.kin.tool_frame(q);
        let e = self.model.pose_error(q);
        let mut f = SVector::<f64, 5>::zeros();
        for i in 0..3 {
            // P₀(q') + e(q') − P₀(q)
            f[i] = frame.p[i] + e.position_um[i] * 1e-3 - self.target[i];
        }
        if let Some((e1, e2)) = self.dir {
            let d = actual_axis(&frame, e.orientation_urad?);
            f[3] = e1.dot(&d);
            f[4] = e2.dot(&d);
        }
        f.iter().all(|v| v.is_finite()).then_some(f)
    }
}

/// The actual tool axis Rot(ω)·R₀·ẑ from the ideal frame and the orientation error ω (µrad).
pub fn actual_axis(ideal: &Htm, orientation_urad: [f64; 3]) -> Vector3<f64> {
    let w = Vector3::from(orientation_urad) * 1e-6;
    let d = ideal.r * Vector3::z();
    let angle = w.norm();
    if angle == 0.0 {
        return d;
    }
    mtec_model::htm::rodrigues(&(w / angle), angle) * d
}

/// The unknowns: X, Y, Z, then the rotary axes `rot` (indices 0..3 into A, B, C).
fn shifted(q: &Pose, k: usize, rot: [usize; 2], h: f64) -> Pose {
    let mut p = *q;
    if k < 3 {
        p.linear_mm[k] += h;
    } else {
        p.rotary_deg[rot[k - 3]] += h;
    }
    p
}

/// The command whose actual tool tip is the ideal tool tip of `nominal` (module docs), by
/// Newton's method on the exact chain with a central-difference Jacobian. The rotary axes are
/// kept as programmed unless the orientation is corrected (see [`PoseSolveOptions`] and
/// [`MIN_ORIENTATION_SINGULAR_VALUE`]).
pub fn command_for_pose(
    model: &dyn ErrorModel,
    kin: &ChainKinematics,
    nominal: &Pose,
    opt: &PoseSolveOptions,
) -> Result<PoseCommand, PoseSolveError> {
    let ideal = kin.tool_frame(nominal);
    let d0 = ideal.r * Vector3::z();
    // two unit vectors normal to the wanted tool axis
    let helper = if d0.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = d0.cross(&helper).normalize();
    let e2 = d0.cross(&e1);
    let rot_axes: Vec<usize> = (0..3).filter(|&k| kin.rotary_axes()[k]).collect();
    let knows_orientation = model.pose_error(nominal).orientation_urad.is_some();
    let mut rot = [0usize; 2];
    let mut orient = opt.orientation && rot_axes.len() == 2 && knows_orientation;
    if orient {
        rot = [rot_axes[0], rot_axes[1]];
        // the tool axis' Jacobian with respect to the two rotary axes, per rad
        let mut jd = Matrix2::zeros();
        for (c, &r) in rot.iter().enumerate() {
            let h = STEP_DEG;
            let mut a = *nominal;
            let mut b = *nominal;
            a.rotary_deg[r] += h;
            b.rotary_deg[r] -= h;
            let dd = (Vector3::from(kin.tool_direction(&a))
                - Vector3::from(kin.tool_direction(&b)))
                / (2.0 * h.to_radians());
            jd[(0, c)] = e1.dot(&dd);
            jd[(1, c)] = e2.dot(&dd);
        }
        let s = jd.singular_values();
        if s.min() < MIN_ORIENTATION_SINGULAR_VALUE {
            orient = false;
        }
    }
    let eq = Equations {
        model,
        kin,
        target: ideal.p,
        dir: orient.then_some((e1, e2)),
    };
    let n = if orient { 5 } else { 3 };
    let mut q = *nominal;
    let mut f = eq.eval(&q).ok_or(PoseSolveError::NotFinite { pose: q })?;
    let mut iterations = 0;
    loop {
        let pos = Vector3::new(f[0], f[1], f[2]).norm();
        let dir = (f[3] * f[3] + f[4] * f[4]).sqrt();
        if pos <= POSITION_TOLERANCE_MM && dir <= DIRECTION_TOLERANCE_RAD {
            break;
        }
        if iterations == MAX_NEWTON {
            return Err(PoseSolveError::NotConverged {
                residual_um: pos * 1e3,
            });
        }
        iterations += 1;
        // J·Δ = −F, J by central differences of the exact equations
        let mut j = SMatrix::<f64, 5, 5>::identity();
        for k in 0..n {
            let h = if k < 3 { STEP_MM } else { STEP_DEG };
            let fp = eq
                .eval(&shifted(&q, k, rot, h))
                .ok_or(PoseSolveError::NotFinite { pose: q })?;
            let fm = eq
                .eval(&shifted(&q, k, rot, -h))
                .ok_or(PoseSolveError::NotFinite { pose: q })?;
            for r in 0..n {
                j[(r, k)] = (fp[r] - fm[r]) / (2.0 * h);
            }
        }
        let step = j.lu().solve(&(-f)).ok_or(PoseSolveError::Singular)?;
        for k in 0..n {
            if k < 3 {
                q.linear_mm[k] += step[k];
            } else {
                q.rotary_deg[rot[k - 3]] += step[k];
            }
        }
        f = eq.eval(&q).ok_or(PoseSolveError::NotFinite { pose: q })?;
    }
    let c = [0, 1, 2].map(|i| q.linear_mm[i] - nominal.linear_mm[i]);
    let correction_um = Vector3::from(c).norm() * 1e3;
    if correction_um > opt.max_correction_um {
        return Err(PoseSolveError::TooLarge {
            correction_um,
            max_um: opt.max_correction_um,
        });
    }
    let residual_um = Vector3::new(f[0], f[1], f[2]).norm() * 1e3;
    let orientation_residual_urad = model.pose_error(&q).orientation_urad.map(|w| {
        let d = actual_axis(&kin.tool_frame(&q), w);
        d.cross(&d0).norm().asin() * 1e6
    });
    Ok(PoseCommand {
        command: q,
        residual_um,
        orientation_residual_urad,
        orientation_corrected: orient,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematic::KinematicModel;
    use mtec_model::{
        location_elements, motion_elements, AxisSpec, ErrorFrame, ErrorFunction, MachineSpec,
    };
    use mtec_model::{ErrorSet, Machine, VolumetricModel};
    use nalgebra::Matrix3;
    use std::collections::BTreeMap;

    /// A machine of `chain` with realistic centres and a tool offset.
    fn machine(chain: &str) -> Machine {
        let mut axes = BTreeMap::new();
        for c in chain.chars().filter(|c| "XYZABC".contains(*c)) {
            let rotary = "ABC".contains(c);
            axes.insert(
                c.to_string(),
                AxisSpec {
                    travel: if rotary {
                        [-120.0, 120.0]
                    } else {
                        [-300.0, 300.0]
                    },
                    centre_mm: if rotary { [1.5, -2.0, 40.0] } else { [0.0; 3] },
                    period_mm: None,
                },
            );
        }
        Machine::from_spec(MachineSpec {
            name: chain.into(),
            chain: chain.into(),
            axes,
            tool_offset_mm: [0.0, 0.0, 120.0],
            workpiece_origin_mm: [10.0, -5.0, 60.0],
            error_frame: ErrorFrame::Moving,
        })
        .unwrap()
    }

    /// Deterministic error functions of every element, of realistic size (µm, µrad).
    fn errors(m: &Machine) -> ErrorSet {
        let mut set = ErrorSet::new("test");
        let mut k = 0.0f64;
        for &a in &m.axes {
            let mut els: Vec<mtec_model::ErrorElement> = motion_elements(a).to_vec();
            els.extend(location_elements(a));
            for e in els {
                k += 1.0;
                let mag = if e.is_angular() { 25.0 } else { 8.0 };
                let s = (k * 1.7).sin();
                let f = if e.location {
                    ErrorFunction::constant(mag * s)
                } else if a.is_rotary() {
                    ErrorFunction::fourier(
                        mag * s,
                        vec![0.5 * mag * (k * 0.3).cos(), 0.2 * mag],
                        vec![0.4 * mag * s, 0.0, 0.1 * mag],
                    )
                } else {
                    ErrorFunction::polynomial(vec![
                        mag * 0.2 * s,
                        mag * s / 300.0,
                        mag * (k * 0.9).cos() / 90_000.0,
                    ])
                };
                set.insert(e, f);
            }
        }
        set
    }

    fn pose_at(i: usize) -> Pose {
        let f = |k: f64| ((i as f64 + 1.0) * k).sin();
        Pose::new(
            [250.0 * f(0.37), 250.0 * f(0.71), 200.0 * f(1.13)],
            [100.0 * f(0.53), 100.0 * f(0.29), 110.0 * f(0.91)],
        )
    }

    /// Newton's solution checked on the exact forward kinematics computed independently of
    /// `pose_error` (the chain product with the errors): the actual tool tip at the command is
    /// the ideal tool tip of the programmed pose within 1e-9 mm, and where the orientation is
    /// corrected the actual tool axis is the ideal one within 1e-9 rad.
    #[test]
    fn newton_reaches_the_ideal_tool_tip_on_the_exact_chain() {
        for chain in ["WCAYFXZT", "WCXYFZT", "WXYFZCBT", "WXYFZT"] {
            let m = machine(chain);
            let set = errors(&m);
            let model = KinematicModel::new(&m, &set, "test").unwrap();
            let kin = model.kinematics().unwrap().clone();
            let exact = VolumetricModel::new(&m, &set);
            let mut corrected = 0;
            for i in 0..60 {
                let nominal = pose_at(i);
                for orientation in [false, true] {
                    let opt = PoseSolveOptions {
                        orientation,
                        max_correction_um: 1e4,
                    };
                    let c = command_for_pose(&model, &kin, &nominal, &opt).unwrap();
                    let q = kin.pose_vector(&c.command);
                    let q = &q[..kin.n_axes()];
                    let mut actual = exact.tool_frame(q, true);
                    if !kin.has_rotary() {
                        // a chain without rotary axes is modelled to first order (kinematic.rs)
                        let v = exact.error(
                            q,
                            mtec_model::Formalism::Htm,
                            mtec_model::Order::FirstOrder,
                        );
                        actual.p =
                            exact.tool_frame(q, false).p + Vector3::from(v.position_um) * 1e-3;
                    }
                    let ideal = kin.tool_frame(&nominal);
                    let miss = (actual.p - ideal.p).norm();
                    assert!(miss <= 1e-9, "{chain} {i}: {miss:e} mm");
                    assert!(c.residual_um <= 1e-6);
                    if c.orientation_corrected {
                        corrected += 1;
                        let d = actual.r * Vector3::z();
                        let d0 = ideal.r * Vector3::z();
                        assert!(d.cross(&d0).norm() <= 1e-9, "{chain} {i}");
                    } else {
                        assert_eq!(c.command.rotary_deg, nominal.rotary_deg);
                    }
                    // the correction is of the size of the errors, not a different solution
                    let dx = (0..3)
                        .map(|k| (c.command.linear_mm[k] - nominal.linear_mm[k]).abs())
                        .fold(0.0, f64::max);
                    assert!(dx < 0.2, "{chain}: {dx} mm");
                }
            }
            // two rotary axes: the tool axis is corrected away from the singular poses
            if chain == "WCAYFXZT" || chain == "WXYFZCBT" {
                assert!(corrected > 40, "{chain}: {corrected}");
            } else {
                assert_eq!(corrected, 0, "{chain}");
            }
        }
    }

    /// Near the singular pose of a table-tilting chain (A ≈ 0: C turns about the tool axis)
    /// the tool axis cannot be steered by C; only the tool tip is corrected there.
    #[test]
    fn the_singular_pose_keeps_the_rotary_commands() {
        let m = machine("WCAYFXZT");
        let model = KinematicModel::new(&m, &errors(&m), "test").unwrap();
        let kin = model.kinematics().unwrap();
        let opt = PoseSolveOptions {
            orientation: true,
            max_correction_um: 1e4,
        };
        let nominal = Pose::new([10.0, 20.0, 30.0], [0.5, 0.0, 40.0]);
        let c = command_for_pose(&model, kin, &nominal, &opt).unwrap();
        assert!(!c.orientation_corrected);
        assert_eq!(c.command.rotary_deg, nominal.rotary_deg);
        let tilted = Pose::new([10.0, 20.0, 30.0], [30.0, 0.0, 40.0]);
        assert!(
            command_for_pose(&model, kin, &tilted, &opt)
                .unwrap()
                .orientation_corrected
        );
    }

    #[test]
    fn the_linear_jacobian_is_the_workpiece_frame_of_the_axes() {
        let m = machine("WCAYFXZT");
        let kin = ChainKinematics::new(&m).unwrap();
        assert_eq!(kin.linear_jacobian([0.0; 3]), Matrix3::identity());
        // a table turned by C = 90°: +X of the tool is −Y in the table frame (it turns +90°)
        let j = kin.linear_jacobian([0.0, 0.0, 90.0]);
        let x = j.column(0);
        assert!((x[1] + 1.0).abs() < 1e-12 && x[0].abs() < 1e-12, "{j}");
        assert!(ChainKinematics::new(&machine("WCFT"))
            .unwrap_err()
            .contains("X"));
    }
}
