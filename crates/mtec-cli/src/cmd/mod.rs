//! One module per subcommand: its clap `Args` and a `run(args) -> Result<(), CliError>`.

pub mod circular;
pub mod compensate_gcode;
pub mod compensate_table;
pub mod compensate_thermal_offset;
pub mod flatten;
pub mod identify_ballbar;
pub mod identify_lines;
pub mod iso230_2;
pub mod machine;
pub mod machine_stage;
pub mod map;
pub mod model_loader;
pub mod neural;
pub mod sensitivity;
pub mod simulate;
pub mod state;
#[cfg(feature = "neural")]
pub mod terminal;
pub mod thermal;
pub mod volumetric;

pub mod compensate;
pub mod demo;
pub mod pipeline;
pub mod pipeline_thermal;
pub mod run;

#[cfg(feature = "neural")]
pub mod map_bpnn;

/// Where a command's report lines go: stdout, or stderr when the output file itself streams to
/// stdout (`-o -`), so the two never mix. Write errors (a closed pipe) are the caller's to ignore.
pub(crate) fn messages(dest: &mtec_io::Destination) -> Box<dyn std::io::Write> {
    if dest.is_stdout() {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    }
}
