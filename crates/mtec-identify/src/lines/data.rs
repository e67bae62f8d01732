//! Line measurements (SPEC §4 `line,step,x_mm,y_mm,z_mm,ux,uy,uz,reading_um`): parsing,
//! validation with located errors, and the geometry of each line inferred from its points.
//!
//! A *channel* is one value of the `line` column (`X1`, `X1.y`, ...): one laser set-up reading
//! along one unit direction `u` at the commanded points of one straight line. The part of the
//! name before the first `.` names the *line*; a line's channels may share its points. Nothing
//! about a design is hard-coded: start, direction and moving axes come from the points.
//!
//! Decisions where SPEC is silent:
//! - A channel whose `u` is along the line (|u·d| ≥ 0.999) is a displacement channel; any other
//!   is read by straightness optics, whose hand alignment adds an unknown linear trend (a
//!   nuisance parameter of the identification).
//! - The reference point of a channel is its point with the lowest `step`; readings are
//!   relative to it (its own reading is kept: it carries the reference's noise).
//! - Repeat runs: an optional `run` column (a whole number ≥ 1). Each (line value, run) is its own
//!   channel, with its own reference point and alignment slope, as a re-zeroed, re-aligned
//!   laser set-up is; the identification then averages the runs through least squares. Without
//!   the column every row is run 1.
//! - Tolerances: |u| = 1 within 1e-3; `u` the same on every row of a channel within 1e-5; each
//!   point within 1e-3 mm of the straight line through the channel's end points.

use mtec_io::plausible::{MAX_ERROR_UM, MAX_POSITION_MM};
use mtec_io::{InputError, Table};
use mtec_model::Axis;

/// Columns a line-measurement file must have.
pub const LINE_COLUMNS: [&str; 9] = [
    "line",
    "step",
    "x_mm",
    "y_mm",
    "z_mm",
    "ux",
    "uy",
    "uz",
    "reading_um",
];

/// |u| must be 1 within this.
const UNIT_TOL: f64 = 1e-3;
/// `u` must not change along a channel by more than this (per component).
const SAME_U_TOL: f64 = 1e-5;
/// Points must lie within this distance (mm) of the channel's straight line.
const STRAIGHT_TOL_MM: f64 = 1e-3;
/// A channel with |u·d| at least this is a displacement channel.
const ALONG_COS: f64 = 0.999;

/// Optional column: the repeat run of a reading.
pub const RUN_COLUMN: &str = "run";

/// One parsed row: step, point (mm), direction, reading (µm), file line.
type Reading = (i64, [f64; 3], [f64; 3], f64, usize);

/// What a channel reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ChannelKind {
    /// Linear optics: displacement along the line.
    Displacement,
    /// Straightness optics: displacement across the line, plus an unknown alignment trend.
    Straightness,
}

/// One measured channel, its points sorted by step.
#[derive(Debug, Clone)]
pub struct Channel {
    /// The `line` value, e.g. `X1.y`.
    pub name: String,
    /// The line it belongs to (name before the first `.`), e.g. `X1`.
    pub line: String,
    /// The repeat run (1 when the file has no `run` column).
    pub run: i64,
    /// Unit reading direction.
    pub u: [f64; 3],
    pub kind: ChannelKind,
    /// Commanded points (mm), sorted by step; the first is the reference.
    pub points_mm: Vec<[f64; 3]>,
    /// Readings (µm), relative to the reference point.
    pub readings_um: Vec<f64>,
    /// File line of each reading (for messages), 0 when built in memory.
    pub file_lines: Vec<usize>,
    /// Unit direction of the line (first to last point).
    pub direction: [f64; 3],
    /// Axes that move along the line.
    pub moving_axes: Vec<Axis>,
}

impl Channel {
    /// The name to show: `X1.y`, or `X1.y run 2` for a later repeat run.
    pub fn label(&self) -> String {
        if self.run == 1 {
            self.name.clone()
        } else {
            format!("{} run {}", self.name, self.run)
        }
    }
    /// Distance (mm) of point k from the reference point.
    pub fn distance_mm(&self, k: usize) -> f64 {
        norm(sub(self.points_mm[k], self.points_mm[0]))
    }
    /// Length of the measured line (mm).
    pub fn length_mm(&self) -> f64 {
        self.distance_mm(self.points_mm.len() - 1)
    }
}

/// A whole line-measurement file.
#[derive(Debug, Clone)]
pub struct LineData {
    /// Where it came from (file path or a description).
    pub source: String,
    /// The file, when read from one (for located messages about points).
    pub path: Option<std::path::PathBuf>,
    /// 1-based column of `x_mm` in that file.
    pub point_column: usize,
    /// Channels in order of first appearance.
    pub channels: Vec<Channel>,
}

impl LineData {
    /// Reads and validates a line-measurement CSV.
    pub fn read(path: &std::path::Path) -> Result<LineData, InputError> {
        LineData::from_table(&Table::read(path)?)
    }

