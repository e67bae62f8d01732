//! Screw theory in the form of Lynch & Park, *Modern Robotics* (2017): twists, the matrix
//! exponential of a twist, the adjoint map, and forward kinematics as a product of exponentials
//! in the space frame.

use crate::htm::{rodrigues, skew, Htm};
use nalgebra::{Matrix3, Vector3};

/// A twist (screw axis times a rate): angular part ω and linear part v, both in the space frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Twist {
    pub w: Vector3<f64>,
    pub v: Vector3<f64>,
}

impl Twist {
    /// A pure translation screw along unit direction `u` (ω = 0, v = u).
    pub fn prismatic(u: Vector3<f64>) -> Twist {
        Twist {
            w: Vector3::zeros(),
            v: u,
        }
    }

    /// A revolute screw about unit direction `w` through the point `q`: v = −ω × q (MR eq. 3.71).
    pub fn revolute(w: Vector3<f64>, q: Vector3<f64>) -> Twist {
        Twist { w, v: -w.cross(&q) }
    }

    /// The twist scaled by θ.
    pub fn scaled(&self, theta: f64) -> Twist {
        Twist {
            w: self.w * theta,
            v: self.v * theta,
        }
    }

    /// The velocity this twist gives a point x (first-order displacement for a small twist): ω × x + v.
    pub fn point_velocity(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.w.cross(x) + self.v
    }
}

/// Matrix exponential of a unit screw S times θ (MR Prop. 3.25, eq. 3.88):
/// e^{[S]θ} = [[e^{[ω]θ}, (Iθ + (1 − cosθ)[ω] + (θ − sinθ)[ω]²) v], [0, 1]] for |ω| = 1;
/// [[I, vθ], [0, 1]] for ω = 0.
pub fn exp6(s: &Twist, theta: f64) -> Htm {
    let wn = s.w.norm();
    if wn < 1e-15 {
        return Htm::translation(s.v * theta);
    }
    // normalise so that the screw has a unit rotation axis
    let w = s.w / wn;
    let v = s.v / wn;
    let th = theta * wn;
    let k = skew(&w);
    let g = Matrix3::identity() * th + k * (1.0 - th.cos()) + k * k * (th - th.sin());
    Htm {
        r: rodrigues(&w, th),
        p: g * v,
    }
}

/// The adjoint map of T = (R, p) applied to a twist (MR eq. 3.83): ω' = Rω, v' = [p]Rω + Rv.
pub fn adjoint(t: &Htm, s: &Twist) -> Twist {
    let w = t.r * s.w;
    Twist {
        w,
        v: t.p.cross(&w) + t.r * s.v,
    }
}

/// Forward kinematics in the space frame (MR eq. 4.14): T = e^{[S1]θ1} ··· e^{[Sn]θn} M.
pub fn fk_in_space(m: &Htm, screws: &[(Twist, f64)]) -> Htm {
    screws
        .iter()
        .rev()
        .fold(*m, |acc, (s, th)| exp6(s, *th) * acc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp6_of_revolute_is_rotation_about_the_line() {
        let q = Vector3::new(10.0, -5.0, 3.0);
        let s = Twist::revolute(Vector3::z(), q);
        let t = exp6(&s, 0.7);
        let h = Htm::rotation_about_line(Vector3::z(), q, 0.7);
        assert!((t.r - h.r).norm() < 1e-14 && (t.p - h.p).norm() < 1e-12);
        // points on the axis do not move
        assert!((t.point(&q) - q).norm() < 1e-12);
    }

    #[test]
    fn adjoint_conjugates_the_exponential() {
        // e^{[Ad_T S]θ} = T e^{[S]θ} T⁻¹ (MR eq. 3.84)
        let t = Htm::rotation(Vector3::new(1.0, 2.0, 2.0) / 3.0, 0.4)
            * Htm::translation(Vector3::new(1.0, 2.0, 3.0));
        let s = Twist {
            w: Vector3::new(0.0, 0.6, 0.8),
            v: Vector3::new(1.0, -1.0, 0.5),
        };
        let lhs = exp6(&adjoint(&t, &s), 0.3);
        let rhs = t * exp6(&s, 0.3) * t.inverse();
        assert!((lhs.r - rhs.r).norm() < 1e-13 && (lhs.p - rhs.p).norm() < 1e-12);
    }
}
