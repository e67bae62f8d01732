//! A circular test of two linear axes (ballbar, ISO 230-4): G, G(b), H and the ballbar
//! diagnostics ranked by their contribution; optionally `circular.json` and a polar plot.
//! The job of `mtec circular`.

use crate::{Error, Observer, Result};
use mtec_io::{InputError, OutputGuard, Table};
use mtec_measure::circular::{
    diagnose, evaluate, radii_about, Arc, CircularTrace, Diagnostics, DiagnosticsConfig, Iso230_4,
    Plane, TraceOptions, Travel,
};
use mtec_report::polar::{polar_svg, PolarOptions, PolarTrace};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// The results file the job writes into [`Options::out`].
pub const RESULTS_FILE: &str = "circular.json";
/// The polar plot the job writes into [`Options::out`].
pub const PLOT_FILE: &str = "polar.svg";

/// What to evaluate and how.
#[derive(Debug, Clone)]
pub struct Options {
    /// The trace file (CSV `angle_deg,direction,dl_um`).
    pub run: PathBuf,
    /// Nominal radius (mm); overrides `# radius_mm` in the file.
    pub radius_mm: Option<f64>,
    /// Feed (mm/min); overrides `# feed_mm_min`. Needed for the servo mismatch in ms.
    pub feed_mm_min: Option<f64>,
    /// Plane; overrides `# plane`.
    pub plane: Option<Plane>,
    /// A partial arc (start, end) in degrees, traced ccw from start to end; overrides
    /// `# arc_start_deg` and `# arc_end_deg`.
    pub arc_deg: Option<[f64; 2]>,
    /// Contribution (µm) from which a fault is reported as present.
    pub threshold_um: f64,
    /// Folder to write `circular.json` and `polar.svg` into; `None` writes nothing.
    pub out: Option<PathBuf>,
}

impl Options {
    /// The header's radius, plane and feed, the default threshold (0.3 µm), nothing written.
    pub fn new(run: impl Into<PathBuf>) -> Options {
        Options {
            run: run.into(),
            radius_mm: None,
            feed_mm_min: None,
            plane: None,
            arc_deg: None,
            threshold_um: 0.3,
            out: None,
        }
    }
}

/// Samples per direction.
#[derive(Debug, Clone, Serialize)]
pub struct Samples {
    pub ccw: usize,
    pub cw: usize,
}

/// The result: `mtec.circular/1` (docs/formats.md).
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// `mtec.circular/1`.
    pub format: String,
    /// The trace file as given.
    pub file: String,
    /// Nominal radius (mm).
    pub radius_mm: f64,
    pub plane: Plane,
    /// Feed (mm/min), when known.
    pub feed_mm_min: Option<f64>,
    /// The partial arc (start, end, span in degrees), `null` for a full circle.
    pub arc: Option<Arc>,
    pub samples: Samples,
    /// G, G(b), H and the least-squares circles (µm).
    pub iso230_4: Iso230_4,
    /// The faults, ranked by contribution.
    pub diagnostics: Diagnostics,
}

/// The plane named `s` (`--plane`: XY, YZ or ZX).
pub fn parse_plane(s: &str) -> Result<Plane> {
    Plane::parse(s).ok_or_else(|| Error::usage(format!("--plane {s}: expected XY, YZ or ZX")))
}

/// A partial arc from its start and end (`--arc-start-deg`, `--arc-end-deg`): both or neither.
pub fn arc_deg(start: Option<f64>, end: Option<f64>) -> Result<Option<[f64; 2]>> {
    match (start, end) {
        (None, None) => Ok(None),
        (Some(a), Some(b)) => Ok(Some([a, b])),
        _ => Err(Error::usage(
            "a partial arc needs both --arc-start-deg and --arc-end-deg",
        )),
    }
}

impl Outcome {
    /// The outcome as the pretty JSON text of `circular.json` (keys sorted).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(&serde_json::to_value(self)?)?)
    }
}

/// Checks the options (usage errors).
fn check(o: &Options) -> Result<()> {
    for (name, v) in [
        ("--radius-mm", o.radius_mm),
        ("--feed-mm-min", o.feed_mm_min),
    ] {
        if let Some(v) = v {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::usage(format!(
                    "{name} {v}: must be a positive number"
                )));
            }
        }
    }
    if let Some([a, b]) = o.arc_deg {
        if !(a.is_finite() && b.is_finite()) {
            return Err(Error::usage(
                "--arc-start-deg and --arc-end-deg must be finite numbers",
            ));
        }
    }
    if !(o.threshold_um >= 0.0 && o.threshold_um.is_finite()) {
        return Err(Error::usage("--threshold-um must be a non-negative number"));
    }
    Ok(())
}

/// Evaluates the trace; writes `circular.json` and `polar.svg` into `opts.out` when given.
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    check(opts)?;
    // where the files go is settled before any work
    let guard = OutputGuard::new(&[&opts.run]);
    check_out(&guard, opts)?;
    evaluate_into(&Table::read(&opts.run)?, opts, &guard)
}

/// [`run`] of a trace already read (a file, or the Python module's arrays): `opts.run` is not
/// read; the table's path names the trace in errors and in the outcome's `file`.
pub fn run_table(table: &Table, opts: &Options) -> Result<Outcome> {
    check(opts)?;
    let guard = OutputGuard::new(&[&table.path]);
    check_out(&guard, opts)?;
    evaluate_into(table, opts, &guard)
}

/// Neither file of `opts.out` is an input.
fn check_out(guard: &OutputGuard, opts: &Options) -> Result<()> {
    if let Some(dir) = &opts.out {
        check_files(guard, dir)?;
    }
    Ok(())
}

