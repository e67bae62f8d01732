//! The circular-test (ballbar) trace file: `angle_deg,direction,dl_um` with the radius, plane
//! and feed in `#` header comments or given as options.
//!
//! Decisions where SPEC §4 is silent:
//! - Header keys: `# radius_mm = 100`, `# plane = XY` (`XY`, `YZ` or `ZX`; the ISO 230-4 planes),
//!   `# feed_mm_min = 1000` (optional; servo mismatch in ms needs it). Options override the file.
//! - `angle_deg` is the commanded angle measured from the plane's first axis towards its second
//!   (X→Y in XY, Y→Z in YZ, Z→X in ZX); any finite value, taken modulo 360.
//! - `ccw` is travel in the direction of increasing angle, `cw` the opposite.
//! - `dl_um` is the change of the bar length from its nominal length (= the radius): positive
//!   when the tool is farther from the pivot than nominal.
//! - Both directions must be present, each with at least 8 samples and no angular gap larger
//!   than 45°, round the full circle unless a partial arc is declared.
//! - A partial arc (ISO 230-4 allows one where the full circle cannot be reached, e.g. 220° in a
//!   vertical plane) is declared by `# arc_start_deg = -110` and `# arc_end_deg = 110` (or
//!   `--arc-start-deg`, `--arc-end-deg`): traced ccw from start to end and cw back. It must span
//!   at least [`MIN_ARC_DEG`] (below that the least-squares centre is ill-conditioned, see
//!   [`circle_fit_condition`]); every sample must lie on it; each direction must cover it end to
//!   end (first and last sample within [`MAX_END_GAP_DEG`] of its ends) with no gap over 45°.
//!   Declaring the arc keeps a full-circle test with lost data refused rather than silently
//!   evaluated as an arc.

use mtec_io::{InputError, Table};
use std::path::Path;

/// Fastest feed a trace may state (mm/min): 1000 m/min, beyond any machine tool.
pub const MAX_FEED_MM_MIN: f64 = 1e6;

/// The plane of the test: which machine axes are axis 1 and axis 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Plane {
    XY,
    YZ,
    ZX,
}

impl Plane {
    /// Parses `XY`, `YZ`, `ZX` (case-insensitive; `YX`, `ZY`, `XZ` are refused because their
    /// angle would run the other way round).
    pub fn parse(s: &str) -> Option<Plane> {
        match s.trim().to_ascii_uppercase().as_str() {
            "XY" | "G17" => Some(Plane::XY),
            "YZ" | "G19" => Some(Plane::YZ),
            "ZX" | "G18" => Some(Plane::ZX),
            _ => None,
        }
    }
    /// Names of axis 1 and axis 2.
    pub fn axes(self) -> [&'static str; 2] {
        match self {
            Plane::XY => ["X", "Y"],
            Plane::YZ => ["Y", "Z"],
            Plane::ZX => ["Z", "X"],
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Plane::XY => "XY",
            Plane::YZ => "YZ",
            Plane::ZX => "ZX",
        }
    }
}

/// Direction of travel round the circle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Travel {
    /// Increasing angle (axis 1 towards axis 2).
    Ccw,
    /// Decreasing angle.
    Cw,
}

impl Travel {
    /// d = +1 for ccw, −1 for cw: the sign of dθ/dt.
    pub fn sign(self) -> f64 {
        match self {
            Travel::Ccw => 1.0,
            Travel::Cw => -1.0,
        }
    }
}

/// One reading: commanded angle (deg, in [0, 360)) and bar-length change (µm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub angle_deg: f64,
    pub dl_um: f64,
}

/// Values that may come from options instead of the header.
#[derive(Debug, Clone, Default)]
pub struct TraceOptions {
    pub radius_mm: Option<f64>,
    pub plane: Option<Plane>,
    pub feed_mm_min: Option<f64>,
    /// A partial arc: start and end (deg), traced ccw from start to end.
    pub arc_deg: Option<[f64; 2]>,
}

/// A partial arc: from `start_deg` ccw to `end_deg` (both in [0, 360)), `span_deg` in
/// [[`MIN_ARC_DEG`], 360).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Arc {
    pub start_deg: f64,
    pub end_deg: f64,
    pub span_deg: f64,
}

impl Arc {
    /// Position of an angle along the arc (deg from its start, ccw), in [−tol, 360 − tol).
    pub fn along(&self, angle_deg: f64) -> f64 {
        let u = (angle_deg - self.start_deg).rem_euclid(360.0);
        if u > 360.0 - ANGLE_TOL_DEG {
            u - 360.0
        } else {
            u
        }
    }
}

