//! The path bound: how far the tool can stray from the nominal path along one output move.
//!
//! A rewritten straight move commands the axes from `P0` to `P1`; the machine puts the tool at
//! `T(s) = P(s) + e(P(s))` with `P(s) = P0 + s·(P1 − P0)`, `s ∈ [0, 1]`. With `Pk = tk + ck`
//! and the residuals `rk = Pk + e(Pk) − tk` of the correction solve at the ends, the deviation
//! from the nominal point `t(s) = t0 + s·(t1 − t0)` is
//!
//! `T(s) − t(s) = (1 − s)·r0 + s·r1 + g(s)`, `g(s) = e(P(s)) − [(1 − s)·e(P0) + s·e(P1)]`,
//!
//! so `|T(s) − t(s)| ≤ max(|r0|, |r1|) + max_s |g(s)|`: the correction is exact at the ends and
//! the whole error along the move is the departure of the model from its chord, `g`.
//!
//! How `max |g|` is bounded depends on what is known about the model:
//! - **Trilinear grid maps** ([`GridMap`]): along a straight line, inside one cell, the
//!   trilinear polynomial is a cubic in `s` (a product of three affine functions of `s`); the
//!   clamped and extrapolated regions outside the grid are cubic too, and change form only at
//!   grid planes. The move is cut where it crosses a grid plane, the cubic of each piece is
//!   found from four values (Newton's forward differences) and its extremes from the roots of
//!   its derivative: the maximum is exact, not sampled, so a single-node bump between two
//!   sample points cannot hide.
//! - **Other models** (kinematic, polynomial, BPNN): smooth, with no structure mtec can bound
//!   in closed form; `g` is evaluated at samples no further apart than `check_step_mm` (a
//!   dense check, documented as such).
//!
//! For an arc kept as an arc, [`PathBound::variation_um`] bounds `|e(p) − e(q)|` over a box
//! holding the arc: for a grid map the range of the node values of the cells the box touches
//! (trilinear interpolation is a convex combination of its cell's nodes), otherwise samples.

use crate::{map::Outside, ErrorModel};

/// Bounds the model's departure from its chord along moves; reuses its buffers. The model is
/// given to each call (the rewriter's view of it changes with the rotary axes' angles).
pub struct PathBound {
    check_step_mm: f64,
    breaks: Vec<f64>,
    /// Per axis: the box's ends and the grid planes between them ([`PathBound::variation_um`]).
    planes: [Vec<f64>; 3],
}

/// Most points [`PathBound::variation_um`] evaluates for the exact range over a box; a box
/// crossing more grid planes takes the range of the nodes of its cells (cheaper, looser).
const MAX_RANGE_POINTS: usize = 4096;

/// One end of an output move, see [`PathBound::end`].
#[derive(Debug, Clone, Copy)]
pub struct MoveEnd {
    /// The command, mm.
    pub p: [f64; 3],
    /// The model's error at the command, µm.
    pub e: [f64; 3],
    /// |p + e(p) − target|, µm.
    pub residual_um: f64,
}

/// Euclidean norm of a 3-vector.
pub fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn lerp(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * s)
}

