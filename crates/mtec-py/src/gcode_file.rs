//! An NC program file compensated as `mtec compensate gcode` does it, with everything the
//! command has: tool tables, the block delete switch, selective elements and flattening through
//! LinuxCNC's interpreter (`compensate_gcode` in [`crate::comp`] rewrites program text in memory
//! and has none of these, which read files beside the program).

use crate::convert::serde_to_py;
use crate::errors::{choice, refuse_stdout, usage, Result};
use mtec_comp::gcode::RewriteOptions;
use mtec_workflow::ops::compensate_gcode::{self as op, Options};
use mtec_workflow::ops::selective::Elements;
use mtec_workflow::rs274::Rs274;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Compensates an NC program file into `output`: the library behind `mtec compensate gcode`,
/// byte for byte.
///
/// `input` is the program, `model` any model file mtec compensates with (`state`: the log that
/// brings a model with a state to now), `output` the compensated program (written atomically,
/// never over an input; the CLI's `-` for stdout is refused). Beyond `compensate_gcode`'s
/// options (`tolerance_um`, `max_segment_mm`, `chord_tolerance_um`, `max_correction_um`,
/// `on_unsupported`, `default_units`, `start_position_mm`, `offsets`): `tool_table` (LinuxCNC's
/// G43 lengths) in `machine_units`; `block_delete` True (skip `/` blocks), False (run them) or
/// None (refuse a `/` block that moves or sets a mode); `elements` (`all`, `key` or a list such
/// as `EXX,EYX`) of a kinematic model; `decimals_mm`, `decimals_inch`, `check_step_mm`,
/// `start_rotary_deg`, `check_step_deg`, `max_line_chars`; and `flatten_with="rs274"`, which
/// runs the program through LinuxCNC's interpreter first (subroutines, loops, canned cycles;
/// `rs274` the binary, `var_file` its parameter file, `rs274_timeout_s`).
///
/// Returns the report `mtec compensate gcode` prints: `report` (`lines_read`,
/// `lines_written`, `moves_compensated`, `max_correction_um`, ...), `source`, `output`,
/// `flattened`, `warnings`, `notes`, `selective`. A block mtec cannot compensate raises
/// `mtec.InputError` at its file, line and column.
///
/// >>> import mtec, tempfile, os
/// >>> d = tempfile.mkdtemp()
/// >>> _ = mtec.map_fit({"x_mm": [0, 100], "y_mm": [0, 0], "z_mm": [0, 0],
/// ...                   "ex_um": [0, 10], "ey_um": [0, 0], "ez_um": [0, 0]},
/// ...                  out=os.path.join(d, "map.json"))
/// >>> prog = os.path.join(d, "part.ngc")
/// >>> _ = open(prog, "w").write("G21 G90\nG0 X0 Y0 Z0\n/G1 X80 F100\nG1 X50 F100\nM2\n")
/// >>> r = mtec.compensate_gcode_file(prog, os.path.join(d, "map.json"),
/// ...                                os.path.join(d, "out.ngc"), block_delete=True)
/// >>> r["report"]["moves_compensated"], open(os.path.join(d, "out.ngc")).read().splitlines()[-2]
/// (1, 'G1 X49.995')
#[pyfunction]
#[pyo3(signature = (input, model, output, *, state = None, offsets = None, tool_table = None,
    machine_units = "mm", block_delete = None, elements = "all", tolerance_um = 0.5,
    max_segment_mm = 10.0, chord_tolerance_um = 0.5, max_correction_um = 500.0,
    on_unsupported = "refuse", default_units = "mm", decimals_mm = None, decimals_inch = None,
    start_position_mm = None, check_step_mm = 0.5, start_rotary_deg = None, check_step_deg = 0.5,
    max_line_chars = 251, flatten_with = None, rs274 = None, var_file = None,
    rs274_timeout_s = None))]
#[allow(clippy::too_many_arguments)]
pub fn compensate_gcode_file<'py>(
    py: Python<'py>,
    input: PathBuf,
    model: PathBuf,
    output: PathBuf,
    state: Option<PathBuf>,
    offsets: Option<PathBuf>,
    tool_table: Option<PathBuf>,
    machine_units: &str,
    block_delete: Option<bool>,
    elements: &str,
    tolerance_um: f64,
    max_segment_mm: f64,
    chord_tolerance_um: f64,
    max_correction_um: f64,
    on_unsupported: &str,
    default_units: &str,
    decimals_mm: Option<usize>,
    decimals_inch: Option<usize>,
    start_position_mm: Option<[f64; 3]>,
    check_step_mm: f64,
    start_rotary_deg: Option<[f64; 3]>,
    check_step_deg: f64,
    max_line_chars: usize,
    flatten_with: Option<String>,
    rs274: Option<PathBuf>,
    var_file: Option<PathBuf>,
    rs274_timeout_s: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let run = || -> Result<Bound<'py, PyAny>> {
        refuse_stdout(&output, "output")?;
        let flatten = match flatten_with.as_deref() {
            Some("rs274") => Some(Rs274 {
                bin: rs274,
                var_file,
                timeout_s: rs274_timeout_s.unwrap_or(Rs274::default().timeout_s),
            }),
            Some(other) => {
                return Err(usage(format!(
                    "flatten_with `{other}`: expected rs274 (LinuxCNC's interpreter)"
                )))
            }
            None if rs274.is_some() || var_file.is_some() || rs274_timeout_s.is_some() => {
                return Err(usage(
                    "rs274, var_file and rs274_timeout_s go with flatten_with=\"rs274\"",
                ))
            }
            None => None,
        };
        let base = RewriteOptions::with_tolerance(tolerance_um);
        let rewrite = RewriteOptions {
            max_segment_mm,
            chord_tolerance_um,
            max_correction_um,
            on_unsupported: choice("on_unsupported", on_unsupported)?,
            default_units: choice("default_units", default_units)?,
            decimals_mm: decimals_mm.unwrap_or(base.decimals_mm),
            decimals_inch: decimals_inch.unwrap_or(base.decimals_inch),
            check_step_mm,
            check_step_deg,
            max_line_chars,
            start_position_mm,
            start_rotary_deg,
            ..base
        };
        let opts = Options {
            state,
            rewrite,
            offsets,
            tool_table,
            machine_units: choice("machine_units", machine_units)?,
            block_delete,
            flatten,
            elements: elements.parse::<Elements>().map_err(usage)?,
            ..Options::new(model, input, output)
        };
        let outcome = py.detach(|| op::run(&opts, &mut mtec_workflow::Collect::default()))?;
        serde_to_py(py, &outcome)
    };
    Ok(run()?)
}