/// A validated circular-test trace.
#[derive(Debug, Clone)]
pub struct CircularTrace {
    pub radius_mm: f64,
    pub plane: Plane,
    pub feed_mm_min: Option<f64>,
    /// The partial arc, `None` for a full circle.
    pub arc: Option<Arc>,
    /// Samples in file order per direction.
    pub ccw: Vec<Sample>,
    pub cw: Vec<Sample>,
}

const MIN_SAMPLES: usize = 8;
const MAX_GAP_DEG: f64 = 45.0;
/// The shortest partial arc evaluated (deg). The circle fit's condition number (columns 1,
/// cos θ, sin θ over evenly spaced samples, [`circle_fit_condition_of_span`]) is √2 = 1.41 on
/// the full circle, 3.0 at 220°, 4.6 at 180°, 20 at 90°, 84 at 45° and 330 at 22.5°: it grows
/// as 1/span², because over a short arc 1 and cos θ differ only by θ²/2, so the radius and the
/// centre's component along the arc's bisector trade off against each other (a short arc fits
/// circles of many radii). 90° caps it at 20, 14 times the full circle's.
pub const MIN_ARC_DEG: f64 = 90.0;
/// How far (deg) a direction's first and last samples may be from the declared arc's ends.
pub const MAX_END_GAP_DEG: f64 = 5.0;
/// Angles are compared to the arc's ends to this tolerance (deg): files hold 4 decimals.
const ANGLE_TOL_DEG: f64 = 1e-3;

impl CircularTrace {
    /// Reads and validates a trace file; `opts` override the header comments.
    pub fn read(path: &Path, opts: &TraceOptions) -> Result<CircularTrace, InputError> {
        let table = Table::read(path)?;
        Self::from_table(&table, opts)
    }

