//! Cubic B-splines with knots chosen from the data, the alternative to the Legendre basis for
//! error functions with local features (a guideway joint, a scraped spot) that a polynomial of
//! the whole travel can only follow by raising its degree everywhere.
//!
//! Knots: the clamped knot vector of a cubic spline on the travel [q_min, q_max] (q_min and
//! q_max four times each) with `interior` knots at the quantiles j/(interior + 1) of the axis
//! positions the lines measure (de Boor, *A Practical Guide to Splines*, 2001, ch. XIII: knots
//! placed so that each interval holds about as many data; with the Schoenberg–Whitney condition
//! met when every function has a measured position in its support, which [`Spline::new`]
//! checks). The functions B_j are evaluated by the Cox–de Boor recursion (de Boor ch. IX, eq. 16)
//!   B_{j,0}(q) = 1 on [t_j, t_{j+1}), B_{j,k}(q) = (q − t_j)/(t_{j+k} − t_j)·B_{j,k−1}(q)
//!                + (t_{j+k+1} − q)/(t_{j+k+1} − t_{j+1})·B_{j+1,k−1}(q).
//!
//! The conventions of the Legendre basis ([`super::basis`]) hold for the spline columns too:
//! - zero at the origin: B_0 is the only function that is not zero at q_min (clamped knots), so
//!   it is left out: the columns are B_1 .. B_{n−1};
//! - straightness from its least-squares reference line: each column is B_j − b_j·(x + 1), b_j
//!   the least-squares slope of B_j against x ∈ [−1, 1] over the travel (so the column is still
//!   zero at the origin and has no slope), and the last function B_{n−1} is left out because the
//!   line x + 1 lies in the span (its B-spline coefficients are the Greville abscissae + 1, the
//!   last one 2 ≠ 0): the columns span the splines zero at the origin with no slope.

/// A cubic spline space on an axis travel.
#[derive(Debug, Clone, PartialEq)]
pub struct Spline {
    /// Interior knots chosen from the data, mm.
    pub interior: Vec<f64>,
    /// The full clamped knot vector, mm.
    knots: Vec<f64>,
    /// Least-squares slopes removed from the columns (straightness), else empty.
    slopes: Vec<f64>,
    travel: [f64; 2],
}

/// Degree of the splines.
const K: usize = 3;

impl Spline {
    /// The spline space with `interior` knots at the quantiles of `positions` (the measured
    /// axis positions, sorted and distinct) on `travel`; `straightness` removes the slope. None
    /// if some function would have no measured position inside its support (the data cannot
    /// determine its coefficient).
    pub fn new(
        positions: &[f64],
        travel: [f64; 2],
        interior: usize,
        straightness: bool,
    ) -> Option<Spline> {
        if positions.len() < 2 {
            return None;
        }
        let quantile = |f: f64| {
            let r = f * (positions.len() - 1) as f64;
            let i = (r.floor() as usize).min(positions.len() - 2);
            positions[i] + (r - i as f64) * (positions[i + 1] - positions[i])
        };
        let inner: Vec<f64> = (1..=interior)
            .map(|j| quantile(j as f64 / (interior + 1) as f64))
            .collect();
        let mut knots = vec![travel[0]; K + 1];
        knots.extend(&inner);
        knots.extend([travel[1]; K + 1]);
        let mut s = Spline {
            interior: inner,
            knots,
            slopes: Vec::new(),
            travel,
        };
        // Schoenberg–Whitney: a distinct measured position inside the support of every used
        // function (greedy matching in order: supports and positions are both sorted)
        let n = s.n_functions();
        let mut next = 0;
        for j in 1..n {
            let (a, b) = (s.knots[j], s.knots[j + K + 1]);
            while next < positions.len() && positions[next] <= a {
                next += 1;
            }
            if next == positions.len() || positions[next] >= b {
                return None;
            }
            next += 1;
        }
        if straightness {
            // b_j = Σ (x − x̄)(B_j − B̄_j) / Σ (x − x̄)² on a fine uniform grid of the travel
            let m = 2001;
            let xs: Vec<f64> = (0..m)
                .map(|i| -1.0 + 2.0 * i as f64 / (m - 1) as f64)
                .collect();
            let sxx: f64 = xs.iter().map(|x| x * x).sum();
            let mut slopes = vec![0.0; n];
            let mut means = vec![0.0; n];
            let vals: Vec<Vec<f64>> = xs.iter().map(|&x| s.all(s.q(x))).collect();
            for v in &vals {
                for j in 0..n {
                    means[j] += v[j] / m as f64;
                }
            }
            for (x, v) in xs.iter().zip(&vals) {
                for j in 0..n {
                    slopes[j] += x * (v[j] - means[j]) / sxx;
                }
            }
            s.slopes = slopes;
        }
        Some(s)
    }

    fn q(&self, x: f64) -> f64 {
        self.travel[0] + (x + 1.0) / 2.0 * (self.travel[1] - self.travel[0])
    }