    /// Validates a parsed table: every problem is reported with its file, line and column.
    pub fn from_table(t: &Table) -> Result<LineData, InputError> {
        t.require(&LINE_COLUMNS)?;
        let col = |n: &str| t.column(n);
        let (c_line, c_step) = (col("line")?, col("step")?);
        let c_xyz = [col("x_mm")?, col("y_mm")?, col("z_mm")?];
        let c_u = [col("ux")?, col("uy")?, col("uz")?];
        let c_read = col("reading_um")?;
        let c_run = t.column(RUN_COLUMN).ok();
        // rows grouped by channel (name, run), in order of first appearance
        let mut names: Vec<(String, i64)> = Vec::new();
        let mut rows: Vec<Vec<Reading>> = Vec::new();
        for row in &t.rows {
            let name = row.fields[c_line].trim().to_string();
            if name.is_empty() {
                return Err(InputError::at(
                    &t.path,
                    row.line,
                    c_line + 1,
                    "`line` is empty: every reading needs the name of its line (e.g. X1, X1.y)",
                ));
            }
            let step_s = row.fields[c_step].trim();
            let step: i64 = step_s.parse().map_err(|_| {
                InputError::at(
                    &t.path,
                    row.line,
                    c_step + 1,
                    format!("`step` is `{step_s}`: not a whole number"),
                )
            })?;
            let p = [
                t.cell_f64_within(row, c_xyz[0], MAX_POSITION_MM, "mm")?,
                t.cell_f64_within(row, c_xyz[1], MAX_POSITION_MM, "mm")?,
                t.cell_f64_within(row, c_xyz[2], MAX_POSITION_MM, "mm")?,
            ];
            let u = [
                t.cell_f64(row, c_u[0])?,
                t.cell_f64(row, c_u[1])?,
                t.cell_f64(row, c_u[2])?,
            ];
            let n = norm(u);
            if (n - 1.0).abs() > UNIT_TOL {
                return Err(InputError::at(
                    &t.path,
                    row.line,
                    c_u[0] + 1,
                    format!(
                        "reading direction (ux, uy, uz) = ({}, {}, {}) has length {n:.6}; it must be a unit vector",
                        u[0], u[1], u[2]
                    ),
                ));
            }
            let reading = t.cell_f64_within(row, c_read, MAX_ERROR_UM, "um")?;
            let run = match c_run {
                None => 1,
                Some(c) => {
                    let v = row.fields[c].trim();
                    match v.parse::<i64>() {
                        Ok(r) if r >= 1 => r,
                        _ => {
                            return Err(InputError::at(
                                &t.path,
                                row.line,
                                c + 1,
                                format!("`run` is `{v}`: a repeat run is a whole number from 1"),
                            ))
                        }
                    }
                }
            };
            let name = (name, run);
            let i = match names.iter().position(|x| *x == name) {
                Some(i) => i,
                None => {
                    names.push(name);
                    rows.push(Vec::new());
                    names.len() - 1
                }
            };
            rows[i].push((step, p, u, reading, row.line));
        }
        let mut channels = Vec::with_capacity(names.len());
        for ((name, run), mut r) in names.into_iter().zip(rows) {
            let shown = if run == 1 {
                name.clone()
            } else {
                format!("{name} run {run}")
            };
            r.sort_by_key(|x| x.0);
            if let Some(w) = r.windows(2).find(|w| w[0].0 == w[1].0) {
                return Err(InputError::at(
                    &t.path,
                    w[1].4,
                    c_step + 1,
                    format!(
                        "line `{shown}` has step {} twice (first at line {})",
                        w[1].0, w[0].4
                    ),
                ));
            }
            if r.len() < 3 {
                return Err(InputError::line(
                    &t.path,
                    r[0].4,
                    format!(
                        "line `{shown}` has {} point(s): a line needs at least 3 to say anything beyond its reference",
                        r.len()
                    ),
                ));
            }
            let u0 = r[0].2;
            if let Some(bad) = r
                .iter()
                .find(|x| (0..3).any(|i| (x.2[i] - u0[i]).abs() > SAME_U_TOL))
            {
                return Err(InputError::at(
                    &t.path,
                    bad.4,
                    c_u[0] + 1,
                    format!(
                        "line `{shown}` changes its reading direction here ({:?} after {:?} at line {}): one channel reads along one direction; give another direction another line name",
                        bad.2, u0, r[0].4
                    ),
                ));
            }
            let points: Vec<[f64; 3]> = r.iter().map(|x| x.1).collect();
            let file_lines: Vec<usize> = r.iter().map(|x| x.4).collect();
            let geometry = line_geometry(&points).map_err(|(k, msg)| {
                InputError::at(
                    &t.path,
                    file_lines[k],
                    c_xyz[0] + 1,
                    format!("line `{shown}`: {msg}"),
                )
            })?;
            let mut channel = Channel::new(
                name,
                normalise(u0),
                points,
                r.iter().map(|x| x.3).collect(),
                file_lines,
                geometry,
            );
            channel.run = run;
            channels.push(channel);
        }
        Ok(LineData {
            source: t.path.display().to_string(),
            path: Some(t.path.clone()),
            point_column: c_xyz[0] + 1,
            channels,
        })
    }

