//! `mtec identify`: identification of error elements from measurements, one subcommand per
//! method (`lines`; the ballbar method plugs in as another variant).

use crate::error::CliError;

/// Identify error elements from measurements.
///
/// Methods:
///   lines    the 21 error elements of a three-axis machine from laser-interferometer lines
///            (9-line method and other line designs)
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub method: Method,
}

#[derive(clap::Subcommand, Debug)]
pub enum Method {
    /// Error elements of a 3-axis machine from line measurements (9-line method).
    Lines(super::identify_lines::Args),
}

pub fn run(args: Args) -> Result<(), CliError> {
    match args.method {
        Method::Lines(a) => super::identify_lines::run(a),
    }
}
