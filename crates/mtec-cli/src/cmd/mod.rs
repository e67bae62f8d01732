//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod circular;
pub mod compensate_gcode;
pub mod compensate_table;
pub mod compensate_thermal_offset;
pub mod identify_ballbar;
pub mod identify_lines;
pub mod iso230_2;
pub mod machine;
pub mod machine_stage;
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
pub mod pipeline;
pub mod pipeline_thermal;
pub mod run;

/// Where a command's report lines go: stdout, or stderr when the output file itself streams to
/// stdout (`-o -`), so the two never mix. Write errors (a closed pipe) are the caller's to ignore.
pub(crate) fn messages(dest: &mtec_io::Destination) -> Box<dyn std::io::Write> {
    if dest.is_stdout() {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
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
