//! `mtec circular`: ISO 230-4 values and ballbar diagnostics of a circular test.

use crate::error::CliError;
use mtec_io::{InputError, OutputGuard};
use mtec_measure::circular::{
    diagnose, evaluate, radii_about, CircularTrace, DiagnosticsConfig, Plane, TraceOptions, Travel,
};
use mtec_report::polar::{polar_svg, PolarOptions, PolarTrace};
use serde_json::json;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

const LONG: &str = "\
Evaluates a circular test of two linear axes (ballbar, ISO 230-4): the least-squares circle of each
direction and of both, the circular deviation G (cw, ccw), the bidirectional circular deviation
G(b) and the circular hysteresis H; then fits the ballbar diagnostics from the trace and ranks them
by their contribution to the circularity: centre offset, scale mismatch (ppm), squareness (um/m),
servo mismatch (ms, needs the feed), backlash of each axis at its positive and negative end,
lateral play, reversal spikes, straightness and cyclic error (amplitude and pitch). A fault is
reported as present when it adds at least --threshold-um to the circularity and exceeds 3
standard errors.

Input (CSV, docs/formats.md, \"Circular test CSV\"): angle_deg,direction,dl_um
  angle_deg from the plane's first axis towards its second; direction cw or ccw (ccw =
  increasing angle); dl_um = bar length minus nominal. Header comments give the test:
    # radius_mm = 100
    # plane = XY          (XY, YZ or ZX)
    # feed_mm_min = 1000  (optional)
  Options override them. Both directions, full circles; the diagnostics need >= 90 samples each.";

const EXAMPLES: &str = crate::help::examples!(
    "  # a ballbar test of X and Y (R 100 mm, both directions) with injected faults
  $ mtec simulate circular-test --out c
  # G, G(b), H per ISO 230-4 and the faults that cause them, ranked; the JSON
  # results and the polar plot go to c/result (circular.json, polar.svg)
  $ mtec circular c/circular.csv --out c/result
  # the same machine without the faults, to compare
  $ mtec circular c/circular-fault-free.csv"
);

