//! The ambient-temperature-adaptive feed-axis model (SPEC §1 T(c), after the source patent):
//!
//! δ(x, t) = k·x + b,  b = b_a·(1 − exp(−ΔT_up/b_b)),  k = k_a·(1 − exp(−ΔT_nut/k_b)),
//!
//! with ΔT_up the temperature rise of the upper bearing, ΔT_nut that of the ball-screw nut, and
//! b_a, b_b, k_a, k_b polynomials of the ambient temperature T_a (cubic in the patent).
//!
//! Decisions where the source is silent:
//! - a temperature rise is measured from the first reading of its experiment (a run starts from
//!   the machine at rest, in equilibrium with the room);
//! - the polynomials are in u = (T_a − 20 °C)/10 °C (conditioning); their degree is
//!   min(3, L − 1) for L distinct ambient levels (experiment means rounded to 0.5 °C): a cubic
//!   needs four levels, and three levels determine at most a quadratic. One level is refused;
//! - b_b and k_b may come out negative: the same form then describes drift that grows faster
//!   than the temperature rise (the measured point lags the sensor), which the positive form
//!   cannot;
//! - fitting: per ambient level, a grid over (b_b, k_b) with (b_a, k_a) solved linearly, then
//!   Levenberg–Marquardt on the four numbers; then the polynomials through the per-level values;
//!   then Levenberg–Marquardt on all coefficients over all rows (`levenberg-marquardt` crate,
//!   analytic Jacobian). Uncertainties are √diag(σ²(JᵀJ)⁻¹) at the optimum, σ² = SSE/(n − m).

use crate::data::ThermalData;
use crate::error::ThermalError;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use serde::{Deserialize, Serialize};

/// Reference and scale of the ambient variable u = (T_a − 20)/10 of the polynomials.
pub const AMBIENT_REF_C: f64 = 20.0;
pub const AMBIENT_SCALE_C: f64 = 10.0;

/// The four exponential parameters at one ambient level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LevelParams {
    pub ambient_c: f64,
    pub b_a_um: f64,
    pub b_b_c: f64,
    pub k_a_um_per_mm: f64,
    pub k_b_c: f64,
}

/// A fitted exp-ambient model: polynomial coefficients (ascending powers of u) and their
/// standard uncertainties.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExpAmbientModel {
    pub up_sensor: String,
    pub nut_sensor: String,
    pub degree: usize,
    pub b_a: Vec<f64>,
    pub b_b: Vec<f64>,
    pub k_a: Vec<f64>,
    pub k_b: Vec<f64>,
    pub b_a_sd: Vec<f64>,
    pub b_b_sd: Vec<f64>,
    pub k_a_sd: Vec<f64>,
    pub k_b_sd: Vec<f64>,
    pub training_levels: Vec<LevelParams>,
}

/// One row of the model's inputs.
#[derive(Debug, Clone, Copy)]
struct Row {
    dt_up: f64,
    dt_nut: f64,
    u: f64,
    x: f64,
    y: f64,
}

fn poly(c: &[f64], u: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, a| acc * u + a)
}

/// 1 − exp(−Δ/β) and its derivative with respect to β.
fn sat(delta: f64, beta: f64) -> (f64, f64) {
    let beta = if beta.abs() < 1e-9 {
        1e-9f64.copysign(beta)
    } else {
        beta
    };
    let e = (-delta / beta).exp();
    (1.0 - e, -e * delta / (beta * beta))
}

/// The least-squares problem of the model with polynomial degree `degree` (0 = one level).
struct Problem<'a> {
    rows: &'a [Row],
    degree: usize,
    p: DVector<f64>,
}

