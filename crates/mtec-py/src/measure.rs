//! ISO 230-2 positioning statistics and ISO 230-4 circular tests (mtec-measure).

use crate::columns::{as_path, read_table};
use crate::convert::serde_to_py;
use crate::errors::{choice, Result};
use mtec_workflow::ops::circular as circular_op;
use mtec_workflow::ops::iso230_2 as iso_op;
use pyo3::prelude::*;
use std::path::PathBuf;

/// ISO 230-2:2014 positioning statistics of a linear axis, and the VDI/DGQ 3441 values: the
/// library behind `mtec iso230-2`.
///
/// `data` is the run file (CSV path with `target_mm,run,direction,deviation_um`) or a mapping
/// with these four columns (`direction` holds `"+"` or `"-"`). The environmental corrections
/// of the readings (docs/methods.md §2.1), as the CLI's options: the air the laser measured in
/// (`air_temp_c`, `pressure_pa`, `humidity_pct`, all three; `co2_ppm`; `wavelength_nm`, a HeNe
/// laser by default; `air_formula` `ciddor`, `edlen` (Birch & Downs) or `bonsch-potulski`;
/// `laser_n`, the index the laser used, by default the formula's at 20 °C, 101325 Pa, 50 %)
/// and the ISO 1 normalisation to 20 °C (`material_temp_c` and `alpha_um_per_m_k`, both).
/// `standard`: `iso230-2:2014`, `vdi-3441` or `all` (their axis values side by side in
/// `standards`). `out` (a folder) also gets the CLI's iso230-2.json.
///
/// Returns the document `mtec iso230-2 --json` prints (`format` `mtec.iso230-2/1`): the axis
/// values (`A_um`, `E_um`, `R_um`, `B_um`, `M_um`, ... in µm), `targets` and
/// `vdi3441["targets"]` as dicts of numpy arrays (one entry per target position), `runs_up`,
/// `runs_down`, `corrections` (each correction applied, in ppm, and the `scale_factor` of the
/// positions) and `warnings` (what ISO 230-2 asks for that the data does not meet). Raises
/// `mtec.InputError` at the offending row.
///
/// >>> import mtec
/// >>> r = mtec.iso230_2({"target_mm": [0, 10, 0, 10, 0, 10, 0, 10],
/// ...                    "run": [1, 1, 2, 2, 1, 1, 2, 2],
/// ...                    "direction": ["+", "+", "+", "+", "-", "-", "-", "-"],
/// ...                    "deviation_um": [1, 2, 3, 4, 0, 1, 1, 2]})
/// >>> r["B_um"], r["targets"]["mean_up_um"].tolist()
/// (1.5, [2.0, 3.0])
/// >>> runs = {"target_mm": [0, 1000] * 4, "run": [1, 1, 2, 2] * 2,
/// ...         "direction": ["+"] * 4 + ["-"] * 4, "deviation_um": [0.0] * 8}
/// >>> warm = mtec.iso230_2(runs, material_temp_c=21.0, alpha_um_per_m_k=11.5)  # 1 K warm
/// >>> round(warm["corrections"]["material"]["correction_ppm"], 3), round(warm["E_um"], 3)
/// (-11.5, 11.5)
#[pyfunction]
#[pyo3(signature = (data, *, air_temp_c = None, pressure_pa = None, humidity_pct = None,
    co2_ppm = 450.0, wavelength_nm = None, air_formula = "ciddor", laser_n = None,
    material_temp_c = None, alpha_um_per_m_k = None, standard = iso_op::DEFAULT_STANDARD,
    out = None))]
#[allow(clippy::too_many_arguments)]
pub fn iso230_2<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    air_temp_c: Option<f64>,
    pressure_pa: Option<f64>,
    humidity_pct: Option<f64>,
    co2_ppm: f64,
    wavelength_nm: Option<f64>,
    air_formula: &str,
    laser_n: Option<f64>,
    material_temp_c: Option<f64>,
    alpha_um_per_m_k: Option<f64>,
    standard: &str,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let run = || -> Result<Bound<'py, PyAny>> {
        let table = read_table(data, "data")?;
        let defaults = iso_op::Options::new(&table.path);
        let opts = iso_op::Options {
            out,
            air_temp_c,
            pressure_pa,
            humidity_pct,
            co2_ppm,
            wavelength_nm: wavelength_nm.unwrap_or(defaults.wavelength_nm),
            air_formula: choice("air_formula", air_formula)?,
            laser_n,
            material_temp_c,
            alpha_um_per_m_k,
            standard: standard.to_string(),
            ..defaults
        };
        let outcome =
            py.detach(|| iso_op::run_table(&table, &opts, &mut mtec_workflow::Collect::default()))?;
        serde_to_py(py, &outcome)
    };
    Ok(run()?)
}

