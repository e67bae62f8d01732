//! Controller compensation tables: from an [`ErrorModel`] to the files a CNC loads.
//!
//! Every writer works from sampled compensation values and runs a constraint checker on what it
//! wrote (the rules each controller documents: point counts, ordering, equal spacing, value
//! ranges, sum-to-zero of rotary axes), so a table mtec writes is one the controller accepts.
//!
//! Sign conventions (each format's module says which documented rule it follows):
//! - mtec's models give the error e (µm): the tool reaches p + e when commanded to p. The
//!   compensation value is c = −e ("compensation values = the negative of the predicted error",
//!   SPEC §1, method C), sampled at the nominal table positions. (Solving p + e(p) = t instead
//!   would change c by e·∂e/∂p ≈ 10⁻⁵·e, far below any table's resolution.)
//! - LinuxCNC type 1, Siemens CEC, FANUC: the value is the correction added to the command, i.e.
//!   c. LinuxCNC type 0 stores the actual position nominal + e. Siemens LEC (`$AA_ENC_COMP`): a
//!   positive value moves the axis negative, so the value written is −c = e. HEIDENHAIN: the axis
//!   error e (mtec's reading of the manuals, see its module).
//!   Beckhoff/ISG volumetric compensation takes the error parameters themselves (e, in mm) and
//!   compensates them.
//!
//! Units: positions mm, values mm (µm in Fanuc detection units), as each format demands.
//!
//! Size bound (issue 15, defect 7): no writer formats a value before it has passed
//! [`check_correction`], the same rule as `compensate gcode --max-correction-um`
//! ([`DEFAULT_MAX_CORRECTION_UM`] unless told): a 1-D table is refused when a value |c| exceeds
//! the limit, a Beckhoff volumetric table when the length of the correction vector (ex, ey, ez)
//! does, and every table when a value is not finite. A 10 mm "trim" is a model in the wrong units
//! or a broken fit, never a correction a machine should be given. The 1-D writers check the
//! [`AxisProfile`] they are handed (its `max_correction_um`), so a profile built by hand is held
//! to the same bound as a sampled one.

pub mod beckhoff;
pub mod bidirectional;
pub mod fanuc;
pub mod heidenhain;
pub mod linuxcnc;
pub mod sinumerik;

use crate::ErrorModel;

/// Default largest correction a table may hold (µm), the default of `compensate gcode
/// --max-correction-um` too.
pub const DEFAULT_MAX_CORRECTION_UM: f64 = 500.0;

/// A machine axis of the Cartesian error models.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// 0, 1, 2 for X, Y, Z.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
    /// `X`, `Y` or `Z`.
    pub fn letter(self) -> char {
        ['X', 'Y', 'Z'][self.index()]
    }
    /// Parses `X`/`x`, `Y`/`y`, `Z`/`z`.
    pub fn parse(s: &str) -> Option<Axis> {
        match s {
            "X" | "x" => Some(Axis::X),
            "Y" | "y" => Some(Axis::Y),
            "Z" | "z" => Some(Axis::Z),
            _ => None,
        }
    }
}

/// Compensation values of one output axis at equally spaced positions of one input axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisProfile {
    /// The axis whose position selects the value (base axis, "master").
    pub input_axis: Axis,
    /// The axis that is moved by the value (compensation axis, "slave").
    pub output_axis: Axis,
    /// Position of the first point (mm, or deg for a rotary axis).
    pub start_mm: f64,
    /// Distance between points (> 0).
    pub step_mm: f64,
    /// Compensation value c = −e (µm) at each point.
    pub comp_um: Vec<f64>,
    /// The input axis is rotary (positions in degrees, one turn = the table's range).
    pub rotary: bool,
    /// Largest |value| (µm) a writer accepts ([`DEFAULT_MAX_CORRECTION_UM`] from
    /// [`axis_profile`]); see [`check_correction`].
    pub max_correction_um: f64,
    /// The coordinates of the other axes (mm) the values were sampled at (for error messages).
    pub at_mm: [f64; 3],
}

