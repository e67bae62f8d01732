//! The ambient-temperature-adaptive feed-axis model (SPEC §1 T(c), after the source patent):
//! the stored model ([`ExpAmbientModel`]) and its fitter ([`ExpAmbient`]), the `exp-ambient` kind.
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
//! - b_b and k_b are time-constant-like rises (°C) and must be positive: the saturating form
//!   1 − exp(−ΔT/β) is the patent's premise (the error levels off as the temperature does).
//!   mtec fits ln b_b and ln k_b as the polynomials of u, so b_b(T_a) = exp(Σ β_c u^c) > 0 at
//!   every ambient, including outside the training levels (a cubic in b_b itself can cross zero
//!   between or beyond the levels, where the model blows up). Until this choice the fit was
//!   free in sign and came out with b_b, k_b < 0 on `feed-axis-ambient` (b_b ≈ −1.5 °C,
//!   b_a ≈ −0.07 µm: an exploding exponential). That is not a sign convention nor the
//!   initialisation: the scenario's zero-point error is the growth of the column head, a slow
//!   body (τ ≈ 300 min), while the bearing sensor settles in minutes, so the error keeps growing
//!   after ΔT_up has levelled off — it is convex in ΔT_up, and only a negative b_b bends the
//!   curve that way. The positive form cannot, so it runs to its linear limit b_b ≫ ΔT, where
//!   1 − exp(−ΔT/b_b) ≈ ΔT/b_b and only the ratio b_a/b_b (µm/°C) is determined;
//! - identifiability is reported: at each training level, ρ = max ΔT / b_b is how far into its
//!   curve the exponential gets. ρ < 0.2 (curvature below 10 %: 1 − e^(−ρ) ≥ 0.9·ρ) means the
//!   data cannot separate b_a from b_b (nor k_a from k_b); the model stores a warning and the
//!   CLI prints it with the determined slope. The remedy is physical, not numerical: longer
//!   warm-ups, or a temperature rise that leads the error instead of lagging it, e.g. a group
//!   of sensors (below) that includes the structure that moves;
//! - ΔT_up and ΔT_nut may each come from several sensors (the patent: "a dimensionality
//!   reduction of several sensors"): the first principal component of the group's standardised
//!   rises on the training rows, expressed in °C as the weighted mean ΔT = Σ w_j ΔT_j with
//!   w_j ∝ v_j/s_j (v the PC1 loadings, s_j the rise's standard deviation) and Σ w_j = 1, so b_b
//!   and k_b stay in °C. The weights are stored with the model. Standardised (correlation)
//!   PCA, so that a sensor with a large rise does not take the component alone;
use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::fit::{Fit, Predict};
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
    /// The upper-bearing sensor (the first of the group when ΔT_up is a group's component).
    pub up_sensor: String,
    /// The ball-screw-nut sensor (the first of the group, likewise).
    pub nut_sensor: String,
    /// ΔT_up = Σ w_j ΔT_j over these sensors (module docs); empty: `up_sensor` alone.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub up_group: Vec<GroupWeight>,
    /// ΔT_nut likewise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub nut_group: Vec<GroupWeight>,
    pub degree: usize,
    pub b_a: Vec<f64>,
    /// Legacy (files written before ln b_b): polynomial of b_b itself. Empty in new fits.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub b_b: Vec<f64>,
    pub k_a: Vec<f64>,
    /// Legacy, like `b_b`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub k_b: Vec<f64>,
    /// b_b(u) = exp(Σ ln_b_b[c]·u^c) (°C).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ln_b_b: Vec<f64>,
    /// k_b(u) = exp(Σ ln_k_b[c]·u^c) (°C).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ln_k_b: Vec<f64>,
    pub b_a_sd: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub b_b_sd: Vec<f64>,
    pub k_a_sd: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub k_b_sd: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ln_b_b_sd: Vec<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ln_k_b_sd: Vec<f64>,
    pub training_levels: Vec<LevelParams>,
    /// The fitted model at each training level: b_b, k_b and how far into the exponential the
    /// data reach (ρ = max ΔT / b_b).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub identifiability: Vec<LevelIdentifiability>,
    /// Parameters the fit held at their cap, `BETA_CAP_FACTOR` × the largest training rise
    /// (the linear limit, module docs): "b_b", "k_b". Their `_sd` entries are 0.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_at_cap: Vec<String>,
    /// What the data could not determine (module docs); empty when everything was.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// One sensor's weight in a group's temperature rise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupWeight {
    pub sensor: String,
    pub weight: f64,
}

