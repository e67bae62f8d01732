//! Measurement designs for line-based identification: which lines a laser interferometer
//! measures, and along which directions it reads.
//!
//! A line is a straight commanded trajectory of the tool from `start_mm` to `end_mm` in `steps`
//! intervals, with one or more reading channels. A channel reads the projection of the tool
//! displacement on its unit direction: along the line (linear optics: displacement) or across
//! it (straightness optics). A straightness channel's optics are aligned by hand, so its reading
//! carries an unknown linear trend along the line; identification must treat that trend as a
//! nuisance parameter, which is why squareness comes from two-axis (diagonal) lines and not
//! from straightness slopes.
//!
//! # Presets
//! - `nine-line` (the 9-line method): X along three lines (offsets in Y and Z give its yaw and
//!   pitch as Abbe differences, the Y-straightness at two heights gives its roll), Y along two
//!   lines (the Z offset gives its pitch and roll), Z along one line, each with displacement and
//!   both straightness channels; plus three face diagonals with two axes moving together
//!   (XY, XZ, YZ: displacement) that fix the three squareness errors.
//! - `fifteen-line`: the nine plus the three opposite face diagonals and three more axial lines
//!   (X and Y at the far corner, Z at a second XY position): redundancy for a better-conditioned
//!   estimate.

use crate::machine::Machine;
use crate::Axis;
use serde::{Deserialize, Serialize};

/// One measured line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineSpec {
    pub name: String,
    pub start_mm: [f64; 3],
    pub end_mm: [f64; 3],
    pub steps: usize,
    /// Reading directions (unit vectors). The first is usually along the line.
    pub channels: Vec<[f64; 3]>,
}

impl LineSpec {
    /// Commanded points of the line (steps + 1 of them).
    pub fn points(&self) -> Vec<[f64; 3]> {
        (0..=self.steps)
            .map(|k| {
                let t = k as f64 / self.steps as f64;
                [0, 1, 2].map(|i| self.start_mm[i] + t * (self.end_mm[i] - self.start_mm[i]))
            })
            .collect()
    }

    /// Unit direction of the line.
    pub fn direction(&self) -> [f64; 3] {
        let d = [0, 1, 2].map(|i| self.end_mm[i] - self.start_mm[i]);
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        d.map(|v| v / n)
    }
}

/// Names of the built-in designs.
pub const LINE_PRESETS: &[&str] = &["nine-line", "fifteen-line"];

/// A built-in design for a three-axis machine with axes X, Y, Z, inset `margin_mm` from the
/// travel ends, `steps` intervals per line.
pub fn line_preset(
    name: &str,
    machine: &Machine,
    steps: usize,
    margin_mm: f64,
) -> Option<Vec<LineSpec>> {
    let t = |a: Axis| {
        let tr = machine.travel(a);
        [tr[0] + margin_mm, tr[1] - margin_mm]
    };
    if ![Axis::X, Axis::Y, Axis::Z]
        .iter()
        .all(|a| machine.axes.contains(a))
    {
        return None;
    }
    let (x, y, z) = (t(Axis::X), t(Axis::Y), t(Axis::Z));
    let axial = |name: &str, a: usize, fixed: [f64; 3], range: [f64; 2]| {
        let mut s = fixed;
        let mut e = fixed;
        s[a] = range[0];
        e[a] = range[1];
        let mut ch = vec![[0.0; 3]; 3];
        for (k, c) in ch.iter_mut().enumerate() {
            c[(a + k) % 3] = 1.0;
        }
        LineSpec {
            name: name.into(),
            start_mm: s,
            end_mm: e,
            steps,
            channels: ch,
        }
    };
    let diagonal = |name: &str, s: [f64; 3], e: [f64; 3]| {
        let mut l = LineSpec {
            name: name.into(),
            start_mm: s,
            end_mm: e,
            steps,
            channels: vec![],
        };
        l.channels = vec![l.direction()];
        l
    };
    let mut lines = vec![
        axial("X1", 0, [0.0, y[0], z[0]], x),
        axial("X2", 0, [0.0, y[1], z[0]], x),
        axial("X3", 0, [0.0, y[0], z[1]], x),
        axial("Y1", 1, [x[0], 0.0, z[0]], y),
        axial("Y2", 1, [x[0], 0.0, z[1]], y),
        axial("Z1", 2, [x[0], y[0], 0.0], z),
        diagonal("XY", [x[0], y[0], z[0]], [x[1], y[1], z[0]]),
        diagonal("XZ", [x[0], y[0], z[0]], [x[1], y[0], z[1]]),
        diagonal("YZ", [x[0], y[0], z[0]], [x[0], y[1], z[1]]),
    ];
    match name {
        "nine-line" => {}
        "fifteen-line" => {
            lines.push(diagonal("XY-", [x[0], y[1], z[0]], [x[1], y[0], z[0]]));
            lines.push(diagonal("XZ-", [x[0], y[0], z[1]], [x[1], y[0], z[0]]));
            lines.push(diagonal("YZ-", [x[0], y[0], z[1]], [x[0], y[1], z[0]]));
            lines.push(axial("X4", 0, [0.0, y[1], z[1]], x));
            lines.push(axial("Y3", 1, [x[1], 0.0, z[1]], y));
            lines.push(axial("Z2", 2, [x[1], y[1], 0.0], z));
        }
        _ => return None,
    }
    Some(lines)
}
