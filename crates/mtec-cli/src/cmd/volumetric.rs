//! `mtec volumetric`: volumetric error of the tool tip at commanded points.

use crate::error::CliError;
use mtec_workflow::ops::volumetric::{self as op, Options};
use std::path::PathBuf;

const LONG: &str = "\
Volumetric error Ex, Ey, Ez (um) of the tool tip relative to the workpiece at commanded points.

The machine (TOML: chain, travels, tool offset; docs/formats.md, \"Machine TOML\") and the error
set (JSON mtec.errors/1, e.g. from `mtec identify lines`, or a simulation's truth.json) give the
error model; the points file has one column per machine axis: x_mm, y_mm, z_mm, a_deg, b_deg,
c_deg as the chain needs. Output (CSV on stdout, or --json): the point, then ex_um, ey_um, ez_um
and, for chains with rotary axes, the orientation error eax_urad, eay_urad, eaz_urad.

--form chooses the formalism (HTM multi-body or POE screw theory) and order (exact rigid-body or
first-order linearised); all four agree to first order, HTM and POE exactly.";

const EXAMPLES: &str = crate::help::examples!(
    "  # a machine and its true errors (a simulation's truth.json is an error set)
  $ mtec simulate vmc-9line --out d
  # two commanded points, one column per axis of the chain
  $ printf 'x_mm,y_mm,z_mm\\n100,200,50\\n500,700,250\\n' > pts.csv
  # Ex, Ey, Ez of the tool tip there: exact HTM, then first-order POE
  $ mtec volumetric --machine d/machine.toml --errors d/truth.json \\
      --points pts.csv
  $ mtec volumetric --machine d/machine.toml --errors d/truth.json \\
      --points pts.csv --form poe-first"
);

/// Arguments of `mtec volumetric`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Volumetric error at commanded points (HTM or POE, exact or first-order)",
    long_about = LONG,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// Machine description (TOML).
    #[arg(long)]
    pub machine: PathBuf,
    /// Error set (JSON, "format": "mtec.errors/1"); a simulation's truth.json also works.
    #[arg(long)]
    pub errors: PathBuf,
    /// Commanded points (CSV with x_mm, y_mm, z_mm, ... columns).
    #[arg(long)]
    pub points: PathBuf,
    /// Formalism and order.
    #[arg(long, value_enum, default_value = "htm-exact")]
    pub form: Form,
    /// Print JSON instead of CSV.
    #[arg(long)]
    pub json: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum Form {
    HtmExact,
    HtmFirst,
    PoeExact,
    PoeFirst,
}

impl From<Form> for op::Form {
    fn from(f: Form) -> Self {
        match f {
            Form::HtmExact => op::Form::HtmExact,
            Form::HtmFirst => op::Form::HtmFirst,
            Form::PoeExact => op::Form::PoeExact,
            Form::PoeFirst => op::Form::PoeFirst,
        }
    }
}

impl Args {
    fn options(&self) -> Options {
        Options {
            machine: self.machine.clone(),
            errors: self.errors.clone(),
            points: self.points.clone(),
            form: self.form.into(),
        }
    }
}

pub fn run(args: Args) -> Result<(), CliError> {
    let outcome = op::run(&args.options(), &mut crate::observer::Stderr::default())?;
    if args.json {
        super::emit(&format!("{}\n", outcome.to_json()?))
    } else {
        super::emit(&outcome.to_string())
    }
}
