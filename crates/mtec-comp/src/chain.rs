//! The ideal kinematics of a machine chain in the poses of its axes: [`Pose`] (X, Y, Z in mm,
//! A, B, C in degrees), the tool tip and tool axis of the ideal chain ([`ChainKinematics`]) and
//! the error of a pose ([`PoseError`]). No error model here: `model` (the `ErrorModel` trait)
//! and `pose` (the corrected command of a pose) build on it.

use mtec_model::{Axis, ErrorSet, Htm, Machine, VolumetricModel};
use nalgebra::{Matrix3, Vector3};

/// A position of every axis: linear axes in mm, rotary axes in degrees. The axes a machine
/// does not have are ignored.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// X, Y, Z in mm.
    pub linear_mm: [f64; 3],
    /// A, B, C in degrees.
    pub rotary_deg: [f64; 3],
}

impl Pose {
    pub fn new(linear_mm: [f64; 3], rotary_deg: [f64; 3]) -> Pose {
        Pose {
            linear_mm,
            rotary_deg,
        }
    }
    /// A pose with the rotary axes at 0°.
    pub fn linear(linear_mm: [f64; 3]) -> Pose {
        Pose::new(linear_mm, [0.0; 3])
    }
}

/// The error of the tool relative to the workpiece at a pose, in the workpiece frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseError {
    /// Actual minus ideal tool tip, µm.
    pub position_um: [f64; 3],
    /// Orientation error of the tool as a rotation vector (actual = Rot(ω)·ideal), µrad;
    /// `None` when the model does not know it (grid maps, fitted networks).
    pub orientation_urad: Option<[f64; 3]>,
}

/// The ideal kinematics of a chain that has X, Y and Z and any of A, B, C: the tool tip and
/// tool axis of a pose in the workpiece frame. Allocates nothing per evaluation.
#[derive(Debug, Clone)]
pub struct ChainKinematics {
    ideal: VolumetricModel,
    /// Index in the machine's pose vector of X, Y, Z, A, B, C.
    index: [Option<usize>; 6],
    n: usize,
    rotary: [bool; 3],
    tool_side_rotary: bool,
}

impl ChainKinematics {
    /// The ideal chain of a machine. Compensation moves the tool tip with X, Y and Z, so the
    /// chain must have all three.
    pub fn new(machine: &Machine) -> Result<ChainKinematics, String> {
        for a in [Axis::X, Axis::Y, Axis::Z] {
            if machine.axis_index(a).is_none() {
                return Err(format!(
                    "chain `{}` has no {a} axis: compensation moves the tool tip with X, Y and Z, so the machine must have all three (a rotary table alone, `WCFT`, is an identification chain: give the whole machine, e.g. `WCXYFZT` or `WCAYFXZT`)",
                    machine.chain.text
                ));
            }
        }
        let ideal = VolumetricModel::new(machine, &ErrorSet::new("ideal chain"));
        let index = Axis::ALL.map(|a| machine.axis_index(a));
        let rotary = [index[3].is_some(), index[4].is_some(), index[5].is_some()];
        let tool_side_rotary = ideal.has_tool_side_rotary();
        Ok(ChainKinematics {
            ideal,
            index,
            n: machine.axes.len(),
            rotary,
            tool_side_rotary,
        })
    }

    /// The chain text, e.g. `WCAYFXZT`.
    pub fn chain(&self) -> &str {
        &self.ideal.machine().chain.text
    }

    /// The machine.
    pub fn machine(&self) -> &Machine {
        self.ideal.machine()
    }

    /// Which of A, B, C the chain has.
    pub fn rotary_axes(&self) -> [bool; 3] {
        self.rotary
    }

    /// True when the chain has a rotary axis.
    pub fn has_rotary(&self) -> bool {
        self.rotary.iter().any(|&r| r)
    }

    /// True when a rotary axis turns the tool (a head) rather than the workpiece.
    pub fn has_tool_side_rotary(&self) -> bool {
        self.tool_side_rotary
    }

    /// The pose as the machine's pose vector (its first [`Self::n_axes`] entries).
    pub fn pose_vector(&self, pose: &Pose) -> [f64; 6] {
        let mut q = [0.0; 6];
        for (k, idx) in self.index.iter().enumerate() {
            if let Some(i) = idx {
                q[*i] = if k < 3 {
                    pose.linear_mm[k]
                } else {
                    pose.rotary_deg[k - 3]
                };
            }
        }
        q
    }

    /// Number of axes of the chain.
    pub fn n_axes(&self) -> usize {
        self.n
    }

    /// The ideal tool frame at a pose (translation: tool tip, mm; rotation: tool → workpiece).
    pub fn tool_frame(&self, pose: &Pose) -> Htm {
        let q = self.pose_vector(pose);
        self.ideal.tool_frame(&q[..self.n], false)
    }

    /// The ideal tool tip in the workpiece frame, mm.
    pub fn tool_point(&self, pose: &Pose) -> [f64; 3] {
        self.tool_frame(pose).p.into()
    }

    /// The ideal tool axis (unit, the tool frame's +Z) in the workpiece frame.
    pub fn tool_direction(&self, pose: &Pose) -> [f64; 3] {
        (self.tool_frame(pose).r * Vector3::z()).into()
    }

    /// ∂P₀/∂(x, y, z) at rotary angles `rotary_deg`: column i is the workpiece-frame motion of
    /// the tool tip per mm of linear axis i. The ideal tool tip is affine in the linear axes
    /// (rotations depend on the angles only), so the columns are exact differences.
    pub fn linear_jacobian(&self, rotary_deg: [f64; 3]) -> Matrix3<f64> {
        let base = self.tool_frame(&Pose::new([0.0; 3], rotary_deg)).p;
        let mut j = Matrix3::zeros();
        for i in 0..3 {
            let mut l = [0.0; 3];
            l[i] = 1.0;
            let p = self.tool_frame(&Pose::new(l, rotary_deg)).p;
            j.set_column(i, &(p - base));
        }
        j
    }
}