/// Largest |p(v)| on v ∈ [0, 3] of the cubic through (0, g0), (1, g1), (2, g2), (3, g3).
fn cubic_max_abs(g: [f64; 4]) -> f64 {
    // Newton forward differences: p(v) = g0 + d1·v + d2·v(v−1)/2 + d3·v(v−1)(v−2)/6
    let d1 = g[1] - g[0];
    let d2 = g[2] - 2.0 * g[1] + g[0];
    let d3 = g[3] - 3.0 * g[2] + 3.0 * g[1] - g[0];
    // in powers of v: c0 + c1·v + c2·v² + c3·v³
    let c1 = d1 - d2 / 2.0 + d3 / 3.0;
    let c2 = d2 / 2.0 - d3 / 2.0;
    let c3 = d3 / 6.0;
    let p = |v: f64| g[0] + v * (c1 + v * (c2 + v * c3));
    let mut m = g[0].abs().max(g[3].abs());
    // p'(v) = c1 + 2·c2·v + 3·c3·v² = 0
    let (a, b, c) = (3.0 * c3, 2.0 * c2, c1);
    let mut consider = |v: f64| {
        if v > 0.0 && v < 3.0 {
            m = m.max(p(v).abs());
        }
    };
    let scale = a.abs().max(b.abs()).max(c.abs());
    if scale == 0.0 {
        return m;
    }
    if a.abs() <= 1e-14 * scale {
        if b != 0.0 {
            consider(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            // the stable form of the two roots
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            if q != 0.0 {
                consider(q / a);
                consider(c / q);
            } else {
                consider(0.0);
            }
        }
    }
    m
}

impl PathBound {
    /// `check_step_mm`: sample spacing of the dense check for models without a grid structure.
    pub fn new(check_step_mm: f64) -> Self {
        PathBound {
            check_step_mm,
            breaks: Vec::new(),
            planes: Default::default(),
        }
    }

    /// True when the bound of `model` is exact (a grid map), false when it comes from samples.
    pub fn is_exact(model: &dyn ErrorModel) -> bool {
        model.as_grid().is_some()
    }

    /// `max_s |g(s)|` in µm along the command segment p0 → p1 (mm), given the model's values
    /// `e0`, `e1` at the ends (`model.error_um(p0)` and `(p1)`: g is zero there by definition,
    /// and not evaluated again). NaN when the model has no value somewhere along it.
    pub fn chord_departure_um(
        &mut self,
        model: &dyn ErrorModel,
        p0: [f64; 3],
        p1: [f64; 3],
        e0: [f64; 3],
        e1: [f64; 3],
    ) -> f64 {
        let g = |model: &dyn ErrorModel, s: f64| -> [f64; 3] {
            let e = model.error_um(lerp(p0, p1, s));
            [0, 1, 2].map(|i| e[i] - (e0[i] + (e1[i] - e0[i]) * s))
        };
        match model.as_grid() {
            Some(grid) => {
                self.breaks.clear();
                self.breaks.push(0.0);
                let axes = grid.axes_mm();
                for a in 0..3 {
                    let d = p1[a] - p0[a];
                    let ax = &axes[a];
                    if ax.len() < 2 || d == 0.0 {
                        continue;
                    }
                    let (lo, hi) = if d > 0.0 {
                        (p0[a], p1[a])
                    } else {
                        (p1[a], p0[a])
                    };
                    let first = ax.partition_point(|&x| x <= lo);
                    // no grid value in (lo, hi) when hi is at most the first value above lo
                    // (the usual short move, inside one cell): the second search is not needed
                    if first == ax.len() || hi <= ax[first] {
                        continue;
                    }
                    let last = ax.partition_point(|&x| x < hi);
                    for &x in &ax[first..last] {
                        self.breaks.push((x - p0[a]) / d);
                    }
                }
                self.breaks.push(1.0);
                if self.breaks.len() > 2 {
                    self.breaks.sort_unstable_by(|a, b| {
                        a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal)
                    });
                }
                let mut worst = [0.0f64; 3];
                // g is zero at both ends: e0 and e1 are the model's values there (a NaN in
                // either reaches every interior value of g, so it is not lost)
                let mut g_prev = [0.0; 3];
                let mut s_prev = 0.0;
                for k in 1..self.breaks.len() {
                    let s1 = self.breaks[k];
                    if s1 <= s_prev || s1.is_nan() {
                        continue;
                    }
                    let h = (s1 - s_prev) / 3.0;
                    let ga = g(model, s_prev + h);
                    let gb = g(model, s_prev + 2.0 * h);
                    let g1 = if s1 >= 1.0 { [0.0; 3] } else { g(model, s1) };
                    for i in 0..3 {
                        let m = cubic_max_abs([g_prev[i], ga[i], gb[i], g1[i]]);
                        worst[i] = if m.is_nan() {
                            f64::NAN
                        } else {
                            worst[i].max(m)
                        };
                    }
                    g_prev = g1;
                    s_prev = s1;
                }
                norm(worst)
            }
            None => {
                let len = norm([0, 1, 2].map(|i| p1[i] - p0[i]));
                let n = ((len / self.check_step_mm).ceil() as usize).clamp(4, 1_000_000);
                let mut worst = 0.0f64;
                for k in 1..n {
                    let v = norm(g(model, k as f64 / n as f64));
                    if v.is_nan() {
                        return f64::NAN;
                    }
                    worst = worst.max(v);
                }
                worst
            }
        }
    }

    /// A bound of `max |e(p) − e(q)|` (µm) for p, q in the box `lo..hi` (mm), for a grid map;
    /// for other models the largest |e(p) − e(first)| over `samples` (points of the path).
    /// Infinity when a grid map extrapolates beyond its nodes inside the box.
    ///
    /// For a grid map it is the norm of the exact range of each component over the box: between
    /// two consecutive grid planes of every axis the map is multilinear (trilinear in a cell,
    /// and constant along an axis where it is clamped), so over each such part of the box each
    /// component takes its extremes at the part's corners; the corners of all parts are the
    /// points whose coordinates are the box's ends or a grid plane between them. (Before
    /// 2026-11-30 it was the range of the node values of every cell the box touches, which for a
    /// map of one large cell, a tilt over ±5 m, was the whole map's range: every arc was cut
    /// into chords.) A box crossing so many planes that this takes more than
    /// [`MAX_RANGE_POINTS`] evaluations gets the range of its cells' nodes.
    pub fn variation_um(
        &mut self,
        model: &dyn ErrorModel,
        lo: [f64; 3],
        hi: [f64; 3],
        samples: &mut dyn Iterator<Item = [f64; 3]>,
    ) -> f64 {
        match model.as_grid() {
            Some(grid) => {
                let axes = grid.axes_mm();
                for a in 0..3 {
                    let ax = &axes[a];
                    let n = ax.len();
                    if n > 1
                        && (lo[a] < ax[0] || hi[a] > ax[n - 1])
                        && grid.outside() != Outside::Clamp
                    {
                        return f64::INFINITY;
                    }
                    let planes = &mut self.planes[a];
                    planes.clear();
                    planes.push(lo[a]);
                    if n > 1 {
                        let first = ax.partition_point(|&x| x <= lo[a]);
                        let last = ax.partition_point(|&x| x < hi[a]).max(first);
                        planes.extend_from_slice(&ax[first..last]);
                        if hi[a] > lo[a] {
                            planes.push(hi[a]);
                        }
                    }
                }
                let points: usize = self.planes.iter().map(Vec::len).product();
                if points <= MAX_RANGE_POINTS {
                    let mut min = [f64::INFINITY; 3];
                    let mut max = [f64::NEG_INFINITY; 3];
                    for &x in &self.planes[0] {
                        for &y in &self.planes[1] {
                            for &z in &self.planes[2] {
                                let v = model.error_um([x, y, z]);
                                if v.iter().any(|c| c.is_nan()) {
                                    return f64::NAN;
                                }
                                for c in 0..3 {
                                    min[c] = min[c].min(v[c]);
                                    max[c] = max[c].max(v[c]);
                                }
                            }
                        }
                    }
                    return norm([0, 1, 2].map(|c| max[c] - min[c]));
                }
                let mut range = [[0usize; 2]; 3];
                for a in 0..3 {
                    let ax = &axes[a];
                    let n = ax.len();
                    if n == 1 {
                        range[a] = [0, 0];
                        continue;
                    }
                    // (a box outside the grid under another policy than clamp returned above)
                    // nodes of the cells that hold lo..hi: the last node ≤ lo to the first ≥ hi
                    let i0 = ax.partition_point(|&x| x <= lo[a]).saturating_sub(1);
                    let i1 = ax.partition_point(|&x| x < hi[a]).min(n - 1);
                    range[a] = [i0.min(n - 1), i1.max(i0.min(n - 1))];
                }
                let mut min = [f64::INFINITY; 3];
                let mut max = [f64::NEG_INFINITY; 3];
                for i in range[0][0]..=range[0][1] {
                    for j in range[1][0]..=range[1][1] {
                        for k in range[2][0]..=range[2][1] {
                            let v = grid.node_um(i, j, k);
                            for c in 0..3 {
                                min[c] = min[c].min(v[c]);
                                max[c] = max[c].max(v[c]);
                            }
                        }
                    }
                }
                norm([0, 1, 2].map(|c| max[c] - min[c]))
            }
            None => {
                let Some(first) = samples.next() else {
                    return 0.0;
                };
                let e0 = model.error_um(first);
                let mut worst = 0.0f64;
                for p in samples {
                    let e = model.error_um(p);
                    let v = norm([0, 1, 2].map(|i| e[i] - e0[i]));
                    if v.is_nan() {
                        return f64::NAN;
                    }
                    worst = worst.max(v);
                }
                worst
            }
        }
    }

    /// One end of an output move: the command `p = t + c` (mm), the model's error `e(p)` (µm)
    /// there, and the residual `|p + e(p) − t|` (µm) of the correction solve.
    pub fn end(model: &dyn ErrorModel, target: [f64; 3], correction: [f64; 3]) -> MoveEnd {
        let p = [0, 1, 2].map(|i| target[i] + correction[i]);
        let e = model.error_um(p);
        let residual_um = norm([0, 1, 2].map(|i| (p[i] - target[i]) * 1e3 + e[i]));
        MoveEnd { p, e, residual_um }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::Outside;
    use crate::GridMap;

    #[test]
    fn cubic_maximum_is_found_between_the_nodes() {
        // p(v) = v(v−1)(v−2)·(−1): values 0 at the first three nodes, −6 at v = 3; its interior
        // extremes at v = 1 ± 1/√3 have |p| = 2/(3√3) ≈ 0.3849
        let m = cubic_max_abs([0.0, 0.0, 0.0, -6.0]);
        assert!((m - 6.0).abs() < 1e-12);
        let m = cubic_max_abs([0.0, 0.0, 0.0, 0.0]);
        assert_eq!(m, 0.0);
        // a parabola with its top at v = 1.5: p = −(v − 1.5)² + 2.25 → p(1.5) = 2.25
        let p = |v: f64| -(v - 1.5) * (v - 1.5) + 2.25;
        let m = cubic_max_abs([p(0.0), p(1.0), p(2.0), p(3.0)]);
        assert!((m - 2.25).abs() < 1e-12, "{m}");
        // the cubic with interior extremes only: v(v−1.5)(v−3) has |p| = 1.299 at v = 1.5 ± √3/2
        let q = |v: f64| v * (v - 1.5) * (v - 3.0);
        let m = cubic_max_abs([q(0.0), q(1.0), q(2.0), q(3.0)]);
        let v = 1.5 - 3f64.sqrt() / 2.0;
        assert!((m - q(v).abs()).abs() < 1e-12, "{m}");
    }

    fn bump_map() -> GridMap {
        // 0..100 mm in steps of 10 on x and y, one z: a 30 µm bump in ey at node (5, 5)
        let xs: Vec<f64> = (0..=10).map(|i| i as f64 * 10.0).collect();
        let mut values = vec![[0.0; 3]; 11 * 11];
        values[5 * 11 + 5] = [0.0, 30.0, 0.0];
        GridMap::new([xs.clone(), xs, vec![0.0]], values, Outside::Clamp, "bump").unwrap()
    }

    #[test]
    fn a_single_node_bump_between_samples_is_seen_exactly() {
        let map = bump_map();
        let mut b = PathBound::new(1.0);
        // a line through the bump's node: the departure from the (zero) chord is the bump
        let p0 = [0.0, 50.0, 0.0];
        let p1 = [100.0, 50.0, 0.0];
        let m = b.chord_departure_um(&map, p0, p1, [0.0; 3], [0.0; 3]);
        assert!((m - 30.0).abs() < 1e-9, "{m}");
        // a line 2.5 mm off the node row: the tent function gives 30·(1 − 0.25) = 22.5 µm
        let m = b.chord_departure_um(
            &map,
            [0.0, 52.5, 0.0],
            [100.0, 52.5, 0.0],
            [0.0; 3],
            [0.0; 3],
        );
        assert!((m - 22.5).abs() < 1e-9, "{m}");
        // a diagonal through the node: along it the bump is (1−|u|)² shaped, peak 30 at the node
        let m = b.chord_departure_um(
            &map,
            [40.0, 40.0, 0.0],
            [60.0, 60.0, 0.0],
            [0.0; 3],
            [0.0; 3],
        );
        assert!((m - 30.0).abs() < 1e-9, "{m}");
        // dense sampling of the same function never exceeds the exact bound
        for k in 0..=1000 {
            let s = k as f64 / 1000.0;
            let e = map.error_um(lerp([40.0, 41.0, 0.0], [60.0, 58.0, 0.0], s));
            let exact = b.chord_departure_um(
                &map,
                [40.0, 41.0, 0.0],
                [60.0, 58.0, 0.0],
                [0.0; 3],
                [0.0; 3],
            );
            assert!(norm(e) <= exact + 1e-9);
        }
    }

    #[test]
    fn variation_over_a_box_is_the_exact_range_of_the_map_on_it() {
        let map = bump_map();
        let mut b = PathBound::new(1.0);
        let none = &mut std::iter::empty();
        let mut v = |b: &mut PathBound, lo: [f64; 2], hi: [f64; 2]| {
            b.variation_um(&map, [lo[0], lo[1], 0.0], [hi[0], hi[1], 0.0], none)
        };
        // the bump is the tent 30·(1 − |x − 50|/10)·(1 − |y − 50|/10) µm on (40, 60)²
        assert_eq!(v(&mut b, [0.0, 0.0], [39.0, 39.0]), 0.0);
        // within one cell: the values at the box's corners, 30·0.5·0.5 − 30·0.1·0.1
        assert!((v(&mut b, [41.0, 41.0], [45.0, 45.0]) - 7.2).abs() < 1e-12);
        // the node inside the box is one of the points: 30 − 30·0.5·0.5
        assert!((v(&mut b, [45.0, 45.0], [55.0, 55.0]) - 22.5).abs() < 1e-12);
        assert_eq!(v(&mut b, [61.0, 0.0], [62.0, 100.0]), 0.0);
        assert_eq!(v(&mut b, [60.0, 0.0], [62.0, 100.0]), 0.0);
        // 0.1 mm into the tent at its crest row: 30·0.01
        assert!((v(&mut b, [59.9, 0.0], [62.0, 100.0]) - 0.3).abs() < 1e-12);
        // clamped outside the grid: the edge values
        assert_eq!(v(&mut b, [-20.0, -20.0], [5.0, 5.0]), 0.0);
        assert!((v(&mut b, [-20.0, 45.0], [45.0, 200.0]) - 15.0).abs() < 1e-12);
        // never below the range of dense samples of the box, never above the nodes' range
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = |lo: f64, hi: f64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (hi - lo) * (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let (x0, y0) = (uniform(-10.0, 100.0), uniform(-10.0, 100.0));
            let (x1, y1) = (x0 + uniform(0.0, 30.0), y0 + uniform(0.0, 30.0));
            let bound = v(&mut b, [x0, y0], [x1, y1]);
            let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..=40 {
                for j in 0..=40 {
                    let p = [
                        x0 + (x1 - x0) * i as f64 / 40.0,
                        y0 + (y1 - y0) * j as f64 / 40.0,
                        0.0,
                    ];
                    let e = map.error_um(p)[1];
                    min = min.min(e);
                    max = max.max(e);
                }
            }
            assert!(max - min <= bound + 1e-9, "{bound} < {}", max - min);
            assert!(bound <= 30.0 + 1e-12);
        }
    }

    /// A box crossing more grid planes than [`MAX_RANGE_POINTS`] allows evaluations for takes
    /// the range of the nodes of its cells.
    #[test]
    fn a_box_over_many_planes_takes_the_range_of_its_cells_nodes() {
        let xs: Vec<f64> = (0..=100).map(|i| i as f64).collect();
        let mut values = vec![[0.0; 3]; 101 * 101];
        values[50 * 101 + 50] = [0.0, 30.0, 0.0];
        let map =
            GridMap::new([xs.clone(), xs, vec![0.0]], values, Outside::Clamp, "bump").unwrap();
        let mut b = PathBound::new(1.0);
        let none = &mut std::iter::empty();
        // 102 × 102 points > 4096: the nodes of the cells, the bump's node among them
        let v = b.variation_um(&map, [0.5, 0.5, 0.0], [99.5, 99.5, 0.0], none);
        assert_eq!(v, 30.0);
        // 62 × 62 points ≤ 4096 (60 planes inside each side): exact, the node is a plane
        let v = b.variation_um(&map, [20.5, 20.5, 0.0], [80.5, 80.5, 0.0], none);
        assert_eq!(v, 30.0);
        let v = b.variation_um(&map, [49.5, 49.5, 0.0], [49.75, 49.75, 0.0], none);
        assert!((v - 30.0 * (0.75 * 0.75 - 0.5 * 0.5)).abs() < 1e-12, "{v}");
    }
}