    fn x(&self, q: f64) -> f64 {
        (2.0 * q - self.travel[0] - self.travel[1]) / (self.travel[1] - self.travel[0])
    }

    /// Number of B-splines n = interior + 4.
    pub fn n_functions(&self) -> usize {
        self.knots.len() - K - 1
    }

    /// Number of columns: n − 1 (zero at the origin), n − 2 for a straightness.
    pub fn n_cols(&self) -> usize {
        self.n_functions() - if self.slopes.is_empty() { 1 } else { 2 }
    }

    /// B_0(q) .. B_{n−1}(q) by the Cox–de Boor recursion (q clamped to the travel; the last
    /// interval is closed so that B_{n−1}(q_max) = 1).
    pub fn all(&self, q: f64) -> Vec<f64> {
        let t = &self.knots;
        let n = self.n_functions();
        let q = q.clamp(self.travel[0], self.travel[1]);
        // the knot interval [t_i, t_{i+1}) holding q, i in K..n
        let mut i = K;
        while i + 1 < n && q >= t[i + 1] {
            i += 1;
        }
        // degree 0, then raise: b[j] holds B_{i−k+j, k}
        let mut b = vec![0.0; K + 1];
        b[0] = 1.0;
        for k in 1..=K {
            let mut next = vec![0.0; K + 1];
            for j in 0..=k {
                let idx = i + j - k; // function index
                let mut v = 0.0;
                if j >= 1 {
                    // (q − t_idx)/(t_{idx+k} − t_idx) · B_{idx,k−1}
                    let d = t[idx + k] - t[idx];
                    if d > 0.0 {
                        v += (q - t[idx]) / d * b[j - 1];
                    }
                }
                if j < k {
                    // (t_{idx+k+1} − q)/(t_{idx+k+1} − t_{idx+1}) · B_{idx+1,k−1}
                    let d = t[idx + k + 1] - t[idx + 1];
                    if d > 0.0 {
                        v += (t[idx + k + 1] - q) / d * b[j];
                    }
                }
                next[j] = v;
            }
            b = next;
        }
        let mut out = vec![0.0; n];
        for (j, v) in b.into_iter().enumerate() {
            out[i - K + j] = v;
        }
        out
    }

    /// The column values at q (see the module docs).
    pub fn columns(&self, q: f64) -> impl Iterator<Item = f64> + '_ {
        let all = self.all(q);
        let x1 = self.x(q) + 1.0;
        let last = self.n_cols() + 1;
        (1..last).map(move |j| all[j] - self.slopes.get(j).map_or(0.0, |b| b * x1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<f64> {
        (0..=20).map(|k| 10.0 + 29.0 * k as f64).collect()
    }

    #[test]
    fn functions_are_a_partition_of_unity_and_match_scipy() {
        let s = Spline::new(&grid(), [0.0, 600.0], 3, false).unwrap();
        for k in 0..=60 {
            let q = 10.0 * k as f64;
            let sum: f64 = s.all(q).iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "{q}: {sum}");
        }
        // scipy.interpolate.BSpline(t, e_j, 3)(123.0), j = 0..3, with t = [0]*4 + [155, 300,
        // 445] + [600]*4 (the knots chosen here; scipy 1.17.1): an independent Cox–de Boor
        let b = s.all(123.0);
        let scipy = [
            0.0087994360712967,
            0.40671633916283445,
            0.494554685077576,
            0.08992953968829286,
        ];
        for j in 0..4 {
            assert!((b[j] - scipy[j]).abs() < 1e-12, "{b:?}");
        }
        assert!((s.all(600.0)[6] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn columns_are_zero_at_the_origin_and_straightness_has_no_slope() {
        let s = Spline::new(&grid(), [0.0, 600.0], 4, true).unwrap();
        assert!(s.columns(0.0).all(|v| v.abs() < 1e-15));
        assert_eq!(s.columns(0.0).count(), 4 + 4 - 2);
        let m = 4001;
        let n = s.n_cols();
        let mut slope = vec![0.0; n];
        for i in 0..m {
            let x = -1.0 + 2.0 * i as f64 / (m - 1) as f64;
            for (j, v) in s.columns(300.0 * (x + 1.0)).enumerate() {
                slope[j] += x * v / m as f64;
            }
        }
        // 1e-4: the quadrature of this grid against the 2001 points of the removal (the slopes
        // removed are ~0.1)
        assert!(slope.iter().all(|v| v.abs() < 1e-4), "{slope:?}");
    }

    #[test]
    fn a_knot_count_the_data_cannot_support_is_refused() {
        // 21 points carry at most 21 coefficients: 17 interior knots make 20 columns, 18 make 21
        // columns, which leave no point for one of them (the one at the origin is not used)
        let s = Spline::new(&grid(), [0.0, 600.0], 3, false).unwrap();
        assert_eq!(s.interior, [155.0, 300.0, 445.0]);
        assert!(Spline::new(&grid(), [0.0, 600.0], 16, false).is_some());
        assert!(Spline::new(&grid(), [0.0, 600.0], 40, false).is_none());
    }
}
