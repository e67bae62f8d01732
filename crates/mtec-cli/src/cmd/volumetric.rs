//! `mtec volumetric`: volumetric error of the tool tip at commanded points.

use crate::error::CliError;
use crate::inputs::{read_errors, read_machine, read_poses};
use mtec_model::{Formalism, Order, VolumetricModel};
use std::fmt::Write;
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

pub fn run(args: Args) -> Result<(), CliError> {
    let machine = read_machine(&args.machine)?;
    let errors = read_errors(&args.errors)?;
    let poses = read_poses(&args.points, &machine)?;
    let (f, o) = match args.form {
        Form::HtmExact => (Formalism::Htm, Order::Exact),
        Form::HtmFirst => (Formalism::Htm, Order::FirstOrder),
        Form::PoeExact => (Formalism::Poe, Order::Exact),
        Form::PoeFirst => (Formalism::Poe, Order::FirstOrder),
    };
    let vm = VolumetricModel::new(&machine, &errors);
    let rotary = machine.axes.iter().any(|a| a.is_rotary());
    let names: Vec<String> = machine
        .axes
        .iter()
        .map(|a| crate::inputs::pose_column(*a))
        .collect();
    if args.json {
        let rows: Vec<serde_json::Value> = poses
            .iter()
            .map(|q| {
                let v = vm.error(q, f, o);
                let mut obj = serde_json::Map::new();
                for (n, x) in names.iter().zip(q) {
                    obj.insert(n.clone(), (*x).into());
                }
                obj.insert("ex_um".into(), v.position_um[0].into());
                obj.insert("ey_um".into(), v.position_um[1].into());
                obj.insert("ez_um".into(), v.position_um[2].into());
                if rotary {
                    obj.insert(
                        "orientation_urad".into(),
                        serde_json::json!(v.orientation_urad),
                    );
                }
                serde_json::Value::Object(obj)
            })
            .collect();
        let out = serde_json::json!({ "format": "mtec.volumetric/1", "form": format!("{:?}", args.form), "points": rows });
        println!(
            "{}",
            serde_json::to_string_pretty(&out).map_err(|e| CliError::Internal(e.into()))?
        );
        return Ok(());
    }
    let mut out = names.join(",") + ",ex_um,ey_um,ez_um";
    if rotary {
        out.push_str(",eax_urad,eay_urad,eaz_urad");
    }
    out.push('\n');
    for q in &poses {
        let v = vm.error(q, f, o);
        let cols: Vec<String> = q.iter().map(|x| format!("{x}")).collect();
        let _ = write!(
            out,
            "{},{:.4},{:.4},{:.4}",
            cols.join(","),
            v.position_um[0],
            v.position_um[1],
            v.position_um[2]
        );
        if rotary {
            let _ = write!(
                out,
                ",{:.3},{:.3},{:.3}",
                v.orientation_urad[0], v.orientation_urad[1], v.orientation_urad[2]
            );
        }
        out.push('\n');
    }
    print!("{out}");
    Ok(())
}
