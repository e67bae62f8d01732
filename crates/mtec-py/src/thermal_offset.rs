//! Thermal models at the machine (mtec-comp's thermal_offset): the work-offset update, or the
//! Siemens temperature-compensation data, for the state the temperature log ends in; the job of
//! `mtec compensate thermal-offset`.

use crate::columns::{as_path, path_arg, read_table};
use crate::convert::{serde_to_py, write_output};
use crate::errors::{choice, Result};
use mtec_workflow::ops::compensate_table::parse_axis;
use mtec_workflow::ops::compensate_thermal_offset::{self as op, Format, Options};
use pyo3::prelude::*;
use std::path::PathBuf;

/// The work-offset update for the thermal drift now (or Siemens temperature-compensation
/// setting data): the library behind `mtec compensate thermal-offset`.
///
/// `model` is a machine error model (`mtec.machine-error/1`, its thermal parts with axis, sign
/// and envelope) or a bare thermal model (`mtec.thermal-model/1`) with `training` (its training
/// log, a path: the envelope is the range of every input in it) and `sign` (1 if its target is
/// the tool's displacement along +axis, -1 if opposite). `temps` is the temperature log up to
/// now (CSV path or mapping: `time_min` and the model's inputs); its last row is now, the rows
/// before it carry the model's filters (`starts_at_rest`: the first row is the machine in
/// equilibrium with the room). `format`: `g10` (LinuxCNC `G10 L2`), `fanuc` (`G10 L2`),
/// `fanuc-macro` (system variables), `sinumerik` (a settable frame), `sinumerik-sd` (SD43900
/// temperature compensation: offset and slope over `travel_mm`). `axis` (`X`, `Y`, `Z`),
/// `offset` (g10 P0-P9, 1 = G54; fanuc 1-6; sinumerik frame), `base_mm` (g10/fanuc: the
/// offset's value with no drift, or when it was set at `zeroed_at_min`), `at_mm` (the machine
/// position the offset is used at, when the drift depends on position). Outside the training
/// envelope now, `outside="refuse"` raises, `"fade"` scales the update down to none; an update
/// above `max_correction_um` is refused. Options the format does not read are refused.
///
/// Returns the document of the update: `format`, `axis`, `update` (`drift_um`,
/// `correction_um`, `weight`, `at_mm`, `position_dependent`) or `setting` (sinumerik-sd),
/// `text` (the lines for the controller), `now_line`, `now_time_min`, `earlier_outside`,
/// `notes`; `out` (a file) also gets the text.
///
/// >>> import mtec, numpy as np, tempfile, os
/// >>> d = tempfile.mkdtemp()
/// >>> t = np.arange(0.0, 240.0, 2.0)
/// >>> s1 = 20 + 5 * (1 - np.exp(-t / 60))
/// >>> log = os.path.join(d, "log.csv")
/// >>> np.savetxt(log, np.column_stack([t, s1, 2 * (s1 - 20)]), delimiter=",",
/// ...            header="time_min,s1_c,dz_um", comments="")
/// >>> _ = mtec.thermal_fit(log, "dz_um", "mlr", out=os.path.join(d, "m.json"))
/// >>> r = mtec.compensate_thermal_offset(os.path.join(d, "m.json"),
/// ...     {"time_min": [0.0, 60.0], "s1_c": [20.0, 23.0]}, "g10", training=log, sign=1.0,
/// ...     base_mm=-312.45)
/// >>> round(r["update"]["drift_um"], 6), r["text"].splitlines()[-1]    # 2 µm/K · 3 K
/// (6.0, 'G10 L2 P1 Z-312.456')
#[pyfunction]
#[pyo3(signature = (model, temps, format = "g10", *, axis = "Z", offset = 1, base_mm = None,
    at_mm = None, position_origin_mm = 0.0, zeroed_at_min = None, starts_at_rest = false,
    outside = "refuse", max_correction_um = mtec_comp::table::DEFAULT_MAX_CORRECTION_UM,
    training = None, sign = None, axis_number = None, machine_axis = None, travel_mm = None,
    comp_add_velo_factor = None, out = None))]
#[allow(clippy::too_many_arguments)]
pub fn compensate_thermal_offset<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    temps: &Bound<'py, PyAny>,
    format: &str,
    axis: &str,
    offset: u32,
    base_mm: Option<f64>,
    at_mm: Option<f64>,
    position_origin_mm: f64,
    zeroed_at_min: Option<f64>,
    starts_at_rest: bool,
    outside: &str,
    max_correction_um: f64,
    training: Option<PathBuf>,
    sign: Option<f64>,
    axis_number: Option<u32>,
    machine_axis: Option<String>,
    travel_mm: Option<(f64, f64)>,
    comp_add_velo_factor: Option<f64>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let update = || -> Result<Bound<'py, PyAny>> {
        let model = path_arg(model, "model")?;
        // the output is settled before any work: never one of the inputs
        let mut inputs = vec![model.clone()];
        inputs.extend(as_path(temps)?);
        inputs.extend(training.clone());
        if let Some(p) = &out {
            mtec_io::OutputGuard::new(&inputs).check(p)?;
        }
        let log = read_table(temps, "temps")?;
        let format = choice::<Format>("format", format)?;
        let defaults = Options::new(&model, &log.path, format);
        let opts = Options {
            axis: parse_axis("axis", axis)?,
            offset,
            base_mm,
            at_mm,
            position_origin_mm,
            zeroed_at_min,
            starts_at_rest,
            outside: choice("outside", outside)?,
            max_correction_um,
            sign,
            axis_number,
            machine_axis,
            travel_mm: travel_mm.map(|(a, b)| [a, b]),
            comp_add_velo_factor: comp_add_velo_factor.unwrap_or(defaults.comp_add_velo_factor),
            out: out.clone(),
            training: training.clone(),
            ..defaults
        };
        let outcome = py.detach(|| op::update_now(&opts, &log))?;
        if let Some(p) = &out {
            write_output(p, &inputs, outcome.text.as_bytes())?;
        }
        serde_to_py(py, &outcome)
    };
    Ok(update()?)
}