impl AxisProfile {
    /// Position of point `n`.
    pub fn position(&self, n: usize) -> f64 {
        self.start_mm + self.step_mm * n as f64
    }
    /// Position of the last point.
    pub fn end_mm(&self) -> f64 {
        self.position(self.comp_um.len().saturating_sub(1))
    }
    /// Machine point of table point `n`: `at_mm` with the input axis at [`Self::position`].
    pub fn point_mm(&self, n: usize) -> [f64; 3] {
        let mut p = self.at_mm;
        p[self.input_axis.index()] = self.position(n);
        p
    }
    /// The same profile with another size bound (µm).
    pub fn with_max_correction_um(mut self, max_um: f64) -> Self {
        self.max_correction_um = max_um;
        self
    }
    /// The values, once each has passed [`check_correction`]; every 1-D writer starts here.
    pub fn checked_values(&self) -> Result<&[f64], TableError> {
        for (n, &c) in self.comp_um.iter().enumerate() {
            check_correction(
                self.output_axis,
                Some((self.input_axis, self.position(n))),
                self.point_mm(n),
                c,
                c.abs(),
                self.max_correction_um,
            )?;
        }
        Ok(&self.comp_um)
    }
}

/// Most points one axis of a table may have: far beyond any controller's table (FANUC numbers
/// its points up to 1023 on many models), and a bound on the memory a range can ask for.
pub const MAX_TABLE_POINTS: usize = 100_000;

/// `--max-correction-um`: positive and at most
/// [`mtec_io::plausible::MAX_CORRECTION_LIMIT_UM`] (a huge limit would switch the size rule off).
pub fn check_max_correction(max_um: f64) -> Result<(), String> {
    use mtec_io::plausible::{positive_option, MAX_CORRECTION_LIMIT_UM};
    positive_option("--max-correction-um", max_um, MAX_CORRECTION_LIMIT_UM, "um").map(|_| ())
}

/// The number of intervals of a table range FROM..TO step STEP: machine positions for ends,
/// a whole number of steps, at least one interval and at most [`MAX_TABLE_POINTS`] − 1.
pub fn range_intervals(from_mm: f64, to_mm: f64, step_mm: f64) -> Result<usize, String> {
    use mtec_io::plausible::position_option;
    position_option("the table range's start", from_mm)?;
    position_option("the table range's end", to_mm)?;
    if step_mm.is_nan() || step_mm <= 0.0 || to_mm <= from_mm {
        return Err(format!(
            "table range {from_mm}..{to_mm} step {step_mm}: the step must be positive and the end above the start"
        ));
    }
    let intervals = (to_mm - from_mm) / step_mm;
    let n = intervals.round();
    if (intervals - n).abs() > 1e-6 {
        return Err(format!(
            "the range {from_mm}..{to_mm} mm is not a whole number of steps of {step_mm} mm ({intervals:.4} steps)"
        ));
    }
    if n < 1.0 || n >= MAX_TABLE_POINTS as f64 {
        return Err(format!(
            "the range {from_mm}..{to_mm} mm step {step_mm} mm gives {} points: a table needs 2 to {MAX_TABLE_POINTS}",
            n + 1.0
        ));
    }
    Ok(n as usize)
}

/// The one size rule of every table writer: `value_um` (the value of `axis` at `p_mm`) must be
/// finite, and `size_um` (|value| for a 1-D table, the vector length for a volumetric one) at
/// most `max_um`. `table_position` is the input axis and position of a 1-D table point.
/// A limit that is not a positive finite number is refused as such.
pub fn check_correction(
    axis: Axis,
    table_position: Option<(Axis, f64)>,
    p_mm: [f64; 3],
    value_um: f64,
    size_um: f64,
    max_um: f64,
) -> Result<(), TableError> {
    check_max_correction(max_um).map_err(TableError::Sampling)?;
    if value_um.is_finite() && size_um.is_finite() && size_um <= max_um {
        return Ok(());
    }
    Err(TableError::TooLarge {
        axis,
        table_position,
        p_mm,
        value_um,
        size_um,
        max_um,
    })
}

fn too_large_message(
    axis: Axis,
    table_position: &Option<(Axis, f64)>,
    p_mm: &[f64; 3],
    value_um: f64,
    size_um: f64,
    max_um: f64,
) -> String {
    let at = match table_position {
        Some((a, pos)) => format!(
            "table position {} = {pos} mm (machine point {}, {}, {} mm)",
            a.letter(),
            p_mm[0],
            p_mm[1],
            p_mm[2]
        ),
        None => format!("machine point {}, {}, {} mm", p_mm[0], p_mm[1], p_mm[2]),
    };
    let what = format!(
        "the {} correction at {at} is {} um",
        axis.letter(),
        readable(value_um)
    );
    if !value_um.is_finite() || !size_um.is_finite() {
        format!("{what}: not a finite number, no table can hold it")
    } else if table_position.is_none() && size_um != value_um.abs() {
        format!(
            "{what}, the correction vector {} um long: more than --max-correction-um {max_um} um (a model in the wrong units or a broken fit?)",
            readable(size_um)
        )
    } else {
        format!(
            "{what}: more than --max-correction-um {max_um} um (a model in the wrong units or a broken fit?)"
        )
    }
}