impl Problem<'_> {
    fn split(&self) -> [&[f64]; 4] {
        let m = self.degree + 1;
        let s = self.p.as_slice();
        [&s[0..m], &s[m..2 * m], &s[2 * m..3 * m], &s[3 * m..4 * m]]
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, p: &DVector<f64>) {
        self.p.copy_from(p);
    }

    fn params(&self) -> DVector<f64> {
        self.p.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let [ba, bb, ka, kb] = self.split();
        let r = DVector::from_iterator(
            self.rows.len(),
            self.rows.iter().map(|r| {
                // δ = k·x + b  (model equation)
                let b = poly(ba, r.u) * sat(r.dt_up, poly(bb, r.u)).0;
                let k = poly(ka, r.u) * sat(r.dt_nut, poly(kb, r.u)).0;
                k * r.x + b - r.y
            }),
        );
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let m = self.degree + 1;
        let [ba, bb, ka, kb] = self.split();
        let mut j = DMatrix::zeros(self.rows.len(), 4 * m);
        for (i, r) in self.rows.iter().enumerate() {
            let (sb, dsb) = sat(r.dt_up, poly(bb, r.u));
            let (sk, dsk) = sat(r.dt_nut, poly(kb, r.u));
            let (pba, pka) = (poly(ba, r.u), poly(ka, r.u));
            let mut um = 1.0;
            for c in 0..m {
                j[(i, c)] = sb * um;
                j[(i, m + c)] = pba * dsb * um;
                j[(i, 2 * m + c)] = r.x * sk * um;
                j[(i, 3 * m + c)] = r.x * pka * dsk * um;
                um *= r.u;
            }
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

fn lm(rows: &[Row], degree: usize, p0: DVector<f64>) -> Result<(DVector<f64>, f64), ThermalError> {
    let problem = Problem {
        rows,
        degree,
        p: p0,
    };
    let (done, report) = LevenbergMarquardt::new().minimize(problem);
    if report.termination.was_usage_issue() {
        return Err(ThermalError::NotConverged(format!(
            "{:?}",
            report.termination
        )));
    }
    let sse = done
        .residuals()
        .map(|r| r.norm_squared())
        .unwrap_or(f64::INFINITY);
    if !sse.is_finite() {
        return Err(ThermalError::NotConverged(format!(
            "{:?} with a non-finite residual",
            report.termination
        )));
    }
    Ok((done.p, sse))
}

/// Exponential fit at one level: grid over (b_b, k_b) with (b_a, k_a) linear, then LM.
fn fit_level(rows: &[Row]) -> Result<[f64; 4], ThermalError> {
    let max_up = rows.iter().fold(0.0_f64, |m, r| m.max(r.dt_up.abs()));
    let max_nut = rows.iter().fold(0.0_f64, |m, r| m.max(r.dt_nut.abs()));
    let factors = [
        -16.0, -8.0, -4.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0,
    ];
    let mut best = (f64::INFINITY, [0.0; 4]);
    let y = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.y));
    for fb in factors {
        for fk in factors {
            let (bb, kb) = (fb * max_up, fk * max_nut);
            let a = DMatrix::from_fn(rows.len(), 2, |i, c| {
                let r = rows[i];
                if c == 0 {
                    sat(r.dt_up, bb).0
                } else {
                    r.x * sat(r.dt_nut, kb).0
                }
            });
            if !a.iter().all(|v| v.is_finite()) {
                continue;
            }
            let Ok(sol) = a.clone().svd(true, true).solve(&y, 1e-12) else {
                continue;
            };
            let sse = (&a * &sol - &y).norm_squared();
            if sse < best.0 {
                best = (sse, [sol[0], bb, sol[1], kb]);
            }
        }
    }
    let p0 = DVector::from_column_slice(&best.1);
    let (p, _) = lm(rows, 0, p0)?;
    Ok([p[0], p[1], p[2], p[3]])
}

fn rise(data: &ThermalData, j: usize) -> Vec<f64> {
    let t = data.sensor(j);
    let mut out = vec![0.0; t.len()];
    for (a, b) in data.segments() {
        for i in a..b {
            out[i] = t[i] - t[a];
        }
    }
    out
}

