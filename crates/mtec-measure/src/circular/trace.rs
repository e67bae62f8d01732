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
//!   than 45°: the least-squares circle of a partial arc is ill-determined.

use mtec_io::{InputError, Table};
use std::path::Path;

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
}

/// A validated circular-test trace.
#[derive(Debug, Clone)]
pub struct CircularTrace {
    pub radius_mm: f64,
    pub plane: Plane,
    pub feed_mm_min: Option<f64>,
    /// Samples in file order per direction.
    pub ccw: Vec<Sample>,
    pub cw: Vec<Sample>,
}

const MIN_SAMPLES: usize = 8;
const MAX_GAP_DEG: f64 = 45.0;

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
            if f <= 0.0 {
                return Err(InputError::file(
                    path,
                    format!("feed {f} mm/min: must be positive"),
                ));
            }
        }

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
                        "dl_um = {} is more than 10 % of the radius: not a ballbar deviation (wrong unit?)",
                        dls[k]
                    ),
                ));
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
            let gap = largest_gap_deg(samples);
            if gap > MAX_GAP_DEG {
                return Err(InputError::file(
                    path,
                    format!(
                        "direction `{name}` leaves a gap of {gap:.1}° without samples: a full circle is needed (largest gap allowed {MAX_GAP_DEG}°)"
                    ),
                ));
            }
        }
        Ok(CircularTrace {
            radius_mm,
            plane,
            feed_mm_min,
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