    /// Validates a parsed table.
    pub fn from_table(table: &Table, opts: &TraceOptions) -> Result<CircularTrace, InputError> {
        let path = &table.path;
        let header_number = |key: &str| -> Result<Option<f64>, InputError> {
            match table.comment_value(key) {
                None => Ok(None),
                Some(v) => v
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .map(Some)
                    .ok_or_else(|| {
                        InputError::file(
                            path,
                            format!("header comment `{key} = {v}`: not a finite number"),
                        )
                    }),
            }
        };
        let radius_mm = match opts.radius_mm {
            Some(r) => r,
            None => header_number("radius_mm")?.ok_or_else(|| {
                InputError::file(
                    path,
                    "the radius is unknown: add a header comment `# radius_mm = 100` or give --radius-mm",
                )
            })?,
        };
        if !(radius_mm > 0.0 && radius_mm.is_finite()) {
            return Err(InputError::file(
                path,
                format!("radius {radius_mm} mm: must be a positive number"),
            ));
        }
        if radius_mm >= mtec_io::plausible::MAX_POSITION_MM {
            return Err(InputError::file(
                path,
                format!(
                    "radius {radius_mm:e} mm is implausible (a ballbar is below {:e} mm): check the unit",
                    mtec_io::plausible::MAX_POSITION_MM
                ),
            ));
        }
        let plane = match opts.plane {
            Some(p) => p,
            None => match table.comment_value("plane") {
                None => Plane::XY,
                Some(v) => Plane::parse(&v).ok_or_else(|| {
                    InputError::file(
                        path,
                        format!("header comment `plane = {v}`: expected XY, YZ or ZX"),
                    )
                })?,
            },
        };
        let feed_mm_min = match opts.feed_mm_min {
            Some(f) => Some(f),
            None => header_number("feed_mm_min")?,
        };
        if let Some(f) = feed_mm_min {
            // 1000 m/min is beyond any machine tool's feed: a unit mistake, and the servo
            // mismatch estimate (a lag of radius·ω) would rank every fault below it
            if !(f > 0.0 && f < MAX_FEED_MM_MIN) {
                return Err(InputError::file(
                    path,
                    format!(
                        "feed {f:e} mm/min: must be positive and below {MAX_FEED_MM_MIN:e} mm/min"
                    ),
                ));
            }
        }
        let arc = read_arc(table, opts)?;

        table.require(&["angle_deg", "direction", "dl_um"])?;
        let angles = table.f64_column("angle_deg")?;
        let dirs = table.str_column("direction")?;
        let dls = table.f64_column("dl_um")?;
        let (mut ccw, mut cw) = (Vec::new(), Vec::new());
        for (k, row) in table.rows.iter().enumerate() {
            let s = Sample {
                angle_deg: angles[k].rem_euclid(360.0),
                dl_um: dls[k],
            };
            if dls[k].abs() > 0.1 * radius_mm * 1000.0 {
                return Err(table.error_at(
                    row,
                    "dl_um",
                    format!(
                        "dl_um = {:e} is more than 10 % of the radius: not a ballbar deviation (wrong unit?)",
                        dls[k]
                    ),
                ));
            }
            if let Some(arc) = &arc {
                if arc.along(s.angle_deg) > arc.span_deg + ANGLE_TOL_DEG {
                    return Err(table.error_at(
                        row,
                        "angle_deg",
                        format!(
                            "angle {}° is outside the declared arc from {}° to {}°",
                            angles[k], arc.start_deg, arc.end_deg
                        ),
                    ));
                }
            }
            match dirs[k].to_ascii_lowercase().as_str() {
                "ccw" => ccw.push(s),
                "cw" => cw.push(s),
                other => {
                    return Err(table.error_at(
                        row,
                        "direction",
                        format!("direction is `{other}`: expected `cw` or `ccw`"),
                    ))
                }
            }
        }
        for (samples, name) in [(&ccw, "ccw"), (&cw, "cw")] {
            if samples.len() < MIN_SAMPLES {
                return Err(InputError::file(
                    path,
                    format!(
                        "{} sample(s) in direction `{name}`: a circular test needs both directions, each with at least {MIN_SAMPLES} samples round the circle",
                        samples.len()
                    ),
                ));
            }
            if let Some(arc) = &arc {
                check_arc_coverage(path, arc, samples, name)?;
                continue;
            }
            let gap = largest_gap_deg(samples);
            if gap > MAX_GAP_DEG {
                return Err(InputError::file(
                    path,
                    format!(
                        "direction `{name}` leaves a gap of {gap:.1}° without samples: a full circle is needed (largest gap allowed {MAX_GAP_DEG}°); a partial arc must be declared: `# arc_start_deg = ...` and `# arc_end_deg = ...` (or --arc-start-deg, --arc-end-deg)"
                    ),
                ));
            }
        }
        Ok(CircularTrace {
            radius_mm,
            plane,
            feed_mm_min,
            arc,
            ccw,
            cw,
        })
    }

    /// Samples of one direction.
    pub fn samples(&self, t: Travel) -> &[Sample] {
        match t {
            Travel::Ccw => &self.ccw,
            Travel::Cw => &self.cw,
        }
    }
}

/// The declared partial arc, from the options or the header comments.
fn read_arc(table: &Table, opts: &TraceOptions) -> Result<Option<Arc>, InputError> {
    let path = &table.path;
    // (start, end, where: a header line or the options)
    let (start, end, line) = match opts.arc_deg {
        Some([a, b]) => (a, b, None),
        None => {
            let get = |key: &str| -> Result<Option<(usize, f64)>, InputError> {
                match table.comment_value_at(key) {
                    None => Ok(None),
                    Some((line, v)) => match v.parse::<f64>().ok().filter(|x| x.is_finite()) {
                        Some(x) => Ok(Some((line, x))),
                        None => Err(InputError::line(
                            path,
                            line,
                            format!("header comment `{key} = {v}`: not a finite number"),
                        )),
                    },
                }
            };
            match (get("arc_start_deg")?, get("arc_end_deg")?) {
                (None, None) => return Ok(None),
                (Some((_, a)), Some((l, b))) => (a, b, Some(l)),
                (Some((l, _)), None) | (None, Some((l, _))) => {
                    return Err(InputError::line(
                        path,
                        l,
                        "a partial arc needs both `# arc_start_deg` and `# arc_end_deg`",
                    ))
                }
            }
        }
    };
    let fail = |msg: String| match line {
        Some(l) => InputError::line(path, l, msg),
        None => InputError::file(path, format!("--arc-start-deg/--arc-end-deg: {msg}")),
    };
    if !(start.is_finite() && end.is_finite()) {
        return Err(fail("the arc's ends must be finite numbers".into()));
    }
    let span = (end - start).rem_euclid(360.0);
    if span < MIN_ARC_DEG {
        return Err(fail(format!(
            "the arc from {start}° to {end}° spans {span:.1}°: too short to determine a circle \
             (at least {MIN_ARC_DEG}°; the least-squares centre's condition number is {:.0} at \
             this span against {:.0} at {MIN_ARC_DEG}°)",
            circle_fit_condition_of_span(span.max(1.0)),
            circle_fit_condition_of_span(MIN_ARC_DEG)
        )));
    }
    Ok(Some(Arc {
        start_deg: start.rem_euclid(360.0),
        end_deg: end.rem_euclid(360.0),
        span_deg: span,
    }))
}

