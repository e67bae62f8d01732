//! Volumetric error maps: a regular (rectilinear) grid of measured errors with trilinear
//! interpolation, the controller-style baseline of compensation.
//!
//! A grid file is CSV with the columns `x_mm,y_mm,z_mm,ex_um,ey_um,ez_um` (SPEC §4), one row per
//! grid node. [`GridMap::read_csv`] checks, with messages that name file, line and column:
//! - every number is finite;
//! - the rows form a full tensor grid: with the distinct x, y, z values x₀<…<x_{nx−1} (likewise
//!   y, z), each of the nx·ny·nz combinations appears exactly once. Rows may come in any order
//!   (the grid is sorted); a duplicated node is refused naming both lines; a value that appears
//!   in fewer rows than a grid value must (a stray point, a typo) is reported at its first row;
//!   a missing node is named by its coordinates;
//! - per-controller limits when asked ([`GridLimits`]): at most N points per axis (FANUC-style 3-D
//!   compensation allows 25 per axis in some controllers, the source literature's figure;
//!   LinuxCNC's `COMP_FILE` holds 256 triplets per joint), and equal spacing.
//!
//! Decisions where the spec is silent:
//! - Coordinates closer than 1e-6 mm (1 nm) are the same grid value (spreadsheet round-off).
//! - Spacing may vary per axis (rectilinear, like SciPy's `RegularGridInterpolator`); equal
//!   spacing is only demanded when a limit asks for it.
//! - An axis with a single value is allowed (a planar map, e.g. z constant): the map is then
//!   independent of that coordinate, which is never "outside".
//! - Outside the grid ([`Outside`], chosen by the user, stored in the map file):
//!   `clamp` (default) evaluates at the nearest point of the grid box (each coordinate clamped to
//!   its axis range: the controller behaviour, the error stays bounded); `extrapolate` continues
//!   the edge cell's trilinear polynomial linearly (identical to SciPy's `fill_value=None`);
//!   `refuse` returns [`OutsideGrid`] (and NaN through the [`ErrorModel`] trait, which correction
//!   turns into a located error). A point within 1e-9 mm of the box counts as inside. Note that
//!   correction evaluates the map at the corrected command, not at the target: with `refuse`, a
//!   target on the edge of the grid whose command moves outside is refused; use `clamp` to
//!   compensate up to the edges.
//!
//! Map JSON (`"format": "mtec.map/1"`): `model` (`"trilinear"`), `outside`, `source`, the axes
//! `x_mm`, `y_mm`, `z_mm` (strictly increasing) and the values `ex_um`, `ey_um`, `ez_um` as flat
//! arrays in C order: node (i, j, k) at index (i·ny + j)·nz + k (x slowest, z fastest — the
//! layout of a NumPy array `values[i, j, k]`).

use mtec_io::plausible::{MAX_ERROR_UM, MAX_POSITION_MM};
use mtec_io::{InputError, Table};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `format` tag of a map file.
pub const MAP_FORMAT: &str = "mtec.map/1";

/// Coordinates closer than this are the same grid value (mm).
const SAME_VALUE_MM: f64 = 1e-6;
/// A point this close outside the grid box counts as inside (mm).
const INSIDE_SLACK_MM: f64 = 1e-9;

/// What a map does at a point outside its grid box.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outside {
    /// Evaluate at the nearest point of the box (each coordinate clamped to its axis range).
    #[default]
    Clamp,
    /// Continue the edge cell's trilinear polynomial (linear extrapolation).
    Extrapolate,
    /// No value: [`GridMap::try_error_um`] fails, [`ErrorModel::error_um`] gives NaN.
    Refuse,
}

impl Outside {
    /// Parses `clamp`, `extrapolate` or `refuse`.
    pub fn parse(s: &str) -> Option<Outside> {
        match s {
            "clamp" => Some(Outside::Clamp),
            "extrapolate" => Some(Outside::Extrapolate),
            "refuse" => Some(Outside::Refuse),
            _ => None,
        }
    }
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Outside::Clamp => "clamp",
            Outside::Extrapolate => "extrapolate",
            Outside::Refuse => "refuse",
        }
    }
}

/// Limits a controller puts on a compensation grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GridLimits {
    /// Largest number of grid values along any one axis.
    pub max_points_per_axis: Option<usize>,
    /// Demand equal spacing along each axis.
    pub require_uniform: bool,
}

impl GridLimits {
    /// Named presets: `fanuc-3d` (≤ 25 points per axis, equal spacing: the controller-style 3-D
    /// compensation of the source literature), `linuxcnc` (≤ 256 per axis: `COMP_FILE` holds 256
    /// triplets per joint), `none`.
    pub fn for_controller(name: &str) -> Option<GridLimits> {
        match name {
            "fanuc-3d" => Some(GridLimits {
                max_points_per_axis: Some(25),
                require_uniform: true,
            }),
            "linuxcnc" => Some(GridLimits {
                max_points_per_axis: Some(256),
                require_uniform: false,
            }),
            "none" => Some(GridLimits::default()),
            _ => None,
        }
    }
}

/// A point outside the grid of a map whose policy is [`Outside::Refuse`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("point ({:.6}, {:.6}, {:.6}) mm is outside the map's grid: {axis} must lie in [{min_mm}, {max_mm}] mm (outside = refuse)", p_mm[0], p_mm[1], p_mm[2])]
pub struct OutsideGrid {
    pub p_mm: [f64; 3],
    pub axis: &'static str,
    pub min_mm: f64,
    pub max_mm: f64,
}

/// A grid map whose parts do not fit together (lengths, ordering, non-finite numbers, limits).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct MapShapeError(pub String);

const AXIS_NAMES: [&str; 3] = ["x_mm", "y_mm", "z_mm"];
const VALUE_NAMES: [&str; 3] = ["ex_um", "ey_um", "ez_um"];

/// One node's [ex, ey, ez, 0] µm, aligned to 32 bytes: a node never straddles two cache lines
/// (the allocator gives 16-byte alignment: every other node was a split load; issue 22).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
struct Node([f64; 4]);