fn rows_of(
    data: &ThermalData,
    up: usize,
    nut: usize,
    need_y: bool,
) -> Result<Vec<Row>, ThermalError> {
    let amb = data
        .ambient_c
        .as_ref()
        .ok_or_else(|| ThermalError::MissingColumn("ambient_c".into()))?;
    let pos = data
        .position_mm
        .as_ref()
        .ok_or_else(|| ThermalError::MissingColumn("position_mm".into()))?;
    let y: Vec<f64> = if need_y {
        data.target_um()?.to_vec()
    } else {
        vec![0.0; data.len()]
    };
    let (ru, rn) = (rise(data, up), rise(data, nut));
    Ok((0..data.len())
        .map(|i| Row {
            dt_up: ru[i],
            dt_nut: rn[i],
            u: (amb[i] - AMBIENT_REF_C) / AMBIENT_SCALE_C,
            x: pos[i],
            y: y[i],
        })
        .collect())
}

/// Ambient level of each experiment (mean ambient rounded to 0.5 °C) and the distinct levels.
fn levels(data: &ThermalData) -> Result<(Vec<f64>, Vec<f64>), ThermalError> {
    let amb = data
        .ambient_c
        .as_ref()
        .ok_or_else(|| ThermalError::MissingColumn("ambient_c".into()))?;
    let mut per_row = vec![0.0; data.len()];
    let mut distinct: Vec<f64> = Vec::new();
    for (a, b) in data.segments() {
        let mean = amb[a..b].iter().sum::<f64>() / (b - a) as f64;
        let level = (mean * 2.0).round() / 2.0;
        per_row[a..b].iter_mut().for_each(|v| *v = level);
        if !distinct.contains(&level) {
            distinct.push(level);
        }
    }
    distinct.sort_by(f64::total_cmp);
    Ok((per_row, distinct))
}

/// Least-squares polynomial of `degree` through (u, v) points (Vandermonde, SVD solve).
fn polyfit(u: &[f64], v: &[f64], degree: usize) -> Vec<f64> {
    let a = DMatrix::from_fn(u.len(), degree + 1, |i, c| u[i].powi(c as i32));
    let b = DVector::from_column_slice(v);
    a.svd(true, true)
        .solve(&b, 1e-12)
        .map(|s| s.iter().copied().collect())
        .unwrap_or_else(|_| vec![0.0; degree + 1])
}

