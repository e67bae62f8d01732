//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod circular;
pub mod compensate_gcode;
pub mod compensate_table;
pub mod compensate_thermal_offset;
pub mod identify_ballbar;
pub mod identify_lines;
pub mod iso230_2;
pub mod machine;
pub mod map;
pub mod neural;
pub mod sensitivity;
pub mod simulate;
#[cfg(feature = "neural")]
pub mod terminal;
pub mod thermal;
pub mod volumetric;

pub mod compensate;
pub mod demo;
pub mod run;

/// Prints an outcome on stdout: its JSON with `--json`, else its text report.
pub(crate) fn report<T: std::fmt::Display>(
    outcome: &T,
    json: bool,
    to_json: fn(&T) -> Result<String, crate::error::CliError>,
) -> Result<(), crate::error::CliError> {
    if json {
        emit(&format!("{}\n", to_json(outcome)?))
    } else {
        emit(&outcome.to_string())
    }
}

/// Writes a report to stdout; a reader that closed the pipe early (`| head`) is not an error.
pub(crate) fn emit(text: &str) -> Result<(), crate::error::CliError> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