/// A volumetric error map on a rectilinear grid, evaluated by trilinear interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMap {
    axes_mm: [Vec<f64>; 3],
    /// [ex, ey, ez, 0] µm of node (i, j, k) at (i·ny + j)·nz + k: padded to four so that a
    /// corner is one aligned 32-byte load and its three components one vector operation.
    values_um: Vec<Node>,
    outside: Outside,
    source: String,
    /// 1 / step of each equally spaced axis (0 when unequal): cell lookup without a search.
    inv_step: [f64; 3],
    /// 1 / (x_{i+1} − x_i) of every cell of each axis: the fraction of the way through a cell
    /// by a multiplication instead of a division (a division costs several multiplications).
    inv_width: [Vec<f64>; 3],
    /// Each axis' lookup constants, computed once (a single-point evaluation would otherwise
    /// derive them from the axes on every call).
    consts: [AxisConst; 3],
}

/// The per-axis constants of a lookup: the range, 1 / step when equally spaced (else 0), the
/// last cell (as an index and as a float), the index stride of one step (0 for a single-value
/// axis).
#[derive(Debug, Clone, Copy, PartialEq)]
struct AxisConst {
    lo: f64,
    hi: f64,
    inv_step: f64,
    last_cell: usize,
    last_cell_f: f64,
    stride: usize,
}

/// The JSON document of a map (`mtec.map/1`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapFile {
    pub format: String,
    pub model: String,
    #[serde(default)]
    pub outside: Outside,
    #[serde(default)]
    pub source: String,
    pub x_mm: Vec<f64>,
    pub y_mm: Vec<f64>,
    pub z_mm: Vec<f64>,
    pub ex_um: Vec<f64>,
    pub ey_um: Vec<f64>,
    pub ez_um: Vec<f64>,
}

