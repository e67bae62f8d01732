//! Controller compensation tables (mtec-comp's writers): the job of `mtec compensate table`.

use crate::convert::serde_to_py;
use crate::errors::{choice, refuse_stdout, usage, Result};
use mtec_workflow::ops::compensate_table::{self as op, Format, Options, Range};
use mtec_workflow::ops::selective::Elements;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Writes a controller's compensation table: the library behind `mtec compensate table`.
///
/// `format` is the controller's (`linuxcnc` COMP_FILE, `sinumerik-cec`, `sinumerik-lec`,
/// `fanuc` pitch error tape, `heidenhain` .COM with its .CMA beside it, `beckhoff` volumetric
/// grid); `out` the table file (written atomically, never over an input). The source is
/// either `model` (any model file mtec compensates with: map, kinematic model, BPNN, machine
/// error with `state`) or `from_iso230_2` (an ISO 230-2 run: the direction-dependent table of
/// `axis` at the run's targets, c↑ = −x̄↑ and c↓ = −x̄↓).
///
/// A 1-D table runs along `axis` (`X`, `Y`, `Z`) at positions `range` = (from, to, step) mm
/// (default: the map's grid) with the other axes at `at` = (x, y, z) mm (default: the centre of
/// the map's box); `output_axis` is the compensated axis of cross-axis tables. `elements`
/// (`all`, `key` ranked by EFAST, or a list such as `EXX,EYX`) samples a kinematic model of
/// those elements only. Every value is checked against `max_correction_um` and the format's
/// limits before anything is written. The format options (`comp_type`, `table_index`,
/// `direction`, `max_points`, FANUC's `reference_mm`, `reference_number`, `magnification`,
/// `detection_unit_um`, `max_increment`, `axis_number`, HEIDENHAIN's `cma_name`, Beckhoff's
/// `x_range`, `y_range`, `z_range`) are the CLI's; one the format does not read is refused.
///
/// Returns what was written: `format`, `provenance`, `points`, `out`, `cma` (HEIDENHAIN),
/// `warnings`, `notes`, `reversal_max_um` (from a run) and `selective` (with `elements`).
///
/// >>> import mtec, numpy as np, tempfile, os
/// >>> d = tempfile.mkdtemp()
/// >>> g = np.array([(x, y, z) for x in (0.0, 100.0, 200.0) for y in (0.0, 100.0)
/// ...               for z in (0.0, 50.0)])
/// >>> _ = mtec.map_fit({"x_mm": g[:, 0], "y_mm": g[:, 1], "z_mm": g[:, 2],
/// ...                   "ex_um": 0.02 * g[:, 0], "ey_um": 0 * g[:, 0], "ez_um": 0 * g[:, 0]},
/// ...                  out=os.path.join(d, "map.json"))
/// >>> r = mtec.compensate_table("linuxcnc", os.path.join(d, "x.comp"),
/// ...                           model=os.path.join(d, "map.json"), axis="X")
/// >>> r["points"]
/// 3
/// >>> print(open(os.path.join(d, "x.comp")).read().splitlines()[-1])   # e = 4 µm at X200
/// 200.000000 -0.004000 -0.004000
#[pyfunction]
#[pyo3(signature = (format, out, *, model = None, from_iso230_2 = None, state = None,
    axis = "X", output_axis = None, range = None, at = None, elements = "all",
    max_correction_um = mtec_comp::table::DEFAULT_MAX_CORRECTION_UM, comp_type = 1,
    table_index = 0, direction = 0, max_points = None, reference_mm = 0.0,
    reference_number = 0, magnification = 1, detection_unit_um = 1.0, max_increment = 127,
    axis_number = None, cma_name = "config.cma".to_string(), x_range = None, y_range = None,
    z_range = None))]
#[allow(clippy::too_many_arguments)]
pub fn compensate_table<'py>(
    py: Python<'py>,
    format: &str,
    out: PathBuf,
    model: Option<PathBuf>,
    from_iso230_2: Option<PathBuf>,
    state: Option<PathBuf>,
    axis: &str,
    output_axis: Option<String>,
    range: Option<(f64, f64, f64)>,
    at: Option<(f64, f64, f64)>,
    elements: &str,
    max_correction_um: f64,
    comp_type: u8,
    table_index: usize,
    direction: i8,
    max_points: Option<usize>,
    reference_mm: f64,
    reference_number: u32,
    magnification: u32,
    detection_unit_um: f64,
    max_increment: i64,
    axis_number: Option<u8>,
    cma_name: String,
    x_range: Option<(f64, f64, f64)>,
    y_range: Option<(f64, f64, f64)>,
    z_range: Option<(f64, f64, f64)>,
) -> PyResult<Bound<'py, PyAny>> {
    let range_of = |r: Option<(f64, f64, f64)>| r.map(|(a, b, c)| Range::new(a, b, c)).transpose();
    let opts = || -> Result<Options> {
        let format = choice::<Format>("format", format)?;
        refuse_stdout(&out, "out")?;
        let model = match (model, &from_iso230_2) {
            (Some(m), None) => m,
            (None, Some(_)) => PathBuf::new(),
            _ => return Err(usage("give `model` or `from_iso230_2` (exactly one)")),
        };
        Ok(Options {
            axis: op::parse_axis("axis", axis)?,
            output_axis: output_axis
                .as_deref()
                .map(|s| op::parse_axis("output_axis", s))
                .transpose()?,
            range: range_of(range)?,
            at: at.map(|(x, y, z)| op::checked_at([x, y, z])).transpose()?,
            grid: [range_of(x_range)?, range_of(y_range)?, range_of(z_range)?],
            from_iso230_2,
            state,
            comp_type,
            table_index,
            direction,
            max_points,
            reference_mm,
            reference_number,
            magnification,
            detection_unit_um,
            max_increment,
            axis_number,
            cma_name,
            max_correction_um,
            elements: elements.parse::<Elements>().map_err(usage)?,
            ..Options::new(model, format, Some(out))
        })
    };
    let opts = opts()?;
    let outcome = py
        .detach(|| op::run(&opts, &mut mtec_workflow::Collect::default()))
        .map_err(crate::errors::Failure::from)?;
    Ok(serde_to_py(py, &outcome)?)
}
