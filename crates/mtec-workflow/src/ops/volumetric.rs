//! The volumetric error of the tool tip at commanded points, from a machine and its error set
//! (`mtec_model::VolumetricModel`, HTM or POE, exact or first-order). The job of
//! `mtec volumetric`.

use crate::inputs::{pose_column, read_errors, read_machine, read_poses};
use crate::{Observer, Result};
use mtec_io::CsvWriter;
use mtec_model::{Formalism, Order, VolumetricModel};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};
use std::fmt;
use std::path::PathBuf;

/// The format tag of the outcome.
pub const FORMAT: &str = "mtec.volumetric/1";

/// Formalism and order of the error model (all four agree to first order; HTM and POE exactly).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Form {
    /// Homogeneous transformation matrices, exact rigid-body.
    HtmExact,
    /// Homogeneous transformation matrices, first-order.
    HtmFirst,
    /// Product of exponentials (screw theory), exact.
    PoeExact,
    /// Product of exponentials, first-order.
    PoeFirst,
}

impl Form {
    /// The model's formalism and order.
    pub fn formalism_order(self) -> (Formalism, Order) {
        match self {
            Form::HtmExact => (Formalism::Htm, Order::Exact),
            Form::HtmFirst => (Formalism::Htm, Order::FirstOrder),
            Form::PoeExact => (Formalism::Poe, Order::Exact),
            Form::PoeFirst => (Formalism::Poe, Order::FirstOrder),
        }
    }
}

/// What to evaluate.
#[derive(Debug, Clone)]
pub struct Options {
    /// Machine description (TOML).
    pub machine: PathBuf,
    /// Error set (JSON `mtec.errors/1`, or a simulation's `truth.json`).
    pub errors: PathBuf,
    /// Commanded points (CSV with one column per machine axis: `x_mm`, ..., `c_deg`).
    pub points: PathBuf,
    /// Formalism and order.
    pub form: Form,
}

impl Options {
    /// Exact HTM, as `mtec volumetric` defaults to.
    pub fn new(
        machine: impl Into<PathBuf>,
        errors: impl Into<PathBuf>,
        points: impl Into<PathBuf>,
    ) -> Options {
        Options {
            machine: machine.into(),
            errors: errors.into(),
            points: points.into(),
            form: Form::HtmExact,
        }
    }
}

/// A commanded pose: the axis positions under their column names (`x_mm`, ..., `c_deg`), in
/// the machine's axis order; serialised as a map.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose(pub Vec<(String, f64)>);

impl Serialize for Pose {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// The error at one commanded point.
#[derive(Debug, Clone, Serialize)]
pub struct Point {
    /// The commanded pose (mm, deg).
    #[serde(flatten)]
    pub pose: Pose,
    /// Tool-tip error along X relative to the workpiece (µm).
    pub ex_um: f64,
    /// Along Y (µm).
    pub ey_um: f64,
    /// Along Z (µm).
    pub ez_um: f64,
    /// Orientation error about X, Y, Z (µrad); for chains with rotary axes only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation_urad: Option<[f64; 3]>,
}

/// The result: `mtec.volumetric/1` (docs/formats.md).
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// `mtec.volumetric/1`.
    pub format: String,
    /// The formalism and order used.
    pub form: Form,
    /// One record per commanded point, in the file's order.
    pub points: Vec<Point>,
    /// The pose columns in the machine's axis order (the CSV header).
    #[serde(skip)]
    pub columns: Vec<String>,
    /// True when the chain has a rotary axis (the orientation error is given).
    #[serde(skip)]
    pub rotary: bool,
}

impl Outcome {
    /// The outcome as the pretty JSON text `mtec volumetric --json` prints (keys sorted).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(&serde_json::to_value(self)?)?)
    }
}

/// Evaluates the error set's volumetric error at every point of `opts.points`.
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    let machine = read_machine(&opts.machine)?;
    let errors = read_errors(&opts.errors)?;
    let poses = read_poses(&opts.points, &machine)?;
    let (f, o) = opts.form.formalism_order();
    let vm = VolumetricModel::new(&machine, &errors);
    let rotary = machine.axes.iter().any(|a| a.is_rotary());
    let columns: Vec<String> = machine.axes.iter().map(|a| pose_column(*a)).collect();
    let points = poses
        .iter()
        .map(|q| {
            let v = vm.error(q, f, o);
            Point {
                pose: Pose(columns.iter().cloned().zip(q.iter().copied()).collect()),
                ex_um: v.position_um[0],
                ey_um: v.position_um[1],
                ez_um: v.position_um[2],
                orientation_urad: rotary.then_some(v.orientation_urad),
            }
        })
        .collect();
    Ok(Outcome {
        format: FORMAT.into(),
        form: opts.form,
        points,
        columns,
        rotary,
    })
}

/// The CSV `mtec volumetric` prints: the pose, `ex_um,ey_um,ez_um` (4 decimals) and, with a
/// rotary axis, `eax_urad,eay_urad,eaz_urad` (3 decimals).
impl fmt::Display for Outcome {
    fn fmt(&self, o: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut header = self.columns.clone();
        header.extend(["ex_um", "ey_um", "ez_um"].map(String::from));
        if self.rotary {
            header.extend(["eax_urad", "eay_urad", "eaz_urad"].map(String::from));
        }
        let mut csv = CsvWriter::new(header);
        for p in &self.points {
            let mut row: Vec<String> = p.pose.0.iter().map(|(_, x)| format!("{x}")).collect();
            row.extend([p.ex_um, p.ey_um, p.ez_um].map(|v| format!("{v:.4}")));
            if let Some(r) = p.orientation_urad {
                row.extend(r.map(|v| format!("{v:.3}")));
            }
            csv.row(row);
        }
        o.write_str(&csv.finish())?;
        Ok(())
    }
}