impl GridMap {
    /// A map from its axes (each strictly increasing, finite, ≥ 1 value) and node values in C
    /// order (see the module docs).
    pub fn new(
        axes_mm: [Vec<f64>; 3],
        values_um: Vec<[f64; 3]>,
        outside: Outside,
        source: impl Into<String>,
    ) -> Result<GridMap, MapShapeError> {
        for (a, name) in axes_mm.iter().zip(AXIS_NAMES) {
            if a.is_empty() {
                return Err(MapShapeError(format!("axis `{name}` has no values")));
            }
            if a.len() > i32::MAX as usize {
                return Err(MapShapeError(format!(
                    "axis `{name}` has more than 2³¹ values"
                )));
            }
            if let Some(v) = a.iter().find(|v| !v.is_finite()) {
                return Err(MapShapeError(format!(
                    "axis `{name}` has a non-finite value {v}"
                )));
            }
            if let Some(w) = a.windows(2).find(|w| w[1] <= w[0]) {
                return Err(MapShapeError(format!(
                    "axis `{name}` must be strictly increasing, but {} is followed by {}",
                    w[0], w[1]
                )));
            }
        }
        let n = axes_mm[0].len() * axes_mm[1].len() * axes_mm[2].len();
        if values_um.len() != n {
            return Err(MapShapeError(format!(
                "{} node values for a grid of {}×{}×{} = {n} nodes",
                values_um.len(),
                axes_mm[0].len(),
                axes_mm[1].len(),
                axes_mm[2].len()
            )));
        }
        if let Some(i) = values_um
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MapShapeError(format!("node value {i} is not finite")));
        }
        // a metre of error is a unit mistake, not a machine (crate mtec_io::plausible); such a
        // node would reach a controller table unbounded
        if let Some(i) = values_um
            .iter()
            .position(|v| v.iter().any(|c| c.abs() >= MAX_ERROR_UM))
        {
            let [x, y, z] = values_um[i];
            return Err(MapShapeError(format!(
                "node value {i} ({x:e}, {y:e}, {z:e}) um is implausible (|error| must be below {MAX_ERROR_UM:e} um): check the unit"
            )));
        }
        if let Some((name, v)) = axes_mm.iter().zip(AXIS_NAMES).find_map(|(a, name)| {
            a.iter()
                .find(|v| v.abs() >= MAX_POSITION_MM)
                .map(|v| (name, v))
        }) {
            return Err(MapShapeError(format!(
                "axis `{name}` has {v:e} mm: implausible (|position| must be below {MAX_POSITION_MM:e} mm): check the unit"
            )));
        }
        let mut map = GridMap {
            axes_mm,
            values_um: values_um
                .iter()
                .map(|&[x, y, z]| Node([x, y, z, 0.0]))
                .collect(),
            outside,
            source: source.into(),
            inv_step: [0.0; 3],
            inv_width: Default::default(),
            consts: [AxisConst {
                lo: 0.0,
                hi: 0.0,
                inv_step: 0.0,
                last_cell: 0,
                last_cell_f: 0.0,
                stride: 0,
            }; 3],
        };
        for a in 0..3 {
            let ax = &map.axes_mm[a];
            if ax.len() >= 2 && map.is_uniform(a) {
                map.inv_step[a] = (ax.len() - 1) as f64 / (ax[ax.len() - 1] - ax[0]);
            }
            map.inv_width[a] = ax.windows(2).map(|w| 1.0 / (w[1] - w[0])).collect();
        }
        let (ny, nz) = (map.axes_mm[1].len(), map.axes_mm[2].len());
        for (a, stride) in [(0, ny * nz), (1, nz), (2, 1)] {
            let ax = &map.axes_mm[a];
            let last_cell = ax.len().saturating_sub(2);
            map.consts[a] = AxisConst {
                lo: ax[0],
                hi: ax[ax.len() - 1],
                inv_step: map.inv_step[a],
                last_cell,
                last_cell_f: last_cell as f64,
                stride: if ax.len() > 1 { stride } else { 0 },
            };
        }
        Ok(map)
    }

    /// Reads and validates a grid CSV (`x_mm,y_mm,z_mm,ex_um,ey_um,ez_um`).
    pub fn read_csv(
        path: &Path,
        limits: &GridLimits,
        outside: Outside,
    ) -> Result<GridMap, InputError> {
        let table = Table::read(path)?;
        GridMap::from_table(&table, limits, outside)
    }

    /// Builds a map from a grid table already read (see [`GridMap::read_csv`]).
    pub fn from_table(
        table: &Table,
        limits: &GridLimits,
        outside: Outside,
    ) -> Result<GridMap, InputError> {
        let path = table.path.as_path();
        let mut cols = [0usize; 6];
        for (c, name) in cols
            .iter_mut()
            .zip(AXIS_NAMES.iter().chain(VALUE_NAMES.iter()))
        {
            *c = table.column(name)?;
        }
        let mut rows: Vec<([f64; 3], [f64; 3])> = Vec::with_capacity(table.rows.len());
        for r in &table.rows {
            let mut p = [0.0; 3];
            let mut e = [0.0; 3];
            for a in 0..3 {
                p[a] = table.cell_f64_within(r, cols[a], MAX_POSITION_MM, "mm")?;
                e[a] = table.cell_f64_within(r, cols[3 + a], MAX_ERROR_UM, "um")?;
            }
            rows.push((p, e));
        }
        // distinct values per axis
        let mut axes: [Vec<f64>; 3] = Default::default();
        for a in 0..3 {
            let mut v: Vec<f64> = rows.iter().map(|(p, _)| p[a]).collect();
            v.sort_by(|x, y| x.total_cmp(y));
            let mut nodes: Vec<f64> = Vec::new();
            for x in v {
                match nodes.last() {
                    Some(&last) if x - last <= SAME_VALUE_MM => {}
                    _ => nodes.push(x),
                }
            }
            axes[a] = nodes;
        }
        let n = [axes[0].len(), axes[1].len(), axes[2].len()];
        // every grid value must appear in the same number of rows (regularity)
        let mut index_of_row: Vec<[usize; 3]> = Vec::with_capacity(rows.len());
        for (p, _) in &rows {
            let mut ijk = [0; 3];
            for a in 0..3 {
                ijk[a] = node_index(&axes[a], p[a]);
            }
            index_of_row.push(ijk);
        }
        // a node measured twice is named as such (before the count check, which it also upsets)
        let mut first_row_of_node: std::collections::HashMap<[usize; 3], usize> =
            std::collections::HashMap::new();
        for (r, ijk) in index_of_row.iter().enumerate() {
            if let Some(&first) = first_row_of_node.get(ijk) {
                let first_line = table.rows[first].line;
                let [x, y, z] = rows[r].0;
                return Err(table.error_at(
                    &table.rows[r],
                    AXIS_NAMES[0],
                    format!(
                        "grid node ({x}, {y}, {z}) mm appears twice (first on line {first_line}): each node needs exactly one row"
                    ),
                ));
            }
            first_row_of_node.insert(*ijk, r);
        }
        // the stray value is the one seen in the smallest share of the rows it needs
        let mut worst: Option<(f64, usize, usize, usize, usize)> = None; // (share, axis, node, count, need)
        for a in 0..3 {
            let need = n[0] * n[1] * n[2] / n[a];
            let mut count = vec![0usize; n[a]];
            for ijk in &index_of_row {
                count[ijk[a]] += 1;
            }
            for (node, &c) in count.iter().enumerate() {
                let share = c as f64 / need as f64;
                if c < need && !matches!(worst, Some(w) if share >= w.0) {
                    worst = Some((share, a, node, c, need));
                }
            }
        }
        if let Some((_, a, bad, count, need)) = worst {
            let r = index_of_row
                .iter()
                .position(|ijk| ijk[a] == bad)
                .unwrap_or(0);
            let row = &table.rows[r];
            return Err(table.error_at(
                row,
                AXIS_NAMES[a],
                format!(
                    "not a regular grid: `{}` = {} appears in {count} row(s) but each grid value needs {need} (one per combination of the other two coordinates)",
                    AXIS_NAMES[a], axes[a][bad]
                ),
            ));
        }
        // limits
        for a in 0..3 {
            if let Some(max) = limits.max_points_per_axis {
                if n[a] > max {
                    return Err(InputError::line(
                        path,
                        table.header_line,
                        format!(
                            "the grid has {} values of `{}`; the controller allows at most {max} points per axis",
                            n[a], AXIS_NAMES[a]
                        ),
                    ));
                }
            }
            if limits.require_uniform && n[a] > 2 {
                let step = axes[a][1] - axes[a][0];
                if let Some(w) = axes[a]
                    .windows(2)
                    .find(|w| ((w[1] - w[0]) - step).abs() > 1e-6 * step.abs().max(1.0))
                {
                    return Err(InputError::line(
                        path,
                        table.header_line,
                        format!(
                            "the controller needs equally spaced `{}` values, but the step from {} to {} is {} instead of {step}",
                            AXIS_NAMES[a], w[0], w[1], w[1] - w[0]
                        ),
                    ));
                }
            }
        }
        // place every row; duplicates refused
        let total = n[0] * n[1] * n[2];
        let mut slot_row: Vec<Option<usize>> = vec![None; total];
        let mut values = vec![[0.0; 3]; total];
        for (r, ijk) in index_of_row.iter().enumerate() {
            let idx = (ijk[0] * n[1] + ijk[1]) * n[2] + ijk[2];
            if let Some(first) = slot_row[idx] {
                let row = &table.rows[r];
                return Err(table.error_at(
                    row,
                    "x_mm",
                    format!(
                        "duplicate grid node ({}, {}, {}) mm: already given on line {}",
                        rows[r].0[0], rows[r].0[1], rows[r].0[2], table.rows[first].line
                    ),
                ));
            }
            slot_row[idx] = Some(r);
            values[idx] = rows[r].1;
        }
        if let Some(idx) = slot_row.iter().position(|s| s.is_none()) {
            let (i, j, k) = (idx / (n[1] * n[2]), (idx / n[2]) % n[1], idx % n[2]);
            return Err(InputError::file(
                path,
                format!(
                    "incomplete grid: no row for node ({}, {}, {}) mm ({}×{}×{} = {total} nodes expected, {} rows given)",
                    axes[0][i], axes[1][j], axes[2][k], n[0], n[1], n[2], rows.len()
                ),
            ));
        }
        GridMap::new(axes, values, outside, path.display().to_string())
            .map_err(|e| InputError::file(path, e.to_string()))
    }

    /// The map as its JSON document.
    pub fn to_file(&self) -> MapFile {
        let col = |c: usize| self.values_um.iter().map(|v| v.0[c]).collect::<Vec<f64>>();
        MapFile {
            format: MAP_FORMAT.to_string(),
            model: "trilinear".to_string(),
            outside: self.outside,
            source: self.source.clone(),
            x_mm: self.axes_mm[0].clone(),
            y_mm: self.axes_mm[1].clone(),
            z_mm: self.axes_mm[2].clone(),
            ex_um: col(0),
            ey_um: col(1),
            ez_um: col(2),
        }
    }

    /// A map from its JSON document, checked.
    pub fn from_file(f: MapFile) -> Result<GridMap, MapShapeError> {
        if f.format != MAP_FORMAT {
            return Err(MapShapeError(format!(
                "format is `{}`, expected `{MAP_FORMAT}`",
                f.format
            )));
        }
        if f.model != "trilinear" {
            return Err(MapShapeError(format!(
                "model `{}` is not a grid map model (expected `trilinear`)",
                f.model
            )));
        }
        let n = f.ex_um.len();
        if f.ey_um.len() != n || f.ez_um.len() != n {
            return Err(MapShapeError(format!(
                "ex_um, ey_um, ez_um have {}, {}, {} values: they must be equally long",
                n,
                f.ey_um.len(),
                f.ez_um.len()
            )));
        }
        let values = (0..n)
            .map(|i| [f.ex_um[i], f.ey_um[i], f.ez_um[i]])
            .collect();
        GridMap::new([f.x_mm, f.y_mm, f.z_mm], values, f.outside, f.source)
    }

    /// Checks the map against controller limits.
    pub fn check_limits(&self, limits: &GridLimits) -> Result<(), MapShapeError> {
        for (a, name) in AXIS_NAMES.iter().enumerate() {
            let n = self.axes_mm[a].len();
            if let Some(max) = limits.max_points_per_axis {
                if n > max {
                    return Err(MapShapeError(format!(
                        "{n} values of `{name}`; the controller allows at most {max} points per axis"
                    )));
                }
            }
            if limits.require_uniform && !self.is_uniform(a) {
                return Err(MapShapeError(format!(
                    "the controller needs equally spaced `{name}` values"
                )));
            }
        }
        Ok(())
    }

    /// True when the grid values along axis `a` (0 = x) are equally spaced.
    pub fn is_uniform(&self, a: usize) -> bool {
        let ax = &self.axes_mm[a];
        if ax.len() < 3 {
            return true;
        }
        let step = ax[1] - ax[0];
        ax.windows(2)
            .all(|w| ((w[1] - w[0]) - step).abs() <= 1e-6 * step.abs().max(1.0))
    }

    /// The grid values of the three axes (mm).
    pub fn axes_mm(&self) -> &[Vec<f64>; 3] {
        &self.axes_mm
    }

    /// Error [ex, ey, ez] µm stored at node (i, j, k).
    pub fn node_um(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let n = [self.axes_mm[1].len(), self.axes_mm[2].len()];
        let [x, y, z, _] = self.values_um[(i * n[0] + j) * n[1] + k].0;
        [x, y, z]
    }

    /// The behaviour outside the grid.
    pub fn outside(&self) -> Outside {
        self.outside
    }

    /// The same map with another outside-grid behaviour.
    pub fn with_outside(mut self, outside: Outside) -> GridMap {
        self.outside = outside;
        self
    }

    /// The same map with another provenance text.
    pub fn with_source(mut self, source: impl Into<String>) -> GridMap {
        self.source = source.into();
        self
    }

    /// Where the map came from (the grid file).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Trilinear interpolation of the error at `p_mm`, following the outside-grid policy.
    #[inline]
    pub fn try_error_um(&self, p_mm: [f64; 3]) -> Result<[f64; 3], OutsideGrid> {
        let lookup = self.lookup();
        match lookup.eval(self.nodes(), p_mm) {
            Some([x, y, z, _]) => Ok([x, y, z]),
            None => Err(self.outside_error(p_mm)),
        }
    }

    /// Trilinear interpolation at many points at once: `out[i]` is
    /// [`ErrorModel::error_um`](crate::ErrorModel::error_um) of `points[i]`, bit for bit (NaN
    /// outside the grid when the policy is `refuse`). No allocation; the per-map constants (axis
    /// ranges, steps, strides, the policy) are read once per call instead of once per point.
    ///
    /// How: blocks of [`BATCH_BLOCK`] points; per block, first each axis locates all points
    /// (cell and fraction, without a branch per point on equally spaced axes, so the compiler
    /// vectorises it), then each point sums its 8 corners, one 4-wide vector operation per
    /// corner. On x86-64 with AVX2 (checked at run time) the same code is compiled for AVX2.
    /// The arithmetic is that of [`GridMap::try_error_um`] operation for operation (no fused
    /// multiply-add), hence the same bits.
    ///
    /// Panics when `out` and `points` differ in length.
    pub fn eval_batch(&self, points: &[[f64; 3]], out: &mut [[f64; 3]]) {
        assert_eq!(
            points.len(),
            out.len(),
            "eval_batch: as many outputs as points"
        );
        let lookup = self.lookup();
        let v = self.nodes();
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above), all the function needs.
            unsafe { eval_batch_avx2(&lookup, v, points, out) };
            return;
        }
        eval_batch_blocks::<false>(&lookup, v, points, out);
    }

    /// The error of a point the policy refuses, naming the first axis outside.
    #[cold]
    fn outside_error(&self, p_mm: [f64; 3]) -> OutsideGrid {
        let a = (0..3)
            .find(|&a| {
                let ax = &self.axes_mm[a];
                ax.len() > 1
                    && !(p_mm[a] >= ax[0] - INSIDE_SLACK_MM
                        && p_mm[a] <= ax[ax.len() - 1] + INSIDE_SLACK_MM)
            })
            .unwrap_or(0);
        let ax = &self.axes_mm[a];
        OutsideGrid {
            p_mm,
            axis: AXIS_NAMES[a],
            min_mm: ax[0],
            max_mm: ax[ax.len() - 1],
        }
    }

    /// The nodes as [ex, ey, ez, 0] µm.
    #[inline]
    fn nodes(&self) -> &[[f64; 4]] {
        // SAFETY: `Node` is `repr(C)` around one [f64; 4]: the same size and layout, with a
        // stricter alignment, so the slice reinterprets the same memory
        unsafe { std::slice::from_raw_parts(self.values_um.as_ptr().cast(), self.values_um.len()) }
    }

    /// The per-map constants of a lookup.
    #[inline]
    fn lookup(&self) -> Lookup<'_> {
        let axis = |a: usize| {
            let c = self.consts[a];
            AxisLookup {
                ax: self.axes_mm[a].as_slice(),
                lo: c.lo,
                hi: c.hi,
                inv_step: c.inv_step,
                inv_width: self.inv_width[a].as_slice(),
                last_cell: c.last_cell,
                last_cell_f: c.last_cell_f,
                stride: c.stride,
            }
        };
        Lookup {
            axes: [axis(0), axis(1), axis(2)],
            outside: self.outside,
        }
    }
}