/// Why a table cannot be written (or a written table breaks its format's rules).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TableError {
    /// The sampling request is inconsistent.
    #[error("{0}")]
    Sampling(String),
    /// The model has no value where the table needs one.
    #[error("the model has no value at ({:.6}, {:.6}, {:.6}) mm (outside a map that refuses points beyond its grid)", p_mm[0], p_mm[1], p_mm[2])]
    Undefined { p_mm: [f64; 3] },
    /// A value is not finite, or larger than the bound (see [`check_correction`]).
    #[error("{}", too_large_message(*axis, table_position, p_mm, *value_um, *size_um, *max_um))]
    TooLarge {
        /// The axis whose value is refused (the largest component of a volumetric table).
        axis: Axis,
        /// Input axis and position of a 1-D table point.
        table_position: Option<(Axis, f64)>,
        p_mm: [f64; 3],
        value_um: f64,
        /// What was compared with the bound: |value|, or the vector length.
        size_um: f64,
        max_um: f64,
    },
    /// A rule of the target format is broken; `line` is 1-based in the written text when known.
    #[error("{format} table rule broken{}: {message}", line.map(|l| format!(" at line {l}")).unwrap_or_default())]
    Constraint {
        format: &'static str,
        line: Option<usize>,
        message: String,
    },
}

impl TableError {
    pub(crate) fn rule(format: &'static str, line: Option<usize>, msg: impl Into<String>) -> Self {
        TableError::Constraint {
            format,
            line,
            message: msg.into(),
        }
    }
}

/// Samples c = −e_output along the input axis from `start_mm` to `end_mm` (inclusive, which
/// must be a whole number of `step_mm` from the start), the other coordinates at `at_mm`.
pub fn axis_profile(
    model: &dyn ErrorModel,
    input_axis: Axis,
    output_axis: Axis,
    start_mm: f64,
    end_mm: f64,
    step_mm: f64,
    at_mm: [f64; 3],
) -> Result<AxisProfile, TableError> {
    let n = range_intervals(start_mm, end_mm, step_mm).map_err(TableError::Sampling)? + 1;
    let mut comp_um = Vec::with_capacity(n);
    for i in 0..n {
        let mut p = at_mm;
        p[input_axis.index()] = start_mm + step_mm * i as f64;
        let e = model.error_um(p);
        let v = e[output_axis.index()];
        // NaN: no value here (a map beyond its grid); an infinite value is refused by the size
        // rule, which names the axis and the value
        if v.is_nan() {
            return Err(TableError::Undefined { p_mm: p });
        }
        comp_um.push(-v);
    }
    Ok(AxisProfile {
        input_axis,
        output_axis,
        start_mm,
        step_mm,
        comp_um,
        rotary: false,
        max_correction_um: DEFAULT_MAX_CORRECTION_UM,
        at_mm,
    })
}

/// A value for a message: 3 decimals, or scientific notation when huge (`1e297`, not 298 digits).
fn readable(v: f64) -> String {
    if v.is_finite() && v.abs() < 1e9 {
        format!("{v:.3}")
    } else {
        format!("{v:e}")
    }
}

/// A number with at most `decimals` decimals, trailing zeros (and a lone point) removed, and no
/// negative zero: `0.010000` → `0.01`, `-0.0000001` → `0`, `400` → `400`.
pub fn trim_number(v: f64, decimals: usize) -> String {
    let s = format!("{:.*}", decimals, v);
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".to_string()
    } else {
        s
    }
}

/// Like [`trim_number`] but keeps one decimal for whole numbers (`400` → `400.0`), the style of
/// the Siemens examples for positions.
pub fn decimal_number(v: f64, decimals: usize) -> String {
    let s = trim_number(v, decimals);
    if s.contains('.') {
        s
    } else {
        format!("{s}.0")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_formatting() {
        assert_eq!(trim_number(0.01, 6), "0.01");
        assert_eq!(trim_number(-0.0000001, 6), "0");
        assert_eq!(trim_number(400.0, 6), "400");
        assert_eq!(decimal_number(-200.0, 6), "-200.0");
        assert_eq!(decimal_number(6.73, 6), "6.73");
    }
}