/// The fitted time-constant-like parameters at one training level against the data's range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LevelIdentifiability {
    pub ambient_c: f64,
    pub b_b_c: f64,
    pub k_b_c: f64,
    pub max_dt_up_c: f64,
    pub max_dt_nut_c: f64,
    /// max ΔT_up / b_b and max ΔT_nut / k_b.
    pub rho_up: f64,
    pub rho_nut: f64,
    /// b_a/b_b (µm/°C) and k_a/k_b (µm/mm/°C): the initial slopes, determined even when ρ ≪ 1.
    pub b_slope_um_per_c: f64,
    pub k_slope_um_per_mm_c: f64,
}

/// Below this ρ = max ΔT / β, 1 − e^(−ρ) is within 10 % of ρ: amplitude and time constant
/// cannot be told apart.
pub const RHO_IDENTIFIABLE: f64 = 0.2;

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
    // a falling (negative) rise over a tiny β would overflow: cap the exponent at e^50, so that a
    // trial step of the LM there is rejected for its huge residual instead of aborting the fit
    let e = (-delta / beta).min(50.0).exp();
    (1.0 - e, -e * delta / (beta * beta))
}

/// The least-squares problem of the model with polynomial degree `degree` (0 = one level);
/// parameters [b_a…, ln b_b…, k_a…, ln k_b…] (module docs), of which those with `free[i]`
/// false are held at their value.
struct Problem<'a> {
    rows: &'a [Row],
    degree: usize,
    p: DVector<f64>,
    free: Vec<bool>,
}