/// Points per block of [`GridMap::eval_batch`]: the cells and fractions of a block stay in L1.
const BATCH_BLOCK: usize = 64;

/// [`eval_batch_blocks`] compiled for AVX2 (same source, same operations, wider registers).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn eval_batch_avx2(
    lookup: &Lookup<'_>,
    v: &[[f64; 4]],
    points: &[[f64; 3]],
    out: &mut [[f64; 3]],
) {
    eval_batch_blocks::<true>(lookup, v, points, out)
}

/// The batch kernel of [`GridMap::eval_batch`]; `AVX`: the sums in AVX intrinsics (only from
/// [`eval_batch_avx2`]).
#[inline(always)]
fn eval_batch_blocks<const AVX: bool>(
    lookup: &Lookup<'_>,
    v: &[[f64; 4]],
    points: &[[f64; 3]],
    out: &mut [[f64; 3]],
) {
    let mut cell = [[0u32; BATCH_BLOCK]; 3];
    let mut frac = [[0.0f64; BATCH_BLOCK]; 3];
    let mut refused = [false; BATCH_BLOCK];
    for (pts, outs) in points.chunks(BATCH_BLOCK).zip(out.chunks_mut(BATCH_BLOCK)) {
        let n = pts.len();
        refused[..n].fill(false);
        for a in 0..3 {
            lookup.axes[a].locate_block(
                pts,
                a,
                lookup.outside,
                &mut cell[a][..n],
                &mut frac[a][..n],
                &mut refused[..n],
            );
        }
        // the sums, straight into the output (all four lanes kept, the fourth dropped here, so
        // that each linear interpolation is one 4-wide operation)
        for (q, (o, &r)) in outs.iter_mut().zip(&refused[..n]).enumerate() {
            let base = lookup.base([cell[0][q], cell[1][q], cell[2][q]]);
            let t = [frac[0][q], frac[1][q], frac[2][q]];
            #[cfg(target_arch = "x86_64")]
            let [x, y, z, _] = if AVX {
                // SAFETY: AVX is true only inside `eval_batch_avx2`, run when AVX2 is present
                unsafe { lookup.sum_avx(base, t, v) }
            } else {
                lookup.sum(base, t, v)
            };
            #[cfg(not(target_arch = "x86_64"))]
            let [x, y, z, _] = lookup.sum(base, t, v);
            *o = if r { [f64::NAN; 3] } else { [x, y, z] };
        }
    }
}