/// An ISO 230-4 circular test of two linear axes (ballbar) and its diagnostics: the library
/// behind `mtec circular`.
///
/// `run` is the trace (CSV path with `angle_deg,direction,dl_um`, `direction` `ccw` or `cw`,
/// and header comments `# radius_mm = 100`, `# plane = XY`, `# feed_mm_min = 1000`; or a
/// mapping of those three columns). `radius_mm`, `plane` (`XY`, `YZ`, `ZX`), `feed_mm_min`
/// (needed for the servo mismatch in ms) override the header; arrays have no header, so they
/// need `radius_mm`. `arc_start_deg` and `arc_end_deg` (both or neither) evaluate a partial arc
/// traced ccw from start to end (at least 90°); `threshold_um` is the contribution from which a
/// fault is reported as present. `out` (a folder) also gets circular.json and polar.svg.
///
/// Returns the document `mtec circular --json` prints (`mtec.circular/1`): `radius_mm`,
/// `plane`, `samples`, `iso230_4` (circular deviation `G_um` of each direction and
/// bidirectional, hysteresis `H_um`, the least-squares circles) and `diagnostics` (the faults
/// ranked by contribution: backlash, lateral play, squareness, scale mismatch, straightness,
/// cyclic error, servo mismatch, ...).
///
/// >>> import mtec, numpy as np
/// >>> a = np.arange(0.0, 360.0, 1.0)
/// >>> dl = 3.0 * np.cos(np.radians(2 * a))       # an ellipse: ±3 µm
/// >>> r = mtec.circular({"angle_deg": np.concatenate([a, a]),
/// ...                    "direction": ["ccw"] * 360 + ["cw"] * 360,
/// ...                    "dl_um": np.concatenate([dl, dl])}, radius_mm=150.0)
/// >>> round(r["iso230_4"]["G_bidirectional_um"], 6), round(r["iso230_4"]["H_um"], 6)
/// (6.0, 0.0)
/// >>> f = r["diagnostics"]["faults"][0]      # 2·3 µm over 150 mm: 40 ppm between the axes
/// >>> f["id"], round(f["value"], 6), f["unit"]
/// ('scale_mismatch', 40.0, 'ppm')
#[pyfunction]
#[pyo3(signature = (run, *, radius_mm = None, plane = None, feed_mm_min = None,
    arc_start_deg = None, arc_end_deg = None, threshold_um = 0.3, out = None))]
#[allow(clippy::too_many_arguments)]
pub fn circular<'py>(
    py: Python<'py>,
    run: &Bound<'py, PyAny>,
    radius_mm: Option<f64>,
    plane: Option<String>,
    feed_mm_min: Option<f64>,
    arc_start_deg: Option<f64>,
    arc_end_deg: Option<f64>,
    threshold_um: f64,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let arc = [arc_start_deg, arc_end_deg];
    let given = CircularArgs {
        radius_mm,
        plane,
        feed_mm_min,
        arc,
        threshold_um,
        out,
    };
    Ok(evaluate_circular(py, run, given)?)
}

/// The keyword arguments of [`circular`].
struct CircularArgs {
    radius_mm: Option<f64>,
    plane: Option<String>,
    feed_mm_min: Option<f64>,
    arc: [Option<f64>; 2],
    threshold_um: f64,
    out: Option<PathBuf>,
}

fn evaluate_circular<'py>(
    py: Python<'py>,
    run: &Bound<'py, PyAny>,
    a: CircularArgs,
) -> Result<Bound<'py, PyAny>> {
    // the output files are settled before any work: neither is the trace file
    if let (Some(dir), Some(trace)) = (&a.out, as_path(run)?) {
        circular_op::check_out_dir(dir, &trace)?;
    }
    let table = read_table(run, "run")?;
    let opts = circular_op::Options {
        radius_mm: a.radius_mm,
        feed_mm_min: a.feed_mm_min,
        plane: a
            .plane
            .as_deref()
            .map(circular_op::parse_plane)
            .transpose()?,
        arc_deg: circular_op::arc_deg(a.arc[0], a.arc[1])?,
        threshold_um: a.threshold_um,
        out: a.out,
        ..circular_op::Options::new(&table.path)
    };
    let outcome = py.detach(|| circular_op::run_table(&table, &opts))?;
    serde_to_py(py, &outcome)
}
