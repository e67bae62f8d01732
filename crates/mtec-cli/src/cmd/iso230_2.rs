//! `mtec iso230-2`: ISO 230-2 positioning statistics of a linear axis (and VDI/DGQ 3441).

use crate::error::CliError;
use mtec_io::OutputGuard;
use mtec_measure::{evaluate_iso230_2, vdi3441, PositioningData};
use serde_json::json;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

const LONG: &str = "\
Evaluates bidirectional positioning runs of one linear axis (laser interferometer) as ISO 230-2:2014
asks: per target and direction the mean deviation, the standard uncertainty s and the mean +/- 2s
band, the reversal value B_i; and the axis values E_up, E_down, E, M, R_up, R_down, R, B, mean B,
A_up, A_down, A. A second report gives the VDI/DGQ 3441 values Ps, U, Pa and P.

Input (CSV, docs/formats.md, \"ISO 230-2 run CSV\"): target_mm,run,direction,deviation_um
  direction is + (target approached moving in the positive direction) or -;
  every run must visit every target in each direction; at least 2 runs per direction
  (ISO 230-2 asks for 5: fewer gives a warning).";

const EXAMPLES: &str = crate::help::examples!(
    "  # five bidirectional laser runs of one axis over 11 targets
  $ mtec simulate iso230-2 --out p
  # A, E, R, B, M per ISO 230-2 and Ps, U, Pa, P per VDI 3441, as a text report
  $ mtec iso230-2 p/iso230-2.csv
  # the same as one JSON object (mtec.iso230-2/1), also in p/iso230-2.json
  $ mtec iso230-2 p/iso230-2.csv --json --out p"
);

/// Arguments of `mtec iso230-2`.
#[derive(clap::Args, Debug)]
#[command(
    about = "ISO 230-2 positioning statistics (A, E, R, B, M) and VDI 3441 of a linear axis",
    long_about = LONG,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// The run file (target_mm,run,direction,deviation_um).
    pub run: PathBuf,
    /// Print the results as one JSON object (format mtec.iso230-2/1) instead of the text report.
    #[arg(long)]
    pub json: bool,
    /// Also write iso230-2.json into this folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let data = PositioningData::read(&args.run)?;
    let iso = evaluate_iso230_2(&data);
    let vdi = vdi3441(&iso);
    for w in &data.warnings {
        eprintln!("warning: {}: {w}", args.run.display());
    }
    let mut doc = json!({
        "format": "mtec.iso230-2/1",
        "file": args.run.display().to_string(),
        "runs_up": iso.runs_up,
        "runs_down": iso.runs_down,
    });
    let obj = doc.as_object_mut().expect("object");
    if let serde_json::Value::Object(axis) =
        serde_json::to_value(&iso.axis).map_err(anyhow::Error::from)?
    {
        obj.extend(axis);
    }
    obj.insert(
        "targets".into(),
        serde_json::to_value(&iso.targets).map_err(anyhow::Error::from)?,
    );
    obj.insert(
        "vdi3441".into(),
        serde_json::to_value(&vdi).map_err(anyhow::Error::from)?,
    );
    obj.insert("warnings".into(), json!(data.warnings));
    let text = serde_json::to_string_pretty(&doc).map_err(anyhow::Error::from)?;
    if let Some(dir) = &args.out {
        OutputGuard::new(&[&args.run]).write(&dir.join("iso230-2.json"), text.as_bytes())?;
    }
    if args.json {
        return emit(&format!("{text}\n"));
    }
    let mut o = String::new();
    let _ = writeln!(
        o,
        "ISO 230-2:2014 positioning of {} ({} runs +, {} runs -)",
        args.run.display(),
        iso.runs_up,
        iso.runs_down
    );
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "{:>10} {:>9} {:>9} {:>7} {:>7} {:>8} {:>8} {:>7}",
        "target_mm", "mean+_um", "mean-_um", "s+_um", "s-_um", "B_i_um", "mean_um", "R_i_um"
    );
    for t in &iso.targets {
        let _ = writeln!(
            o,
            "{:>10.3} {:>9.3} {:>9.3} {:>7.3} {:>7.3} {:>8.3} {:>8.3} {:>7.3}",
            t.target_mm,
            t.mean_up_um,
            t.mean_down_um,
            t.s_up_um,
            t.s_down_um,
            t.reversal_um,
            t.mean_bidirectional_um,
            t.r_um
        );
    }
    let a = &iso.axis;
    let _ = writeln!(o);
    let _ = writeln!(o, "axis values (um)        up      down     bidirectional");
    let _ = writeln!(
        o,
        "  A  accuracy      {:>8.3}  {:>8.3}  {:>8.3}",
        a.a_up_um, a.a_down_um, a.a_um
    );
    let _ = writeln!(
        o,
        "  E  systematic    {:>8.3}  {:>8.3}  {:>8.3}",
        a.e_up_um, a.e_down_um, a.e_um
    );
    let _ = writeln!(
        o,
        "  R  repeatability {:>8.3}  {:>8.3}  {:>8.3}",
        a.r_up_um, a.r_down_um, a.r_um
    );
    let _ = writeln!(
        o,
        "  M  range of mean bidirectional deviation       {:>8.3}",
        a.m_um
    );
    let _ = writeln!(
        o,
        "  B  reversal value (max |B_i|)                  {:>8.3}",
        a.b_um
    );
    let _ = writeln!(
        o,
        "  mean reversal value                            {:>8.3}",
        a.mean_b_um
    );
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "VDI/DGQ 3441 (um): Ps = {:.3}  U = {:.3}  Pa = {:.3}  P = {:.3}",
        vdi.ps_um, vdi.u_um, vdi.pa_um, vdi.p_um
    );
    emit(&o)
}

/// Writes the report to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn emit(text: &str) -> Result<(), CliError> {
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