/// One axis of a [`Lookup`]: the grid values, their range, 1 / step when equally spaced (else
/// 0), the last cell, the index stride of one step (0 for a single-value axis).
#[derive(Clone, Copy)]
struct AxisLookup<'a> {
    ax: &'a [f64],
    lo: f64,
    hi: f64,
    inv_step: f64,
    inv_width: &'a [f64],
    last_cell: usize,
    last_cell_f: f64,
    stride: usize,
}

impl AxisLookup<'_> {
    /// Lower node index of the cell holding `x` and the fraction of the way to the upper node;
    /// `None` when the policy refuses `x`. A single-value axis: (0, 0.0) for any x.
    #[inline(always)]
    fn locate(&self, x: f64, outside: Outside) -> Option<(usize, f64)> {
        if self.stride == 0 {
            return Some((0, 0.0));
        }
        let (x, refuse) = self.admit(x, outside);
        if refuse {
            return None;
        }
        let i = self.cell(x);
        Some((i, self.fraction(i, x)))
    }

    /// The coordinate the policy evaluates at for `x`, and whether it refuses `x`. Within
    /// [`INSIDE_SLACK_MM`] of the range a point is clamped onto it under every policy; beyond,
    /// `clamp` clamps, `extrapolate` keeps `x`, `refuse` refuses (the clamped value it also
    /// gives is only there to keep a batch's cell index in range). NaN stays NaN, unrefused.
    #[inline(always)]
    fn admit(&self, x: f64, outside: Outside) -> (f64, bool) {
        let (lo, hi) = (self.lo, self.hi);
        match outside {
            Outside::Clamp => (x.clamp(lo, hi), false),
            Outside::Extrapolate => {
                let near = x >= lo - INSIDE_SLACK_MM && x <= hi + INSIDE_SLACK_MM;
                (if near { x.clamp(lo, hi) } else { x }, false)
            }
            Outside::Refuse => (
                x.clamp(lo, hi),
                x < lo - INSIDE_SLACK_MM || x > hi + INSIDE_SLACK_MM,
            ),
        }
    }

    /// Lower node of the cell of the admitted `x`: the last grid value ≤ x, kept within
    /// 0..n−2 (direct for equal spacing, binary search otherwise). For equal spacing the
    /// index is clamped as a float, then truncated, which for the value in [0, n−2] (NaN → 0)
    /// is the floor, without a call to libm's floor.
    #[inline(always)]
    fn cell(&self, x: f64) -> usize {
        if self.inv_step > 0.0 {
            let i = ((x - self.lo) * self.inv_step)
                .max(0.0)
                .min(self.last_cell_f);
            // SAFETY: as in `locate_block`: `i` is finite and in [0, n − 2] (`max` maps NaN
            // to 0), and n − 2 fits in an i32 (checked in `GridMap::new`)
            unsafe { i.to_int_unchecked::<i32>() as usize }
        } else {
            self.ax
                .partition_point(|&v| v <= x)
                .saturating_sub(1)
                .min(self.last_cell)
        }
    }

    /// The fraction of the way from node `i` to node `i + 1` at `x`: (x − x_i)·1/(x_{i+1} − x_i).
    #[inline(always)]
    fn fraction(&self, i: usize, x: f64) -> f64 {
        (x - self.ax[i]) * self.inv_width[i]
    }

    /// [`AxisLookup::locate`] of coordinate `a` of every point of a block: cells, fractions,
    /// and `refused` set for the points the policy refuses. Each step is its own loop over the
    /// block, without branches on equally spaced axes, so that it is vectorised.
    #[inline(always)]
    fn locate_block(
        &self,
        pts: &[[f64; 3]],
        a: usize,
        outside: Outside,
        cell: &mut [u32],
        frac: &mut [f64],
        refused: &mut [bool],
    ) {
        if self.stride == 0 {
            cell.fill(0);
            frac.fill(0.0);
            return;
        }
        // the admitted coordinate, kept in `frac` until the fraction replaces it
        match outside {
            Outside::Clamp => self.admit_block(pts, a, Outside::Clamp, frac, refused),
            Outside::Extrapolate => self.admit_block(pts, a, Outside::Extrapolate, frac, refused),
            Outside::Refuse => self.admit_block(pts, a, Outside::Refuse, frac, refused),
        }
        if self.inv_step > 0.0 {
            // as `cell`, with the index clamped as a float (the same integer)
            let last = self.last_cell_f;
            for (c, &x) in cell.iter_mut().zip(frac.iter()) {
                let i = ((x - self.lo) * self.inv_step).max(0.0).min(last);
                // SAFETY: `i` is finite and in [0, n − 2] (`max` maps NaN to 0), and n − 2
                // fits in an i32 (a grid has fewer than 2³¹ values per axis, checked in
                // `GridMap::new`), so the truncation is defined.
                *c = unsafe { i.to_int_unchecked::<i32>() } as u32;
            }
        } else {
            for (c, &x) in cell.iter_mut().zip(frac.iter()) {
                *c = self.cell(x) as u32;
            }
        }
        // the lower nodes and inverse widths of the cells, sliced so that the index needs no
        // check; as `fraction`
        let last = self.last_cell;
        let (lower, inv_width) = (&self.ax[..=last], &self.inv_width[..=last]);
        for (f, &c) in frac.iter_mut().zip(cell.iter()) {
            let i = (c as usize).min(last);
            *f = (*f - lower[i]) * inv_width[i];
        }
    }

    /// The admitted coordinates of a block ([`AxisLookup::admit`]), one policy per loop.
    #[inline(always)]
    fn admit_block(
        &self,
        pts: &[[f64; 3]],
        a: usize,
        outside: Outside,
        xs: &mut [f64],
        refused: &mut [bool],
    ) {
        for ((p, x), r) in pts.iter().zip(xs.iter_mut()).zip(refused.iter_mut()) {
            let (xa, refuse) = self.admit(p[a], outside);
            *x = xa;
            *r |= refuse;
        }
    }
}