/// Whether the folder `dir` can take circular.json and polar.svg, neither over the trace file
/// `run` (a usage error otherwise): for a caller that settles its outputs before reading.
pub fn check_out_dir(dir: &Path, run: &Path) -> Result<()> {
    check_files(&OutputGuard::new(&[run]), dir)
}

fn check_files(guard: &OutputGuard, dir: &Path) -> Result<()> {
    guard.check(&dir.join(RESULTS_FILE))?;
    guard.check(&dir.join(PLOT_FILE))?;
    Ok(())
}

/// The evaluation of the trace `table`, and its files written into `opts.out` when given.
fn evaluate_into(table: &Table, opts: &Options, guard: &OutputGuard) -> Result<Outcome> {
    let trace = CircularTrace::from_table(
        table,
        &TraceOptions {
            radius_mm: opts.radius_mm,
            plane: opts.plane,
            feed_mm_min: opts.feed_mm_min,
            arc_deg: opts.arc_deg,
        },
    )?;
    let iso = evaluate(&trace);
    let cfg = DiagnosticsConfig {
        threshold_um: opts.threshold_um,
        ..Default::default()
    };
    let diagnostics =
        diagnose(&trace, &cfg).map_err(|e| InputError::file(&table.path, e.to_string()))?;
    let outcome = Outcome {
        format: "mtec.circular/1".into(),
        file: table.path.display().to_string(),
        radius_mm: trace.radius_mm,
        plane: trace.plane,
        feed_mm_min: trace.feed_mm_min,
        arc: trace.arc,
        samples: Samples {
            ccw: trace.ccw.len(),
            cw: trace.cw.len(),
        },
        iso230_4: iso,
        diagnostics,
    };
    if let Some(dir) = &opts.out {
        guard.write(&dir.join(RESULTS_FILE), outcome.to_json()?.as_bytes())?;
        guard.write(
            &dir.join(PLOT_FILE),
            polar_plot(&trace, &outcome.iso230_4)?.as_bytes(),
        )?;
    }
    Ok(outcome)
}

/// The polar plot of both directions: radii about the bidirectional least-squares centre,
/// minus its radius deviation.
fn polar_plot(trace: &CircularTrace, iso: &Iso230_4) -> Result<String> {
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
    polar_svg(
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
    .map_err(|e| Error::Internal(anyhow::anyhow!(e.to_string())))
}

impl fmt::Display for Outcome {
    fn fmt(&self, o: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [a1, a2] = self.plane.axes();
        let iso = &self.iso230_4;
        writeln!(
            o,
            "ISO 230-4 circular test {} (plane {}{}, R = {} mm{})",
            self.file,
            a1,
            a2,
            self.radius_mm,
            self.feed_mm_min
                .map(|f| format!(", F = {f} mm/min"))
                .unwrap_or_default()
        )?;
        if let Some(a) = &self.arc {
            writeln!(
                o,
                "partial arc: {:.1}° to {:.1}° (ccw), span {:.1}°; G, G(b) over the arc, H where both directions overlap",
                a.start_deg, a.end_deg, a.span_deg
            )?;
        }
        writeln!(o)?;
        writeln!(
            o,
            "  circular deviation G(ccw)          {:>9.3} um",
            iso.g_ccw_um
        )?;
        writeln!(
            o,
            "  circular deviation G(cw)           {:>9.3} um",
            iso.g_cw_um
        )?;
        writeln!(
            o,
            "  bidirectional circular dev. G(b)   {:>9.3} um",
            iso.g_bidirectional_um
        )?;
        writeln!(
            o,
            "  circular hysteresis H              {:>9.3} um",
            iso.h_um
        )?;
        let c = &iso.circle_bidirectional;
        writeln!(
            o,
            "  least-squares centre ({a1}, {a2})      ({:.3}, {:.3}) um, radius deviation {:.3} um",
            c.centre_um[0], c.centre_um[1], c.radius_deviation_um
        )?;
        writeln!(
            o,
            "  condition number of the circle fit {:>9.2} (full circle 1.41)",
            iso.circle_fit_condition
        )?;
        writeln!(o)?;
        let diag = &self.diagnostics;
        writeln!(
            o,
            "diagnostics, ranked by contribution to circularity (present: >= {} um and > 3 s.e.)",
            diag.threshold_um
        )?;
        writeln!(
            o,
            "  {:<40} {:>11} {:<5} {:>9} {:>8} {:>6}",
            "fault", "value", "unit", "+/- s.e.", "contrib", "%"
        )?;
        for d in &diag.faults {
            let label = match d.pitch_mm {
                Some(p) if d.present => format!("{} (pitch {p:.2} mm)", d.label),
                _ => d.label.clone(),
            };
            let (Some(value), Some(se)) = (d.value, d.std_error) else {
                writeln!(
                    o,
                    "  {:<40} {}",
                    label,
                    d.note.as_deref().unwrap_or("not determined")
                )?;
                continue;
            };
            writeln!(
                o,
                "{} {:<40} {:>11.3} {:<5} {:>9.3} {:>8.3} {:>6.1}",
                if d.present { "*" } else { " " },
                label,
                value,
                d.unit,
                se,
                d.contribution_um,
                d.contribution_percent
            )?;
        }
        writeln!(
            o,
            "  residual RMS after the fit: {:.3} um",
            diag.residual_rms_um
        )?;
        for n in &diag.notes {
            writeln!(o, "  note: {n}")?;
        }
        Ok(())
    }
}
