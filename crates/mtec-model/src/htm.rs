//! Homogeneous transformation matrices (rigid-body transforms) and the small-error transform of
//! ISO 230-1 error motions.

use nalgebra::{Matrix3, Vector3};
use std::ops::Mul;

/// A rigid-body transform: rotation `r` and translation `p` (mm); acts on a point x as r·x + p.
/// Equivalent to the 4×4 homogeneous matrix [[r, p], [0, 1]].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Htm {
    pub r: Matrix3<f64>,
    pub p: Vector3<f64>,
}

impl Htm {
    /// The identity.
    pub fn identity() -> Htm {
        Htm {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// A pure translation.
    pub fn translation(p: Vector3<f64>) -> Htm {
        Htm {
            r: Matrix3::identity(),
            p,
        }
    }

    /// A pure rotation by `angle_rad` about the unit direction `axis` through the origin
    /// (Rodrigues: R = I + sinθ [ω] + (1 − cosθ) [ω]²).
    pub fn rotation(axis: Vector3<f64>, angle_rad: f64) -> Htm {
        Htm {
            r: rodrigues(&axis, angle_rad),
            p: Vector3::zeros(),
        }
    }

    /// A rotation about the line through `point` with direction `axis`: Trans(c)·Rot·Trans(−c).
    pub fn rotation_about_line(axis: Vector3<f64>, point: Vector3<f64>, angle_rad: f64) -> Htm {
        let r = rodrigues(&axis, angle_rad);
        Htm {
            r,
            p: point - r * point,
        }
    }

    /// The exact transform of an error motion: translations δ (mm) and rotations ε (rad) about
    /// the fixed X, then Y, then Z axes: E = Trans(δ)·Rz(εz)·Ry(εy)·Rx(εx).
    pub fn error_exact(delta: Vector3<f64>, eps: Vector3<f64>) -> Htm {
        let rx = rodrigues(&Vector3::x(), eps.x);
        let ry = rodrigues(&Vector3::y(), eps.y);
        let rz = rodrigues(&Vector3::z(), eps.z);
        Htm {
            r: rz * ry * rx,
            p: delta,
        }
    }

    /// The first-order (small-angle) error transform: R ≈ I + [ε]×, p = δ.
    pub fn error_first_order(delta: Vector3<f64>, eps: Vector3<f64>) -> Htm {
        Htm {
            r: Matrix3::identity() + skew(&eps),
            p: delta,
        }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Htm {
        let rt = self.r.transpose();
        Htm {
            r: rt,
            p: -(rt * self.p),
        }
    }

    /// Applies the transform to a point.
    pub fn point(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.r * x + self.p
    }

    /// The 4×4 matrix.
    pub fn to_matrix(&self) -> nalgebra::Matrix4<f64> {
        let mut m = nalgebra::Matrix4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.r);
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.p);
        m
    }
}

impl Mul for Htm {
    type Output = Htm;
    fn mul(self, o: Htm) -> Htm {
        Htm {
            r: self.r * o.r,
            p: self.r * o.p + self.p,
        }
    }
}

/// The skew-symmetric matrix [w]× with [w]× v = w × v.
pub fn skew(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// Rotation matrix about unit axis ω by θ (Rodrigues' formula).
pub fn rodrigues(w: &Vector3<f64>, theta: f64) -> Matrix3<f64> {
    let k = skew(w);
    Matrix3::identity() + k * theta.sin() + k * k * (1.0 - theta.cos())
}

/// The rotation vector (axis·angle) of a rotation matrix (the matrix logarithm of SO(3)).
pub fn rotation_vector(r: &Matrix3<f64>) -> Vector3<f64> {
    let cos = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let theta = cos.acos();
    let v = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    );
    if theta < 1e-8 {
        return v / 2.0;
    }
    v * (theta / (2.0 * theta.sin()))
}