/// What one trilinear evaluation needs of a map, gathered once per call of
/// [`GridMap::try_error_um`] or per batch of [`GridMap::eval_batch`] (both go through
/// [`Lookup::sum`] or [`Lookup::sum_avx`], the same operations, so they agree bit for bit).
struct Lookup<'a> {
    axes: [AxisLookup<'a>; 3],
    outside: Outside,
}

impl Lookup<'_> {
    /// The interpolated error at `p` (padded to four), `None` when the policy refuses it. The
    /// policy is matched once, so that each policy's code has no branch on it per axis.
    #[inline(always)]
    fn eval(&self, v: &[[f64; 4]], p: [f64; 3]) -> Option<[f64; 4]> {
        match self.outside {
            Outside::Clamp => self.eval_in(v, p, Outside::Clamp),
            Outside::Extrapolate => self.eval_in(v, p, Outside::Extrapolate),
            Outside::Refuse => self.eval_in(v, p, Outside::Refuse),
        }
    }

    /// [`Lookup::eval`] under the policy `outside`.
    #[inline(always)]
    fn eval_in(&self, v: &[[f64; 4]], p: [f64; 3], outside: Outside) -> Option<[f64; 4]> {
        let [ax, ay, az] = &self.axes;
        let (i0, tx) = ax.locate(p[0], outside)?;
        let (j0, ty) = ay.locate(p[1], outside)?;
        let (k0, tz) = az.locate(p[2], outside)?;
        let base = self.base([i0 as u32, j0 as u32, k0 as u32]);
        Some(self.sum(base, [tx, ty, tz], v))
    }

    /// Index of node `ijk` (the lower corner of its cell).
    #[inline(always)]
    fn base(&self, ijk: [u32; 3]) -> usize {
        let [ax, ay, _] = &self.axes;
        ijk[0] as usize * ax.stride + ijk[1] as usize * ay.stride + ijk[2] as usize
    }

    /// The trilinear interpolation at fractions t = (tx, ty, tz) in the cell with lower node
    /// `base`: seven linear interpolations (1 − t)·a + t·b, four along z, two along y, one
    /// along x (Numerical Recipes 3rd ed. §3.6, eq. 3.6.5, applied one axis at a time); the
    /// form is exact at the nodes (t = 0 or 1) and costs 21 four-wide operations instead of
    /// the 36 of the eight corner weights (issue 22).
    #[inline(always)]
    fn sum(&self, base: usize, [tx, ty, tz]: [f64; 3], v: &[[f64; 4]]) -> [f64; 4] {
        let [ax, ay, az] = &self.axes;
        // the 8 corners of the cell: the strides of a step in x, y, z
        let (sx, sy, sz) = (ax.stride, ay.stride, az.stride);
        // one bounds check for the cell
        let v = &v[base..=base + sx + sy + sz];
        let lerp = |a: [f64; 4], b: [f64; 4], t: f64| -> [f64; 4] {
            let u = 1.0 - t;
            std::array::from_fn(|l| u * a[l] + t * b[l])
        };
        let (c00, c01) = (lerp(v[0], v[sz], tz), lerp(v[sy], v[sy + sz], tz));
        let (c10, c11) = (
            lerp(v[sx], v[sx + sz], tz),
            lerp(v[sx + sy], v[sx + sy + sz], tz),
        );
        lerp(lerp(c00, c01, ty), lerp(c10, c11, ty), tx)
    }
}