impl ExpAmbientModel {
    /// Fits the model to `data` with the named temperature-rise sensors.
    pub fn fit(
        data: &ThermalData,
        up_sensor: &str,
        nut_sensor: &str,
    ) -> Result<Self, ThermalError> {
        let up = data.sensor_index(up_sensor)?;
        let nut = data.sensor_index(nut_sensor)?;
        let rows = rows_of(data, up, nut, true)?;
        let (row_level, distinct) = levels(data)?;
        if distinct.len() < 2 {
            return Err(ThermalError::Undetermined(format!(
                "the exp-ambient model needs runs at two or more ambient temperatures to determine how its parameters depend on ambient (the patent's cubics need four); the data has one level only: {} °C",
                distinct.first().copied().unwrap_or(f64::NAN)
            )));
        }
        let xs: Vec<f64> = rows.iter().map(|r| r.x).collect();
        let (xmin, xmax) = xs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if !(xmax - xmin > 1e-6) {
            return Err(ThermalError::Undetermined(format!(
                "no position spread: every row is at position_mm = {xmin}; the slope k and the zero-point error b of δ = k·x + b cannot be told apart. Measure at two or more positions along the axis"
            )));
        }
        for (name, j) in [(up_sensor, 0), (nut_sensor, 1)] {
            let max = rows.iter().fold(0.0_f64, |m, r| {
                m.max(if j == 0 { r.dt_up } else { r.dt_nut }.abs())
            });
            if max < 1e-3 {
                return Err(ThermalError::Undetermined(format!(
                    "sensor `{name}` does not warm up (largest rise {max:.4} °C): its exponential term cannot be fitted"
                )));
            }
        }
        let degree = (distinct.len() - 1).min(3);
        let mut per_level = Vec::new();
        for &lv in &distinct {
            let lr: Vec<Row> = rows
                .iter()
                .zip(&row_level)
                .filter(|(_, l)| **l == lv)
                .map(|(r, _)| *r)
                .collect();
            let lx = lr
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                    (a.min(r.x), b.max(r.x))
                });
            if !(lx.1 - lx.0 > 1e-6) {
                return Err(ThermalError::Undetermined(format!(
                    "no position spread at ambient {lv} °C: the slope and zero-point error cannot be told apart there"
                )));
            }
            let p = fit_level(&lr)?;
            per_level.push(LevelParams {
                ambient_c: lv,
                b_a_um: p[0],
                b_b_c: p[1],
                k_a_um_per_mm: p[2],
                k_b_c: p[3],
            });
        }
        let u: Vec<f64> = distinct
            .iter()
            .map(|a| (a - AMBIENT_REF_C) / AMBIENT_SCALE_C)
            .collect();
        let pick = |f: fn(&LevelParams) -> f64| {
            polyfit(&u, &per_level.iter().map(f).collect::<Vec<_>>(), degree)
        };
        let mut p0 = Vec::new();
        p0.extend(pick(|l| l.b_a_um));
        p0.extend(pick(|l| l.b_b_c));
        p0.extend(pick(|l| l.k_a_um_per_mm));
        p0.extend(pick(|l| l.k_b_c));
        let (p, sse) = lm(&rows, degree, DVector::from_vec(p0))?;
        let m = 4 * (degree + 1);
        if rows.len() <= m {
            return Err(ThermalError::TooFewRows {
                rows: rows.len(),
                params: m,
            });
        }
        // covariance σ²(JᵀJ)⁻¹ at the optimum
        let jac = Problem {
            rows: &rows,
            degree,
            p: p.clone(),
        }
        .jacobian()
        .ok_or_else(|| ThermalError::NotConverged("non-finite Jacobian at the optimum".into()))?;
        let jtj = jac.transpose() * &jac;
        let svd = jtj.clone().svd(true, true);
        let smax = svd.singular_values.max();
        let smin = svd.singular_values.min();
        if !(smin > 1e-14 * smax) {
            return Err(ThermalError::Undetermined(format!(
                "the data do not determine all {m} coefficients (JᵀJ condition number {:.3e}): measure more positions, longer warm-ups or more ambient levels",
                smax / smin
            )));
        }
        let sigma2 = sse / (rows.len() - m) as f64;
        let cov = svd
            .pseudo_inverse(0.0)
            .map_err(|e| ThermalError::NotConverged(e.to_string()))?
            * sigma2;
        let sd: Vec<f64> = (0..m).map(|i| cov[(i, i)].max(0.0).sqrt()).collect();
        let d = degree + 1;
        let seg = |v: &[f64], i: usize| v[i * d..(i + 1) * d].to_vec();
        let ps: Vec<f64> = p.iter().copied().collect();
        Ok(ExpAmbientModel {
            up_sensor: data.sensor_names[up].clone(),
            nut_sensor: data.sensor_names[nut].clone(),
            degree,
            b_a: seg(&ps, 0),
            b_b: seg(&ps, 1),
            k_a: seg(&ps, 2),
            k_b: seg(&ps, 3),
            b_a_sd: seg(&sd, 0),
            b_b_sd: seg(&sd, 1),
            k_a_sd: seg(&sd, 2),
            k_b_sd: seg(&sd, 3),
            training_levels: per_level,
        })
    }

    /// Predicted drift δ (µm) on every row of `data`.
    pub fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        let up = data.sensor_index(&self.up_sensor)?;
        let nut = data.sensor_index(&self.nut_sensor)?;
        let rows = rows_of(data, up, nut, false)?;
        Ok(rows
            .iter()
            .map(|r| {
                let b = poly(&self.b_a, r.u) * sat(r.dt_up, poly(&self.b_b, r.u)).0;
                let k = poly(&self.k_a, r.u) * sat(r.dt_nut, poly(&self.k_b, r.u)).0;
                k * r.x + b
            })
            .collect())
    }

    /// Number of fitted coefficients.
    pub fn parameters(&self) -> usize {
        4 * (self.degree + 1)
    }
}