/// Each direction covers the arc end to end without a gap over 45°.
fn check_arc_coverage(
    path: &Path,
    arc: &Arc,
    samples: &[Sample],
    name: &str,
) -> Result<(), InputError> {
    let mut u: Vec<f64> = samples.iter().map(|s| arc.along(s.angle_deg)).collect();
    u.sort_by(f64::total_cmp);
    let (first, last) = (u[0], u[u.len() - 1]);
    if first > MAX_END_GAP_DEG || arc.span_deg - last > MAX_END_GAP_DEG {
        return Err(InputError::file(
            path,
            format!(
                "direction `{name}` covers {first:.1}° to {last:.1}° of the declared {:.1}° arc: \
                 it must be traced end to end (within {MAX_END_GAP_DEG}° of each end)",
                arc.span_deg
            ),
        ));
    }
    let gap = u.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    if gap > MAX_GAP_DEG {
        return Err(InputError::file(
            path,
            format!(
                "direction `{name}` leaves a gap of {gap:.1}° without samples inside the declared arc (largest gap allowed {MAX_GAP_DEG}°)"
            ),
        ));
    }
    Ok(())
}

/// Condition number of the linearised least-squares circle fit (columns 1, cos θ, sin θ; the
/// Gauss–Newton Jacobian at the solution up to signs) at these angles: how much the centre
/// and radius amplify the noise relative to the best case.
pub fn circle_fit_condition(angles_deg: &[f64]) -> f64 {
    let a = nalgebra::DMatrix::from_fn(angles_deg.len(), 3, |i, j| {
        let t = angles_deg[i].to_radians();
        [1.0, t.cos(), t.sin()][j]
    });
    let s = a.singular_values();
    s.max() / s.min()
}

/// [`circle_fit_condition`] of 0.5°-spaced samples over an arc of `span_deg`.
pub fn circle_fit_condition_of_span(span_deg: f64) -> f64 {
    let n = (span_deg / 0.5).ceil().max(2.0) as usize;
    let step = if span_deg >= 360.0 {
        360.0 / n as f64
    } else {
        span_deg / (n - 1) as f64
    };
    let a: Vec<f64> = (0..n).map(|k| k as f64 * step).collect();
    circle_fit_condition(&a)
}

/// Largest angular gap (deg) between consecutive sample angles round the full circle.
pub fn largest_gap_deg(samples: &[Sample]) -> f64 {
    let mut a: Vec<f64> = samples.iter().map(|s| s.angle_deg).collect();
    a.sort_by(f64::total_cmp);
    let mut gap = a[0] + 360.0 - a[a.len() - 1];
    for w in a.windows(2) {
        gap = gap.max(w[1] - w[0]);
    }
    gap
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(header: &str, rows: &str) -> Result<CircularTrace, InputError> {
        let text = format!("{header}angle_deg,direction,dl_um\n{rows}");
        CircularTrace::from_table(
            &Table::parse(Path::new("c.csv"), &text)?,
            &TraceOptions::default(),
        )
    }

    fn full(step: usize) -> String {
        let mut s = String::new();
        for d in ["ccw", "cw"] {
            for a in (0..360).step_by(step) {
                s.push_str(&format!("{a},{d},0.5\n"));
            }
        }
        s
    }

    #[test]
    fn header_values_and_validation() {
        let t = trace(
            "# radius_mm = 150\n# plane = zx\n# feed_mm_min: 2000\n",
            &full(30),
        )
        .unwrap();
        assert_eq!(t.radius_mm, 150.0);
        assert_eq!(t.plane, Plane::ZX);
        assert_eq!(t.feed_mm_min, Some(2000.0));
        assert_eq!(t.ccw.len(), 12);

        let e = trace("", &full(30)).unwrap_err();
        assert!(e.message.contains("radius is unknown"), "{e}");
        // a radius in µm (or 1e300) is refused for what it is, not as unseparable faults
        let e = trace("# radius_mm = 1e300\n", &full(30)).unwrap_err();
        assert!(e.message.contains("radius 1e300 mm is implausible"), "{e}");
        let e = trace("# radius_mm = 100\n", &full(60)).unwrap_err();
        assert!(e.message.contains("at least 8"), "{e}");
        let rows = full(30).replacen("30,cw,0.5", "30,clockwise,0.5", 1);
        let e = trace("# radius_mm = 100\n", &rows).unwrap_err();
        assert_eq!((e.line, e.column), (Some(16), Some(2)), "{e}");
        let rows = full(30).replacen("90,ccw,0.5", "90,ccw,20000", 1);
        let e = trace("# radius_mm = 100\n", &rows).unwrap_err();
        assert_eq!((e.line, e.column), (Some(6), Some(3)), "{e}");
        // a half circle only
        let mut half = String::new();
        for d in ["ccw", "cw"] {
            for a in (0..=180).step_by(10) {
                half.push_str(&format!("{a},{d},0\n"));
            }
        }
        let e = trace("# radius_mm = 100\n", &half).unwrap_err();
        assert!(e.message.contains("gap of 180.0°"), "{e}");
    }
}