impl Lookup<'_> {
    /// [`Lookup::sum`] in AVX intrinsics: the same operations lane by lane (no fused
    /// multiply-add), so the same bits; written out because the compiler split the four lanes
    /// into a pair and a single (the fourth lane is dropped by the caller).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn sum_avx(&self, base: usize, [tx, ty, tz]: [f64; 3], v: &[[f64; 4]]) -> [f64; 4] {
        use std::arch::x86_64::*;
        let [ax, ay, az] = &self.axes;
        let (sx, sy, sz) = (ax.stride, ay.stride, az.stride);
        let v = &v[base..=base + sx + sy + sz];
        let p = v.as_ptr();
        // SAFETY: every offset is within the cell's slice `v` (checked just above)
        let ld = |i: usize| unsafe { _mm256_loadu_pd(p.add(i).cast()) };
        let lerp = |a: __m256d, b: __m256d, t: f64| {
            let (u, t) = (_mm256_set1_pd(1.0 - t), _mm256_set1_pd(t));
            _mm256_add_pd(_mm256_mul_pd(u, a), _mm256_mul_pd(t, b))
        };
        let c00 = lerp(ld(0), ld(sz), tz);
        let c01 = lerp(ld(sy), ld(sy + sz), tz);
        let c10 = lerp(ld(sx), ld(sx + sz), tz);
        let c11 = lerp(ld(sx + sy), ld(sx + sy + sz), tz);
        let r = lerp(lerp(c00, c01, ty), lerp(c10, c11, ty), tx);
        let mut out = [0.0; 4];
        // SAFETY: `out` holds four f64
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), r) };
        out
    }
}

