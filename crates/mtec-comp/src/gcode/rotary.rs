//! The rewriter's view of a model with rotary axes: while the rotary axes stand still, the
//! tool tip is an affine function of X, Y, Z, so a move of the linear axes is compensated with
//! the three-axis machinery unchanged.
//!
//! With the rotary axes at angles θ, the ideal tool tip in the workpiece frame is
//! P₀(x, θ) = J(θ)·x + b(θ) (the chain's rotations depend on the angles only;
//! [`ChainKinematics::linear_jacobian`]). The command x' that puts the actual tool tip on the
//! ideal tool tip of x solves J·x' + b + e(x', θ) = J·x + b, that is
//!
//!   x' + ε(x') = x,   ε(x') = J(θ)⁻¹·e(x', θ)
//!
//! — the three-axis equation `p + e(p) = t` with the error ε read in machine axes. For the
//! chains mtec models J is a rotation (its columns are the machine axes seen from the
//! workpiece), so |ε| = |e| and a distance in machine axes is the same distance in the workpiece
//! frame: every path bound of the three-axis rewriter stays a bound of the tool tip's distance
//! from its nominal path. [`RotaryView::set_rotary`] refuses a pose where J is not a rotation.

use crate::pose::{ChainKinematics, Pose};
use crate::ErrorModel;
use nalgebra::{Matrix3, Vector3};

/// A model seen at fixed rotary angles, in machine axes (module docs).
pub struct RotaryView<'a> {
    model: &'a dyn ErrorModel,
    /// The chain, when it has rotary axes (else the view is the model itself).
    kin: Option<&'a ChainKinematics>,
    rotary_deg: [f64; 3],
    /// J(θ)⁻¹ = J(θ)ᵀ.
    jt: Matrix3<f64>,
    /// b(θ) = P₀(0, θ).
    b: Vector3<f64>,
}

impl<'a> RotaryView<'a> {
    pub fn new(model: &'a dyn ErrorModel) -> Self {
        let kin = model.kinematics().filter(|k| k.has_rotary());
        RotaryView {
            model,
            kin,
            // with rotary axes the angles are not known until the program (or the start
            // pose) gives them
            rotary_deg: if kin.is_some() {
                [f64::NAN; 3]
            } else {
                [0.0; 3]
            },
            jt: Matrix3::identity(),
            b: Vector3::zeros(),
        }
    }

    /// The model behind the view.
    pub fn model(&self) -> &'a dyn ErrorModel {
        self.model
    }

    /// The chain, when the model has rotary axes.
    pub fn kinematics(&self) -> Option<&'a ChainKinematics> {
        self.kin
    }

    /// Which of A, B, C the model has.
    pub fn rotary_axes(&self) -> [bool; 3] {
        self.kin.map_or([false; 3], |k| k.rotary_axes())
    }

    /// The angles the view stands at.
    pub fn rotary_deg(&self) -> [f64; 3] {
        self.rotary_deg
    }

    /// Moves the view to the angles `rotary_deg` (axes the chain lacks are ignored). Refused
    /// when the linear axes do not move the tool tip along three orthonormal directions there.
    pub fn set_rotary(&mut self, rotary_deg: [f64; 3]) -> Result<(), String> {
        let Some(kin) = self.kin else {
            return Ok(());
        };
        let r = [0, 1, 2].map(|k| {
            if kin.rotary_axes()[k] {
                rotary_deg[k]
            } else {
                0.0
            }
        });
        if r == self.rotary_deg {
            return Ok(());
        }
        let j = kin.linear_jacobian(r);
        let off = (j.transpose() * j - Matrix3::identity()).abs().max();
        if off.is_nan() || off > 1e-9 {
            return Err(format!(
                "at A{} B{} C{} the linear axes of chain `{}` do not move the tool tip along three perpendicular directions of the workpiece: not compensated",
                r[0], r[1], r[2], kin.chain()
            ));
        }
        self.jt = j.transpose();
        self.b = kin.tool_frame(&Pose::new([0.0; 3], r)).p;
        self.rotary_deg = r;
        Ok(())
    }

    /// The machine-axis point (mm) whose ideal tool tip at the view's angles is the tool tip
    /// `point` (workpiece frame): J⁻¹·(point − b).
    pub fn machine_point(&self, point: [f64; 3]) -> [f64; 3] {
        if self.kin.is_none() {
            return point;
        }
        (self.jt * (Vector3::from(point) - self.b)).into()
    }
}

impl ErrorModel for RotaryView<'_> {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        match self.kin {
            None => self.model.error_um(p_mm),
            Some(_) => {
                let e = self
                    .model
                    .pose_error(&Pose::new(p_mm, self.rotary_deg))
                    .position_um;
                // ε = J⁻¹·e (module docs)
                (self.jt * Vector3::from(e)).into()
            }
        }
    }
    fn describe(&self) -> String {
        self.model.describe()
    }
    fn as_grid(&self) -> Option<&crate::GridMap> {
        match self.kin {
            None => self.model.as_grid(),
            Some(_) => None,
        }
    }
    fn kinematics(&self) -> Option<&ChainKinematics> {
        self.model.kinematics()
    }
    /// In machine axes, as the model's.
    fn domain_mm(&self) -> Option<[[f64; 2]; 3]> {
        self.model.domain_mm()
    }
}
