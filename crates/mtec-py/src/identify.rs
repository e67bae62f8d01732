//! Identification (mtec-identify): the 21 error elements of a three-axis machine from laser
//! lines, and the error motions of a rotary C axis from ballbar readings.

use crate::columns::{path_arg, read_table};
use crate::convert::{serde_to_py, to_py, write_output};
use crate::errors::{internal, Result};
use crate::model::read_machine;
use mtec_comp::kinematic::KinematicFile;
use mtec_identify::ballbar::{identify as identify_dbb, BallbarError, Measurements, Setup};
use mtec_identify::lines::{self, Degree, LineData, LinesError, DEFAULT_DEGREE};
use mtec_io::InputError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::json;
use std::path::PathBuf;

/// Identifies the error elements of a three-axis machine from line measurements (9-line method).
///
/// `machine` is the machine TOML; `data` the line file (CSV path, or a mapping with the columns
/// `line,step,x_mm,y_mm,z_mm,ux,uy,uz,reading_um` and optionally `run`, docs/formats.md). Each
/// error motion is a polynomial of `degree` in its axis position (None: chosen per kind of
/// element by cross-validation, as the CLI's default `--degree auto`). Returns a dict: `report` (the
/// document `mtec identify lines --json` prints: rank, condition number, residual RMS, every
/// element with its uncertainty, what the design cannot identify) and `errors` (the identified
/// error set, `mtec.errors/1`). `errors_out` and `kinematic_model_out` write the error set and
/// the kinematic model (`mtec.kinematic-model/1`, read by `compensate_gcode` and `map_eval`)
/// byte for byte as the CLI's `-o` and `--kinematic-model` do.
///
/// >>> import mtec, tempfile
/// >>> d = mtec.simulate("vmc-9line", tempfile.mkdtemp(), seed=1)
/// >>> r = mtec.identify_lines(d["machine.toml"], d["lines.csv"])
/// >>> r["report"]["format"], r["errors"]["format"]
/// ('mtec.identify-lines/1', 'mtec.errors/1')
/// >>> sorted(u["element"] for u in r["report"]["unidentifiable"])
/// ['EAZ', 'EBZ', 'ECY', 'ECZ']
#[pyfunction]
#[pyo3(signature = (machine, data, degree = None, errors_out = None, kinematic_model_out = None))]
pub fn identify_lines<'py>(
    py: Python<'py>,
    machine: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
    degree: Option<usize>,
    errors_out: Option<PathBuf>,
    kinematic_model_out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    // None: the CLI's default `--degree auto` (cross-validated)
    let degree = degree.map_or(DEFAULT_DEGREE, Degree::Fixed);
    Ok(run_lines(
        py,
        machine,
        data,
        degree,
        errors_out,
        kinematic_model_out,
    )?)
}

fn run_lines<'py>(
    py: Python<'py>,
    machine: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
    degree: Degree,
    errors_out: Option<PathBuf>,
    kinematic_model_out: Option<PathBuf>,
) -> Result<Bound<'py, PyAny>> {
    let machine_path = path_arg(machine, "machine")?;
    let m = read_machine(&machine_path)?;
    let table = read_table(data, "data")?;
    let d = LineData::from_table(&table)?;
    let data_path = table.path.clone();
    let id = py
        .detach(|| lines::identify_with(&m, &d, degree))
        .map_err(|e| match e {
            LinesError::Input(i) => i,
            LinesError::Model(e) => InputError::file(&machine_path, e.to_string()),
            other => InputError::file(&data_path, other.to_string()),
        })?;
    let mut inputs = vec![machine_path.clone()];
    if data_path.is_file() {
        inputs.push(data_path);
    }
    // everything is made before anything is written (as the CLI does)
    let kinematic = match &kinematic_model_out {
        Some(_) => Some(
            KinematicFile::new(&m, &id.errors)
                .map_err(|e| InputError::file(&machine_path, e))?
                .to_json()
                .map_err(internal)?,
        ),
        None => None,
    };
    if let Some(p) = &errors_out {
        let bytes = serde_json::to_vec_pretty(&id.errors).map_err(internal)?;
        write_output(p, &inputs, &bytes)?;
    }
    if let (Some(p), Some(k)) = (&kinematic_model_out, kinematic) {
        write_output(p, &inputs, k.as_bytes())?;
    }
    let out = PyDict::new(py);
    out.set_item("report", serde_to_py(py, &id.report)?)?;
    out.set_item("errors", serde_to_py(py, &id.errors)?)?;
    Ok(out.into_any())
}

/// Identifies the error motions EXC, EYC, EZC (µm) and EAC, EBC (µrad) of a rotary C axis from
/// double-ball-bar readings in five installation modes.
///
/// `setup` is the setup TOML (five `[[mode]]` tables); `data` the readings (CSV path, or a
/// mapping with `experiment,time_min,mode,angle_deg,dl_um`). Returns the document
/// `mtec identify ballbar --json` prints (`format` `mtec.ballbar-identification/1`):
/// `conditioning` (rank, worst condition number and angle, noise gain) and `motions`, a dict of
/// numpy arrays `experiment, time_min, angle_deg, EXC_um, EYC_um, EZC_um, EAC_urad, EBC_urad`.
/// A mode set that cannot separate the five motions raises `mtec.InputError` naming the setup.
///
/// >>> import mtec, tempfile
/// >>> d = mtec.simulate("dbb-rotary", tempfile.mkdtemp(), seed=1)
/// >>> r = mtec.identify_ballbar(d["setup.toml"], d["dbb.csv"])
/// >>> r["conditioning"]["rank"], sorted(r["motions"])[:3]
/// (5, ['EAC_urad', 'EBC_urad', 'EXC_um'])
#[pyfunction]
#[pyo3(signature = (setup, data))]
pub fn identify_ballbar<'py>(
    py: Python<'py>,
    setup: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    Ok(run_ballbar(py, setup, data)?)
}

fn run_ballbar<'py>(
    py: Python<'py>,
    setup: &Bound<'py, PyAny>,
    data: &Bound<'py, PyAny>,
) -> Result<Bound<'py, PyAny>> {
    let setup_path = path_arg(setup, "setup")?;
    let s = Setup::read(&setup_path)?;
    let table = read_table(data, "data")?;
    let d = Measurements::from_table(&table, &s)?;
    let result = py.detach(|| identify_dbb(&s, &d)).map_err(|e| match e {
        BallbarError::RankDeficient { .. } | BallbarError::Geometry(_) => {
            InputError::file(&setup_path, e.to_string())
        }
        BallbarError::Signal(_) => InputError::file(&table.path, e.to_string()),
    })?;
    let rows: Vec<serde_json::Value> = result
        .rows
        .iter()
        .map(|r| {
            json!({
                "experiment": r.experiment,
                "time_min": r.time_min,
                "angle_deg": r.angle_deg,
                "EXC_um": r.motions.exc_um,
                "EYC_um": r.motions.eyc_um,
                "EZC_um": r.motions.ezc_um,
                "EAC_urad": r.motions.eac_urad,
                "EBC_urad": r.motions.ebc_urad,
            })
        })
        .collect();
    let doc = json!({
        "format": "mtec.ballbar-identification/1",
        "conditioning": result.conditioning,
        "motions": rows,
    });
    Ok(to_py(py, &doc)?)
}