/// Index of the grid value `x` (within [`SAME_VALUE_MM`]) in the sorted `nodes`.
fn node_index(nodes: &[f64], x: f64) -> usize {
    // first node ≥ x − tolerance: nodes are ≥ SAME_VALUE_MM apart, so it is x's own node
    nodes
        .partition_point(|&v| v < x - SAME_VALUE_MM)
        .min(nodes.len() - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ErrorModel;

    fn affine_map(outside: Outside) -> GridMap {
        // e = (1 + 2x + 3y + 4z, x·y, −z) on x ∈ {0, 10, 30}, y ∈ {0, 5}, z ∈ {−1, 1}
        let axes = [vec![0.0, 10.0, 30.0], vec![0.0, 5.0], vec![-1.0, 1.0]];
        let mut values = Vec::new();
        for &x in &axes[0] {
            for &y in &axes[1] {
                for &z in &axes[2] {
                    values.push([1.0 + 2.0 * x + 3.0 * y + 4.0 * z, x * y, -z]);
                }
            }
        }
        GridMap::new(axes, values, outside, "test").unwrap()
    }

    /// Trilinear interpolation reproduces any function of the form a + bx + cy + dz + exy + …
    /// (multilinear) exactly inside each cell: worked by hand at one point.
    #[test]
    fn multilinear_function_is_reproduced() {
        let m = affine_map(Outside::Clamp);
        let e = m.try_error_um([17.0, 2.0, 0.25]).unwrap();
        assert!((e[0] - (1.0 + 34.0 + 6.0 + 1.0)).abs() < 1e-12);
        assert!((e[1] - 34.0).abs() < 1e-12);
        assert!((e[2] + 0.25).abs() < 1e-12);
    }

    #[test]
    fn outside_policies() {
        let p = [40.0, 2.0, 0.0];
        let clamp = affine_map(Outside::Clamp).try_error_um(p).unwrap();
        assert!((clamp[0] - (1.0 + 60.0 + 6.0)).abs() < 1e-12);
        let extra = affine_map(Outside::Extrapolate).try_error_um(p).unwrap();
        assert!((extra[0] - (1.0 + 80.0 + 6.0)).abs() < 1e-12);
        assert!((extra[1] - 80.0).abs() < 1e-12);
        let refuse = affine_map(Outside::Refuse).try_error_um(p).unwrap_err();
        assert_eq!(refuse.axis, "x_mm");
        assert!(affine_map(Outside::Refuse).error_um(p)[0].is_nan());
        // on the edge is inside
        assert!(affine_map(Outside::Refuse)
            .try_error_um([30.0, 5.0, 1.0])
            .is_ok());
    }

    /// The batch gives what the per-point path gives, bit for bit (so also within 1e-12): on
    /// nodes, on cell borders, inside cells, just outside (within the slack), far outside
    /// under each policy, on equally and unequally spaced axes and a single-value axis.
    #[test]
    fn batch_equals_per_point_evaluation() {
        let nonuniform = affine_map(Outside::Clamp); // x: 0, 10, 30 (unequal)
        let uniform = {
            let axes = [
                vec![0.0, 25.0, 50.0, 75.0],
                vec![-10.0, 0.0, 10.0],
                vec![0.0, 0.5],
            ];
            let values = (0..4 * 3 * 2)
                .map(|i| {
                    let f = i as f64;
                    [(f * 0.37).sin(), (f * 0.11).cos() * 3.0, f * f * 1e-3 - 0.2]
                })
                .collect();
            GridMap::new(axes, values, Outside::Clamp, "").unwrap()
        };
        let planar = GridMap::new(
            [vec![0.0, 1.0], vec![0.0, 1.0], vec![50.0]],
            vec![[0.0; 3], [1.0; 3], [2.0; 3], [3.0; 3]],
            Outside::Clamp,
            "",
        )
        .unwrap();
        for map in [nonuniform, uniform, planar] {
            // every node, every mid-cell and border value per axis, and points outside
            let mut values: [Vec<f64>; 3] = Default::default();
            for (v, ax) in values.iter_mut().zip(map.axes_mm()) {
                let (lo, hi) = (ax[0], ax[ax.len() - 1]);
                v.extend(ax.iter().copied());
                v.extend(ax.windows(2).map(|w| 0.5 * (w[0] + w[1])));
                v.extend(ax.windows(2).map(|w| w[1] - 1e-13 * (w[1] - w[0])));
                v.extend([lo - 5e-10, hi + 5e-10, lo - 1e-8, hi + 1e-8]);
                v.extend([lo - 17.0, hi + 3.25, -1e6, 1e6]);
            }
            let mut points = Vec::new();
            for &x in &values[0] {
                for &y in &values[1] {
                    for &z in &values[2] {
                        points.push([x, y, z]);
                    }
                }
            }
            for outside in [Outside::Clamp, Outside::Extrapolate, Outside::Refuse] {
                let m = map.clone().with_outside(outside);
                let mut batch = vec![[0.0; 3]; points.len()];
                m.eval_batch(&points, &mut batch);
                let mut through_trait = vec![[0.0; 3]; points.len()];
                ErrorModel::eval_batch(&m, &points, &mut through_trait);
                // the kernel as compiled without AVX2 (the other path on machines with it)
                let mut generic = vec![[0.0; 3]; points.len()];
                eval_batch_blocks::<false>(&m.lookup(), m.nodes(), &points, &mut generic);
                let mut refused = 0;
                for (((p, b), t), g) in points.iter().zip(&batch).zip(&through_trait).zip(&generic)
                {
                    let one = m.error_um(*p);
                    let same = |a: &[f64; 3]| {
                        a.iter()
                            .zip(one)
                            .all(|(u, v)| u.to_bits() == v.to_bits() || (u.is_nan() && v.is_nan()))
                    };
                    assert!(
                        same(b) && same(t) && same(g),
                        "{outside:?} at {p:?}: {b:?}, {g:?} vs {one:?}"
                    );
                    match m.try_error_um(*p) {
                        Ok(e) => assert_eq!(e.map(f64::to_bits), one.map(f64::to_bits)),
                        Err(_) => {
                            assert!(one.iter().all(|v| v.is_nan()));
                            refused += 1;
                        }
                    }
                }
                // only `refuse` refuses, and it does refuse the far points
                assert_eq!(refused > 0, outside == Outside::Refuse, "{outside:?}");
            }
        }
    }

    /// The threaded batch gives every point exactly what one `eval_batch` call gives, for any
    /// thread count and for sizes around the run quantum (1024) and the thread split.
    #[test]
    fn threaded_batch_equals_one_call() {
        let m = affine_map(Outside::Refuse);
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        // x in −3..33 (the grid is 0..30: some refused), y and z inside and a little out
        let points: Vec<[f64; 3]> = (0..5000)
            .map(|_| [next() * 36.0 - 3.0, next() * 2.2 - 0.1, next() * 1.1 - 0.05])
            .collect();
        for n in [0, 1, 1023, 2047, 2048, 2049, 3073, 5000] {
            let mut one = vec![[0.0; 3]; n];
            m.eval_batch(&points[..n], &mut one);
            for threads in [0, 1, 2, 3, 8] {
                let mut split = vec![[7.0; 3]; n];
                crate::eval_batch_threads(&m, &points[..n], &mut split, threads);
                for (a, b) in one.iter().zip(&split) {
                    for (u, v) in a.iter().zip(b) {
                        assert!(
                            u.to_bits() == v.to_bits() || (u.is_nan() && v.is_nan()),
                            "{n} points, {threads} threads: {a:?} vs {b:?}"
                        );
                    }
                }
            }
        }
    }

    /// The refusal names the first axis outside (x before y before z), as before the batch.
    #[test]
    fn refusal_names_the_first_axis_outside() {
        let m = affine_map(Outside::Refuse);
        assert_eq!(m.try_error_um([5.0, 9.0, 7.0]).unwrap_err().axis, "y_mm");
        assert_eq!(m.try_error_um([5.0, 2.0, 7.0]).unwrap_err().axis, "z_mm");
        let e = m.try_error_um([-1.0, 9.0, 7.0]).unwrap_err();
        assert_eq!((e.axis, e.min_mm, e.max_mm), ("x_mm", 0.0, 30.0));
    }

    #[test]
    fn single_value_axis_is_constant() {
        let axes = [vec![0.0, 1.0], vec![0.0, 1.0], vec![50.0]];
        let values = vec![[0.0; 3], [1.0; 3], [2.0; 3], [3.0; 3]];
        let m = GridMap::new(axes, values, Outside::Refuse, "").unwrap();
        let e = m.try_error_um([0.5, 0.5, -400.0]).unwrap();
        assert!((e[0] - 1.5).abs() < 1e-12);
    }

    #[test]
    fn json_round_trip() {
        let m = affine_map(Outside::Extrapolate);
        let text = serde_json::to_string(&m.to_file()).unwrap();
        let back = GridMap::from_file(serde_json::from_str(&text).unwrap()).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn duplicated_grid_node_is_named_at_its_second_row() {
        let text = "x_mm,y_mm,z_mm,ex_um,ey_um,ez_um\n\
            0,0,0,0,0,0\n0,0,5,0,0,0\n0,5,0,0,0,0\n0,5,5,0,0,0\n\
            5,0,0,0,0,0\n5,0,5,0,0,0\n5,5,0,0,0,0\n0,5,0,1,1,1\n";
        let table = Table::parse(Path::new("grid.csv"), text).unwrap();
        let e = GridMap::from_table(&table, &GridLimits::default(), Outside::Clamp).unwrap_err();
        assert_eq!((e.line, e.column), (Some(9), Some(1)), "{e}");
        assert!(
            e.message
                .contains("(0, 5, 0) mm appears twice (first on line 4)"),
            "{e}"
        );
    }

    #[test]
    fn bad_shapes_refused() {
        let e = GridMap::new(
            [vec![0.0, 0.0], vec![1.0], vec![1.0]],
            vec![[0.0; 3]; 2],
            Outside::Clamp,
            "",
        )
        .unwrap_err();
        assert!(e.0.contains("strictly increasing"));
        let e = GridMap::new(
            [vec![0.0, 1.0], vec![1.0], vec![1.0]],
            vec![[0.0; 3]; 3],
            Outside::Clamp,
            "",
        )
        .unwrap_err();
        assert!(e.0.contains("3 node values"));
    }

    #[test]
    fn values_and_axes_no_machine_has_are_refused() {
        let axes = || [vec![0.0, 10.0], vec![0.0], vec![0.0]];
        let ok = GridMap::new(
            axes(),
            vec![[1.0; 3], [-999_999.0, 0.0, 0.0]],
            Outside::Clamp,
            "t",
        );
        assert!(ok.is_ok());
        let e =
            GridMap::new(axes(), vec![[1.0; 3], [0.0, 1e6, 0.0]], Outside::Clamp, "t").unwrap_err();
        assert!(
            e.0.contains("node value 1") && e.0.contains("implausible"),
            "{}",
            e.0
        );
        let far = [vec![0.0, 1e5], vec![0.0], vec![0.0]];
        let e = GridMap::new(far, vec![[1.0; 3], [1.0; 3]], Outside::Clamp, "t").unwrap_err();
        assert!(e.0.contains("axis `x_mm` has 1e5 mm"), "{}", e.0);
    }
}