impl Problem<'_> {
    fn split(&self) -> [&[f64]; 4] {
        let m = self.degree + 1;
        let s = self.p.as_slice();
        [&s[0..m], &s[m..2 * m], &s[2 * m..3 * m], &s[3 * m..4 * m]]
    }

    /// Jacobian with respect to every parameter, free or not.
    fn full_jacobian(&self) -> Option<DMatrix<f64>> {
        let m = self.degree + 1;
        let [ba, bb, ka, kb] = self.split();
        let mut j = DMatrix::zeros(self.rows.len(), 4 * m);
        for (i, r) in self.rows.iter().enumerate() {
            // β = exp(θ(u)): ∂/∂θ_c = ∂/∂β · β · u^c
            let (beta_b, beta_k) = (poly(bb, r.u).exp(), poly(kb, r.u).exp());
            let (sb, dsb) = sat(r.dt_up, beta_b);
            let (sk, dsk) = sat(r.dt_nut, beta_k);
            let (dsb, dsk) = (dsb * beta_b, dsk * beta_k);
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

    fn free_index(&self) -> Vec<usize> {
        (0..self.free.len()).filter(|&i| self.free[i]).collect()
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, p: &DVector<f64>) {
        for (k, i) in self.free_index().into_iter().enumerate() {
            self.p[i] = p[k];
        }
    }

    fn params(&self) -> DVector<f64> {
        let idx = self.free_index();
        DVector::from_iterator(idx.len(), idx.iter().map(|&i| self.p[i]))
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let [ba, bb, ka, kb] = self.split();
        let r = DVector::from_iterator(
            self.rows.len(),
            self.rows.iter().map(|r| {
                // δ = k·x + b  (model equation)
                let b = poly(ba, r.u) * sat(r.dt_up, poly(bb, r.u).exp()).0;
                let k = poly(ka, r.u) * sat(r.dt_nut, poly(kb, r.u).exp()).0;
                k * r.x + b - r.y
            }),
        );
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let j = self.full_jacobian()?;
        Some(j.select_columns(self.free_index().iter()))
    }
}

fn lm(
    rows: &[Row],
    degree: usize,
    p0: DVector<f64>,
    free: Vec<bool>,
) -> Result<(DVector<f64>, f64), ThermalError> {
    let problem = Problem {
        rows,
        degree,
        p: p0,
        free,
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

/// Largest b_b (k_b) fitted, as a multiple of the largest rise: at ρ = 0.01 the exponential is
/// linear to 0.5 %, and any larger value predicts the same (module docs: linear limit).
pub const BETA_CAP_FACTOR: f64 = 100.0;

/// LM with b_b, k_b bounded above by `caps` (°C): a term whose β runs past its cap at any of
/// the ambient values `us` is held at the cap (ln β ≡ ln cap) and the rest refitted. Returns
/// the parameters, the SSE and which terms ([b, k]) were held.
fn lm_capped(
    rows: &[Row],
    degree: usize,
    mut p: DVector<f64>,
    caps: [f64; 2],
    us: &[f64],
) -> Result<(DVector<f64>, f64, [bool; 2]), ThermalError> {
    let m = degree + 1;
    let mut held = [false; 2];
    loop {
        let mut free = vec![true; 4 * m];
        for (t, seg) in [(0, 1), (1, 3)] {
            if held[t] {
                for c in 0..m {
                    p[seg * m + c] = if c == 0 { caps[t].ln() } else { 0.0 };
                    free[seg * m + c] = false;
                }
            }
        }
        let (q, sse) = lm(rows, degree, p.clone(), free)?;
        let mut changed = false;
        for (t, seg) in [(0, 1), (1, 3)] {
            let theta = &q.as_slice()[seg * m..(seg + 1) * m];
            if !held[t] && us.iter().any(|&u| !(poly(theta, u).exp() <= caps[t])) {
                held[t] = true;
                changed = true;
            }
        }
        if !changed {
            return Ok((q, sse, held));
        }
        p = q;
    }
}

/// Exponential fit at one level: grid over positive (b_b, k_b) with (b_a, k_a) linear, then LM
/// with the caps. Returns [b_a, b_b, k_a, k_b].
fn fit_level(rows: &[Row], caps: [f64; 2]) -> Result<[f64; 4], ThermalError> {
    let max_up = rows.iter().fold(0.0_f64, |m, r| m.max(r.dt_up.abs()));
    let max_nut = rows.iter().fold(0.0_f64, |m, r| m.max(r.dt_nut.abs()));
    let factors = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0];
    let mut best = (f64::INFINITY, [0.0; 4]);
    let y = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.y));
    for fb in factors {
        for fk in factors {
            let (bb, kb) = ((fb * max_up).min(caps[0]), (fk * max_nut).min(caps[1]));
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
    let [ba, bb, ka, kb] = best.1;
    let p0 = DVector::from_column_slice(&[ba, bb.ln(), ka, kb.ln()]);
    let (p, _, _) = lm_capped(rows, 0, p0, caps, &[0.0])?;
    Ok([p[0], p[1].exp(), p[2], p[3].exp()])
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

/// ΔT = Σ w_j ΔT_j of a weighted group.
fn group_rise(data: &ThermalData, group: &[GroupWeight]) -> Result<Vec<f64>, ThermalError> {
    let mut out = vec![0.0; data.len()];
    for g in group {
        let r = rise(data, data.sensor_index(&g.sensor)?);
        for (o, v) in out.iter_mut().zip(r) {
            *o += g.weight * v;
        }
    }
    Ok(out)
}

/// Weights of a sensor group's temperature rise: the first principal component of the
/// standardised rises, rescaled to a weighted mean in °C (module docs). One sensor: weight 1.
pub fn group_weights(
    data: &ThermalData,
    sensors: &[String],
) -> Result<Vec<GroupWeight>, ThermalError> {
    if sensors.is_empty() {
        return Err(ThermalError::Invalid(
            "a temperature-rise group needs at least one sensor".into(),
        ));
    }
    let idx: Vec<usize> = sensors
        .iter()
        .map(|s| data.sensor_index(s))
        .collect::<Result<_, _>>()?;
    let names: Vec<String> = idx.iter().map(|&j| data.sensor_names[j].clone()).collect();
    if idx.len() == 1 {
        return Ok(vec![GroupWeight {
            sensor: names[0].clone(),
            weight: 1.0,
        }]);
    }
    let n = data.len();
    let rises: Vec<Vec<f64>> = idx.iter().map(|&j| rise(data, j)).collect();
    let mut z = DMatrix::zeros(n, idx.len());
    let mut sd = Vec::with_capacity(idx.len());
    for (c, r) in rises.iter().enumerate() {
        let m = r.iter().sum::<f64>() / n as f64;
        let s = (r.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64).sqrt();
        if !(s > 1e-9) {
            return Err(ThermalError::Undetermined(format!(
                "sensor `{}` does not warm up: it cannot weigh in a temperature-rise group",
                names[c]
            )));
        }
        for i in 0..n {
            z[(i, c)] = (r[i] - m) / s;
        }
        sd.push(s);
    }
    // PC1: the leading right singular vector of the standardised rises
    let svd = z.svd(false, true);
    let vt = svd
        .v_t
        .ok_or_else(|| ThermalError::NotConverged("SVD of the sensor group".into()))?;
    let lead = (0..svd.singular_values.len())
        .max_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))
        .unwrap_or(0);
    let raw: Vec<f64> = (0..idx.len()).map(|c| vt[(lead, c)] / sd[c]).collect();
    let total: f64 = raw.iter().sum();
    if !(total.abs() > 1e-12) {
        return Err(ThermalError::Undetermined(
            "the sensor group's first principal component has no common rise (its weights cancel)"
                .into(),
        ));
    }
    Ok(names
        .into_iter()
        .zip(raw)
        .map(|(sensor, w)| GroupWeight {
            sensor,
            weight: w / total,
        })
        .collect())
}

fn rows_of(
    data: &ThermalData,
    up: &[GroupWeight],
    nut: &[GroupWeight],
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
    let (ru, rn) = (group_rise(data, up)?, group_rise(data, nut)?);
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
        Self::fit_groups(data, &[up_sensor.to_string()], &[nut_sensor.to_string()])
    }

    /// Fits the model with ΔT_up and ΔT_nut from sensor groups (first principal component of
    /// each group's rises, module docs); one sensor per group is [`Self::fit`].
    pub fn fit_groups(
        data: &ThermalData,
        up_sensors: &[String],
        nut_sensors: &[String],
    ) -> Result<Self, ThermalError> {
        let up_group = group_weights(data, up_sensors)?;
        let nut_group = group_weights(data, nut_sensors)?;
        let (up_sensor, nut_sensor) = (up_group[0].sensor.clone(), nut_group[0].sensor.clone());
        let rows = rows_of(data, &up_group, &nut_group, true)?;
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
        let (up_name, nut_name) = (up_sensors.join("+"), nut_sensors.join("+"));
        for (name, j) in [(&up_name, 0), (&nut_name, 1)] {
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
        let max_rise = |up: bool| {
            rows.iter().fold(0.0_f64, |m, r| {
                m.max(if up { r.dt_up } else { r.dt_nut }.abs())
            })
        };
        let caps = [
            BETA_CAP_FACTOR * max_rise(true),
            BETA_CAP_FACTOR * max_rise(false),
        ];
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
            let p = fit_level(&lr, caps)?;
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
        p0.extend(pick(|l| l.b_b_c.ln()));
        p0.extend(pick(|l| l.k_a_um_per_mm));
        p0.extend(pick(|l| l.k_b_c.ln()));
        let (p, sse, held) = lm_capped(&rows, degree, DVector::from_vec(p0), caps, &u)?;
        let m = 4 * (degree + 1);
        if rows.len() <= m {
            return Err(ThermalError::TooFewRows {
                rows: rows.len(),
                params: m,
            });
        }
        // covariance σ²(JᵀJ)⁻¹ at the optimum, over the fitted (not held) coefficients
        let d = degree + 1;
        let mut free = vec![true; m];
        for (t, seg) in [(0, 1), (1, 3)] {
            if held[t] {
                free[seg * d..(seg + 1) * d]
                    .iter_mut()
                    .for_each(|f| *f = false);
            }
        }
        let problem = Problem {
            rows: &rows,
            degree,
            p: p.clone(),
            free,
        };
        let jac = problem.jacobian().ok_or_else(|| {
            ThermalError::NotConverged("non-finite Jacobian at the optimum".into())
        })?;
        let jtj = jac.transpose() * &jac;
        let svd = jtj.clone().svd(true, true);
        let smax = svd.singular_values.max();
        let smin = svd.singular_values.min();
        if !(smin > 1e-14 * smax) {
            return Err(ThermalError::Undetermined(format!(
                "the data do not determine all {} fitted coefficients (JᵀJ condition number {:.3e}): measure more positions, longer warm-ups or more ambient levels",
                jac.ncols(),
                smax / smin
            )));
        }
        let sigma2 = sse / (rows.len() - jac.ncols()) as f64;
        let cov = svd
            .pseudo_inverse(0.0)
            .map_err(|e| ThermalError::NotConverged(e.to_string()))?
            * sigma2;
        let mut sd = vec![0.0; m];
        for (k, i) in problem.free_index().into_iter().enumerate() {
            sd[i] = cov[(k, k)].max(0.0).sqrt();
        }
        let seg = |v: &[f64], i: usize| v[i * d..(i + 1) * d].to_vec();
        let ps: Vec<f64> = p.iter().copied().collect();
        let single = |g: Vec<GroupWeight>| if g.len() == 1 { Vec::new() } else { g };
        let mut model = ExpAmbientModel {
            up_sensor,
            nut_sensor,
            up_group: single(up_group),
            nut_group: single(nut_group),
            degree,
            b_a: seg(&ps, 0),
            b_b: Vec::new(),
            k_a: seg(&ps, 2),
            k_b: Vec::new(),
            ln_b_b: seg(&ps, 1),
            ln_k_b: seg(&ps, 3),
            b_a_sd: seg(&sd, 0),
            b_b_sd: Vec::new(),
            k_a_sd: seg(&sd, 2),
            k_b_sd: Vec::new(),
            ln_b_b_sd: seg(&sd, 1),
            ln_k_b_sd: seg(&sd, 3),
            training_levels: per_level,
            identifiability: Vec::new(),
            held_at_cap: Vec::new(),
            warnings: Vec::new(),
        };
        model.held_at_cap = [("b_b", held[0]), ("k_b", held[1])]
            .iter()
            .filter(|(_, h)| *h)
            .map(|(n, _)| n.to_string())
            .collect();
        model.check_identifiability(&rows, &row_level, &distinct);
        Ok(model)
    }

    /// b_b and k_b (°C) at an ambient temperature.
    pub fn time_constants_c(&self, ambient_c: f64) -> (f64, f64) {
        let u = (ambient_c - AMBIENT_REF_C) / AMBIENT_SCALE_C;
        self.betas(u)
    }

    fn betas(&self, u: f64) -> (f64, f64) {
        if self.ln_b_b.is_empty() {
            (poly(&self.b_b, u), poly(&self.k_b, u))
        } else {
            (poly(&self.ln_b_b, u).exp(), poly(&self.ln_k_b, u).exp())
        }
    }

    /// Fills `identifiability` and `warnings` (module docs: ρ = max ΔT / β per level).
    fn check_identifiability(&mut self, rows: &[Row], row_level: &[f64], distinct: &[f64]) {
        let mut weak_b = Vec::new();
        let mut weak_k = Vec::new();
        for &lv in distinct {
            let (mut up, mut nut) = (0.0_f64, 0.0_f64);
            for (r, l) in rows.iter().zip(row_level) {
                if *l == lv {
                    up = up.max(r.dt_up.abs());
                    nut = nut.max(r.dt_nut.abs());
                }
            }
            let u = (lv - AMBIENT_REF_C) / AMBIENT_SCALE_C;
            let (bb, kb) = self.betas(u);
            let (ba, ka) = (poly(&self.b_a, u), poly(&self.k_a, u));
            let li = LevelIdentifiability {
                ambient_c: lv,
                b_b_c: bb,
                k_b_c: kb,
                max_dt_up_c: up,
                max_dt_nut_c: nut,
                rho_up: up / bb,
                rho_nut: nut / kb,
                b_slope_um_per_c: ba / bb,
                k_slope_um_per_mm_c: ka / kb,
            };
            if li.rho_up < RHO_IDENTIFIABLE {
                weak_b.push(li);
            }
            if li.rho_nut < RHO_IDENTIFIABLE {
                weak_k.push(li);
            }
            self.identifiability.push(li);
        }
        let describe = |w: &[LevelIdentifiability], up: bool| -> String {
            w.iter()
                .map(|l| {
                    if up {
                        format!(
                            "{} °C: b_b = {:.3e} °C, largest ΔT_up {:.2} °C, b_a/b_b = {:.4} µm/°C",
                            l.ambient_c, l.b_b_c, l.max_dt_up_c, l.b_slope_um_per_c
                        )
                    } else {
                        format!(
                            "{} °C: k_b = {:.3e} °C, largest ΔT_nut {:.2} °C, k_a/k_b = {:.3e} µm/mm/°C",
                            l.ambient_c, l.k_b_c, l.max_dt_nut_c, l.k_slope_um_per_mm_c
                        )
                    }
                })
                .collect::<Vec<_>>()
                .join("; ")
        };
        let hint = "the error does not level off within the measured rise (it grows at least in proportion, e.g. because the structure that moves lags the sensor); longer warm-ups, or a rise that leads the error (a sensor group that includes the moving structure), would determine both";
        if !weak_b.is_empty() {
            self.warnings.push(format!(
                "b_a and b_b are not separately determined: the exponential stays in its linear range (max ΔT_up / b_b < {RHO_IDENTIFIABLE}), so the data fix only the slope b_a/b_b ({}); {hint}",
                describe(&weak_b, true)
            ));
        }
        if !weak_k.is_empty() {
            self.warnings.push(format!(
                "k_a and k_b are not separately determined: the exponential stays in its linear range (max ΔT_nut / k_b < {RHO_IDENTIFIABLE}), so the data fix only the slope k_a/k_b ({}); {hint}",
                describe(&weak_k, false)
            ));
        }
    }

    pub(crate) fn up_weights(&self) -> Vec<GroupWeight> {
        if self.up_group.is_empty() {
            vec![GroupWeight {
                sensor: self.up_sensor.clone(),
                weight: 1.0,
            }]
        } else {
            self.up_group.clone()
        }
    }

    pub(crate) fn nut_weights(&self) -> Vec<GroupWeight> {
        if self.nut_group.is_empty() {
            vec![GroupWeight {
                sensor: self.nut_sensor.clone(),
                weight: 1.0,
            }]
        } else {
            self.nut_group.clone()
        }
    }

    /// Predicted drift δ (µm) on every row of `data`.
    pub fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        let rows = rows_of(data, &self.up_weights(), &self.nut_weights(), false)?;
        Ok(rows
            .iter()
            .map(|r| self.delta_um(r.u, r.dt_up, r.dt_nut, r.x))
            .collect())
    }

    /// δ (µm) at scaled ambient `u` = (T_amb − 20 °C)/10 °C, rises `dt_up`, `dt_nut` (°C) and
    /// position `x_mm`.
    pub fn delta_um(&self, u: f64, dt_up: f64, dt_nut: f64, x_mm: f64) -> f64 {
        let (bb, kb) = self.betas(u);
        // δ = k·x + b  (model equation)
        let b = poly(&self.b_a, u) * sat(dt_up, bb).0;
        let k = poly(&self.k_a, u) * sat(dt_nut, kb).0;
        k * x_mm + b
    }

    /// Number of fitted coefficients.
    pub fn parameters(&self) -> usize {
        4 * (self.degree + 1)
    }
}

/// The exp-ambient feed-axis model fitter (see [`crate::exp_ambient`]).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct ExpAmbient {
    pub up_sensor: String,
    pub nut_sensor: String,
    /// When not empty, ΔT_up is the first principal component of these sensors' rises (and
    /// `up_sensor` is ignored).
    pub up_sensors: Vec<String>,
    /// Likewise for ΔT_nut.
    pub nut_sensors: Vec<String>,
}

impl Fit for ExpAmbient {
    type Model = ExpAmbientModel;
    fn fit_rows(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> Result<ExpAmbientModel, ThermalError> {
        let pick = |group: &[String], one: &str| {
            if group.is_empty() {
                vec![one.to_string()]
            } else {
                group.to_vec()
            }
        };
        ExpAmbientModel::fit_groups(
            &data.rows(rows),
            &pick(&self.up_sensors, &self.up_sensor),
            &pick(&self.nut_sensors, &self.nut_sensor),
        )
    }
}

impl Predict for ExpAmbientModel {
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        ExpAmbientModel::predict(self, data)
    }
    fn predictors(&self) -> usize {
        self.parameters()
    }
}