    /// The distinct line names, in order of first appearance.
    pub fn line_names(&self) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for c in &self.channels {
            if !v.contains(&c.line) {
                v.push(c.line.clone());
            }
        }
        v
    }

    /// The same data without the channels of the named lines (for design studies).
    pub fn without_lines(&self, lines: &[&str]) -> LineData {
        LineData {
            source: format!("{} without {}", self.source, lines.join(", ")),
            path: self.path.clone(),
            point_column: self.point_column,
            channels: self
                .channels
                .iter()
                .filter(|c| !lines.contains(&c.line.as_str()))
                .cloned()
                .collect(),
        }
    }

    /// A design with no readings yet (all zero): for studying what a design can identify.
    pub fn from_specs(specs: &[mtec_model::LineSpec]) -> Result<LineData, String> {
        let mut channels = Vec::new();
        for l in specs {
            let points = l.points();
            if points.len() < 3 {
                return Err(format!("line `{}` has fewer than 3 points", l.name));
            }
            let d = line_geometry(&points).map_err(|(_, m)| format!("line `{}`: {m}", l.name))?;
            for (k, u) in l.channels.iter().enumerate() {
                let u = normalise(*u);
                let along = dot(u, d).abs() >= ALONG_COS;
                let name = if k == 0 && along {
                    l.name.clone()
                } else {
                    let i = (0..3)
                        .max_by(|&a, &b| u[a].abs().total_cmp(&u[b].abs()))
                        .unwrap_or(0);
                    format!("{}.{}", l.name, ["x", "y", "z"][i])
                };
                let n = points.len();
                channels.push(Channel::new(
                    name,
                    u,
                    points.clone(),
                    vec![0.0; n],
                    vec![0; n],
                    d,
                ));
            }
        }
        Ok(LineData {
            source: "design (no readings)".into(),
            path: None,
            point_column: 0,
            channels,
        })
    }

    /// Total number of readings.
    pub fn n_readings(&self) -> usize {
        self.channels.iter().map(|c| c.readings_um.len()).sum()
    }
}

impl Channel {
    fn new(
        name: String,
        u: [f64; 3],
        points_mm: Vec<[f64; 3]>,
        readings_um: Vec<f64>,
        file_lines: Vec<usize>,
        direction: [f64; 3],
    ) -> Channel {
        let along = dot(u, direction).abs() >= ALONG_COS;
        let moving_axes = [Axis::X, Axis::Y, Axis::Z]
            .into_iter()
            .filter(|a| direction[a.index()].abs() > 1e-9)
            .collect();
        Channel {
            line: name.split('.').next().unwrap_or(&name).to_string(),
            run: 1,
            name,
            u,
            kind: if along {
                ChannelKind::Displacement
            } else {
                ChannelKind::Straightness
            },
            points_mm,
            readings_um,
            file_lines,
            direction,
            moving_axes,
        }
    }
}

/// Unit direction of the points' line, or (index of the offending point, message).
fn line_geometry(points: &[[f64; 3]]) -> Result<[f64; 3], (usize, String)> {
    let last = points.len() - 1;
    let chord = sub(points[last], points[0]);
    let len = norm(chord);
    if len < 1e-6 {
        return Err((
            last,
            "its first and last points coincide: a line must move".into(),
        ));
    }
    let d = chord.map(|v| v / len);
    for (k, p) in points.iter().enumerate() {
        let r = sub(*p, points[0]);
        let along = dot(r, d);
        let off = norm(sub(r, d.map(|v| v * along)));
        if off > STRAIGHT_TOL_MM {
            return Err((
                k,
                format!(
                    "point {k} ({:.4}, {:.4}, {:.4}) is {off:.4} mm off the straight line from its first to its last point",
                    p[0], p[1], p[2]
                ),
            ));
        }
    }
    Ok(d)
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn normalise(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    a.map(|v| v / n)
}

/// Distinct measured positions of each axis (mm, rounded to 1 µm), X, Y, Z.
pub fn measured_positions(data: &LineData) -> [Vec<f64>; 3] {
    [0, 1, 2].map(|a| {
        let mut v: Vec<i64> = data
            .channels
            .iter()
            .filter(|c| c.direction[a].abs() > 1e-9)
            .flat_map(|c| c.points_mm.iter().map(move |p| (p[a] * 1e3).round() as i64))
            .collect();
        v.sort_unstable();
        v.dedup();
        v.into_iter().map(|p| p as f64 * 1e-3).collect()
    })
}
