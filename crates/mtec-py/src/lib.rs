//! The Python module `mtec` (built by maturin as `mtec._mtec`, re-exported by
//! `python/mtec/__init__.py`): the library crates' jobs with numpy arrays in and out.
//!
//! Conventions of every function here:
//! - Tabular inputs are a CSV path (`str` or `os.PathLike`) or a mapping of column name to a 1-D
//!   array (a `dict` of numpy arrays, a pandas `DataFrame`); both go through the same validation
//!   as the command line ([`columns`]).
//! - Results are what the CLI prints with `--json`, as Python objects, with every list of flat
//!   numeric records turned into a dict of 1-D numpy arrays ([`convert`]).
//! - Files are written through `mtec_io` (atomically, never over an input).
//! - Errors ([`errors`]): a located input error is `mtec.InputError` (a `ValueError` with `.file`,
//!   `.line`, `.column`, `.message`), a usage error a `ValueError`, an internal failure a
//!   `RuntimeError`.
//! - Long numerical work runs without the GIL.
//!
//! The pipeline from a project file (`mtec_workflow::project`) is [`workflow`]: `run_project`.

mod columns;
mod comp;
mod convert;
mod errors;
mod gcode_file;
mod identify;
mod machine;
mod measure;
mod model;
mod sensitivity;
mod sim;
mod table;
mod thermal;
mod thermal_offset;
// the place of the project pipeline's binding (`mtec.run_project`), see its docs
mod workflow;

use pyo3::prelude::*;

#[pymodule]
fn _mtec(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("InputError", py.get_type::<errors::InputError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(measure::iso230_2, m)?)?;
    m.add_function(wrap_pyfunction!(measure::circular, m)?)?;
    m.add_function(wrap_pyfunction!(identify::identify_lines, m)?)?;
    m.add_function(wrap_pyfunction!(identify::identify_ballbar, m)?)?;
    m.add_function(wrap_pyfunction!(model::volumetric, m)?)?;
    m.add_function(wrap_pyfunction!(thermal::thermal_fit, m)?)?;
    m.add_function(wrap_pyfunction!(thermal::thermal_predict, m)?)?;
    m.add_function(wrap_pyfunction!(thermal::thermal_select, m)?)?;
    m.add_function(wrap_pyfunction!(thermal::thermal_cv, m)?)?;
    m.add_function(wrap_pyfunction!(comp::map_fit, m)?)?;
    m.add_function(wrap_pyfunction!(comp::map_eval, m)?)?;
    m.add_function(wrap_pyfunction!(comp::compensate_gcode, m)?)?;
    m.add_function(wrap_pyfunction!(gcode_file::compensate_gcode_file, m)?)?;
    m.add_function(wrap_pyfunction!(table::compensate_table, m)?)?;
    m.add_function(wrap_pyfunction!(
        thermal_offset::compensate_thermal_offset,
        m
    )?)?;
    m.add_function(wrap_pyfunction!(machine::machine_build, m)?)?;
    m.add_function(wrap_pyfunction!(machine::machine_replay, m)?)?;
    m.add_function(wrap_pyfunction!(sensitivity::sensitivity, m)?)?;
    m.add_function(wrap_pyfunction!(sim::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(workflow::run_project, m)?)?;
    Ok(())
}