/// Arguments of `mtec circular`.
#[derive(clap::Args, Debug)]
#[command(
    about = "ISO 230-4 circular test (G, H) and ballbar diagnostics, ranked",
    long_about = LONG,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// The trace file (angle_deg,direction,dl_um).
    pub run: PathBuf,
    /// Print the results as one JSON object (format mtec.circular/1).
    #[arg(long)]
    pub json: bool,
    /// Nominal radius (mm); overrides `# radius_mm` in the file.
    #[arg(long)]
    pub radius_mm: Option<f64>,
    /// Feed (mm/min); overrides `# feed_mm_min`. Needed for the servo mismatch in ms.
    #[arg(long)]
    pub feed_mm_min: Option<f64>,
    /// Plane XY, YZ or ZX; overrides `# plane`.
    #[arg(long)]
    pub plane: Option<String>,
    /// Contribution (um) from which a fault is reported as present.
    #[arg(long, default_value_t = 0.3)]
    pub threshold_um: f64,
    /// Write circular.json and polar.svg into this folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let plane = match &args.plane {
        None => None,
        Some(p) => Some(
            Plane::parse(p)
                .ok_or_else(|| CliError::usage(format!("--plane {p}: expected XY, YZ or ZX")))?,
        ),
    };
    for (name, v) in [
        ("--radius-mm", args.radius_mm),
        ("--feed-mm-min", args.feed_mm_min),
    ] {
        if let Some(v) = v {
            if !(v > 0.0 && v.is_finite()) {
                return Err(CliError::usage(format!(
                    "{name} {v}: must be a positive number"
                )));
            }
        }
    }
    if !(args.threshold_um >= 0.0 && args.threshold_um.is_finite()) {
        return Err(CliError::usage(
            "--threshold-um must be a non-negative number",
        ));
    }
    let opts = TraceOptions {
        radius_mm: args.radius_mm,
        plane,
        feed_mm_min: args.feed_mm_min,
    };
    let trace = CircularTrace::read(&args.run, &opts)?;
    let iso = evaluate(&trace);
    let cfg = DiagnosticsConfig {
        threshold_um: args.threshold_um,
        ..Default::default()
    };
    let diag = diagnose(&trace, &cfg).map_err(|e| InputError::file(&args.run, e.to_string()))?;

    let doc = json!({
        "format": "mtec.circular/1",
        "file": args.run.display().to_string(),
        "radius_mm": trace.radius_mm,
        "plane": trace.plane.name(),
        "feed_mm_min": trace.feed_mm_min,
        "samples": {"ccw": trace.ccw.len(), "cw": trace.cw.len()},
        "iso230_4": iso,
        "diagnostics": diag,
    });
    let text = serde_json::to_string_pretty(&doc).map_err(anyhow::Error::from)?;
    if let Some(dir) = &args.out {
        let guard = OutputGuard::new(&[&args.run]);
        guard.write(&dir.join("circular.json"), text.as_bytes())?;
        let c = &iso.circle_bidirectional;
        let dev = |t: Travel| -> (Vec<f64>, Vec<f64>) {
            let s = trace.samples(t);
            let r = radii_about(trace.radius_mm, s, c);
            (
                s.iter().map(|x| x.angle_deg).collect(),
                r.iter().map(|v| v - c.radius_deviation_um).collect(),
            )
        };
        let (a_ccw, d_ccw) = dev(Travel::Ccw);
        let (a_cw, d_cw) = dev(Travel::Cw);
        let svg = polar_svg(
            &[
                PolarTrace {
                    label: "ccw",
                    angles_deg: &a_ccw,
                    deviations_um: &d_ccw,
                    color: (31, 119, 180),
                },
                PolarTrace {
                    label: "cw",
                    angles_deg: &a_cw,
                    deviations_um: &d_cw,
                    color: (214, 39, 40),
                },
            ],
            &PolarOptions {
                title: format!(
                    "Circular test {} R{} mm: G(b) {:.2} um",
                    trace.plane.name(),
                    trace.radius_mm,
                    iso.g_bidirectional_um
                ),
                ..Default::default()
            },
        )
        .map_err(|e| anyhow::anyhow!(e.to_string()))?;
        guard.write(&dir.join("polar.svg"), svg.as_bytes())?;
    }
    if args.json {
        return emit(&format!("{text}\n"));
    }
    let mut o = String::new();
    let [a1, a2] = trace.plane.axes();
    let _ = writeln!(
        o,
        "ISO 230-4 circular test {} (plane {}{}, R = {} mm{})",
        args.run.display(),
        a1,
        a2,
        trace.radius_mm,
        trace
            .feed_mm_min
            .map(|f| format!(", F = {f} mm/min"))
            .unwrap_or_default()
    );
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "  circular deviation G(ccw)          {:>9.3} um",
        iso.g_ccw_um
    );
    let _ = writeln!(
        o,
        "  circular deviation G(cw)           {:>9.3} um",
        iso.g_cw_um
    );
    let _ = writeln!(
        o,
        "  bidirectional circular dev. G(b)   {:>9.3} um",
        iso.g_bidirectional_um
    );
    let _ = writeln!(
        o,
        "  circular hysteresis H              {:>9.3} um",
        iso.h_um
    );
    let c = &iso.circle_bidirectional;
    let _ = writeln!(
        o,
        "  least-squares centre ({a1}, {a2})      ({:.3}, {:.3}) um, radius deviation {:.3} um",
        c.centre_um[0], c.centre_um[1], c.radius_deviation_um
    );
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "diagnostics, ranked by contribution to circularity (present: >= {} um and > 3 s.e.)",
        diag.threshold_um
    );
    let _ = writeln!(
        o,
        "  {:<40} {:>11} {:<5} {:>9} {:>8} {:>6}",
        "fault", "value", "unit", "+/- s.e.", "contrib", "%"
    );
    for d in &diag.faults {
        let label = match d.pitch_mm {
            Some(p) if d.present => format!("{} (pitch {p:.2} mm)", d.label),
            _ => d.label.clone(),
        };
        let _ = writeln!(
            o,
            "{} {:<40} {:>11.3} {:<5} {:>9.3} {:>8.3} {:>6.1}",
            if d.present { "*" } else { " " },
            label,
            d.value,
            d.unit,
            d.std_error,
            d.contribution_um,
            d.contribution_percent
        );
    }
    let _ = writeln!(
        o,
        "  residual RMS after the fit: {:.3} um",
        diag.residual_rms_um
    );
    for n in &diag.notes {
        let _ = writeln!(o, "  note: {n}");
    }
    emit(&o)
}

/// Writes the report to stdout; a reader that closed the pipe early (`| head`) is not an error.
fn emit(text: &str) -> Result<(), CliError> {
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}