#[cfg(test)]
mod arc_tests {
    use super::*;

    /// The full circle worked by hand: n evenly spaced samples make the columns 1, cos θ, sin θ
    /// orthogonal with norms² n, n/2, n/2, so the condition number is √(n/(n/2)) = √2. Over a
    /// short arc it grows as 1/span² (halving the span multiplies it by 4, to 2 %).
    #[test]
    fn circle_fit_condition_by_span() {
        assert!((circle_fit_condition_of_span(360.0) - 2f64.sqrt()).abs() < 1e-9);
        let c = |s: f64| circle_fit_condition_of_span(s);
        for (span, want) in [(220.0, 3.03), (180.0, 4.63), (90.0, 20.38), (45.0, 83.86)] {
            assert!((c(span) - want).abs() < 0.01, "{span}: {}", c(span));
        }
        let ratio = c(22.5) / c(45.0);
        assert!((ratio - 4.0).abs() < 0.08, "{ratio}");
    }

    fn arc_trace(
        header: &str,
        from: i32,
        to: i32,
        step: usize,
    ) -> Result<CircularTrace, InputError> {
        let mut rows = String::new();
        for d in ["ccw", "cw"] {
            for a in (from..=to).step_by(step) {
                rows.push_str(&format!("{a},{d},0.5\n"));
            }
        }
        let text = format!("# radius_mm = 100\n{header}angle_deg,direction,dl_um\n{rows}");
        CircularTrace::from_table(
            &Table::parse(Path::new("arc.csv"), &text)?,
            &TraceOptions::default(),
        )
    }

    #[test]
    fn a_declared_arc_is_read_and_checked() {
        let h = "# arc_start_deg = -110\n# arc_end_deg = 110\n";
        let t = arc_trace(h, -110, 110, 2).unwrap();
        let arc = t.arc.unwrap();
        assert_eq!(
            (arc.start_deg, arc.end_deg, arc.span_deg),
            (250.0, 110.0, 220.0)
        );
        assert_eq!(t.ccw.len(), 111);
        // undeclared, the same data is a full circle with a 140° hole: refused
        let e = arc_trace("", -110, 110, 2).unwrap_err();
        assert!(
            e.message.contains("gap of 140.0°") && e.message.contains("arc_start_deg"),
            "{e}"
        );
        // a sample off the arc is located
        let e = arc_trace(
            "# arc_start_deg = -100\n# arc_end_deg = 110\n",
            -110,
            110,
            2,
        )
        .unwrap_err();
        assert_eq!((e.line, e.column), (Some(5), Some(1)), "{e}");
        // an arc not traced to its end
        let e = arc_trace(h, -110, 90, 2).unwrap_err();
        assert!(e.message.contains("end to end"), "{e}");
        // too short: refused at the line that declares its end
        let e = arc_trace("# arc_start_deg = 10\n# arc_end_deg = 70\n", 10, 70, 1).unwrap_err();
        assert_eq!(e.line, Some(3), "{e}");
        assert!(
            e.message.contains("spans 60.0°") && e.message.contains("at least 90°"),
            "{e}"
        );
        // only one end
        let e = arc_trace("# arc_end_deg = 70\n", 10, 70, 1).unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
    }
}
