//! Ballbar diagnostics: machine faults fitted from a circular-test trace by linear least squares
//! on basis functions derived from the physics of each fault, and ranked by their contribution
//! to the circularity.
//!
//! ## Model
//! The tool moves round a circle of radius R about the nominal centre; the commanded point is
//! p = R(cos θ, sin θ) and it travels with d = +1 (ccw, increasing θ) or d = −1 (cw), so the
//! commanded velocity is v = d·ω·R(−sin θ, cos θ). An axis error e = (e₁, e₂) (µm, axis 1 and
//! axis 2 of the plane) changes the bar length, to first order in e/R, by
//!
//!   dl = n·e = e₁ cos θ + e₂ sin θ,      n = (cos θ, sin θ)                              (1)
//!
//! Each fault below gives e as a function of position and direction of motion; (1) turns it
//! into a column of the design matrix, scaled so that its coefficient is the fault in the unit
//! it is reported in. The trace is the sum of all columns plus noise; the coefficients are the
//! linear least-squares solution (nalgebra SVD), their standard errors come from
//! σ̂²(AᵀA)⁻¹.
//!
//! | fault | error motion | column in dl (µm per unit) |
//! |---|---|---|
//! | radius (bar length / mean scale) | — | 1 |
//! | centre offset (trace centre − pivot) | e = (c₁, c₂) | cos θ, sin θ |
//! | scale mismatch s₁ − s₂ (ppm) | e = (s₁x, s₂y) → dl = R(s₁+s₂)/2 + R(s₁−s₂)/2·cos 2θ | R/2·cos 2θ |
//! | squareness α (µm/m): axis 2 leans towards axis 1 | e₁ = α·y | R/2·sin 2θ |
//! | servo mismatch τ₁ − τ₂ (ms): axis i lags its command by τᵢ | eᵢ = −τᵢvᵢ | d·v_f/2·sin 2θ (v_f = feed) |
//! | backlash of axis 1, b⁺ at +R and b⁻ at −R (µm) | e₁ = −sgn(v₁)·g(x)/2, g(x) = (b⁺+b⁻)/2 + (b⁺−b⁻)/2·x/R | d·sgn(sin θ)·cos θ·(1 ± cos θ)/4 |
//! | backlash of axis 2 | e₂ = −sgn(v₂)·h(y)/2 | −d·sgn(cos θ)·sin θ·(1 ± sin θ)/4 |
//! | lateral play of axis 1 (µm): its carriage shifts sideways when it reverses | e₂ = −sgn(v₁)·p/2 | d·abs(sin θ)/2 |
//! | lateral play of axis 2 | e₁ = −sgn(v₂)·p/2 | −d·abs(cos θ)/2 |
//! | reversal spike of axis i (µm): stick–slip after the axis reverses, decaying while the integrator catches up | outward, exp(−Δθ/w) for the travel Δθ since the reversal | exp(−Δθ/w), w = 3° |
//! | straightness of axis 1 (µm): a bow of peak-to-valley S over ±R | e₂ = S·(x/R)² | sin θ·cos² θ |
//! | straightness of axis 2 | e₁ = S·(y/R)² | cos θ·sin² θ |
//! | cyclic error of axis i: amplitude A, pitch P (scale or screw periodicity) | e₁ = a cos(2πx/P) + b sin(2πx/P) | cos θ·cos(2πx/P), cos θ·sin(2πx/P) |
//!
//! The cyclic pitch enters non-linearly: it is found by scanning the spatial frequency 1/P over
//! [1/(R/2), 1/1 mm] (steps fine enough that the phase over the 2R travel moves < 0.5 rad) for the
//! largest explained variance of the residual, refined by golden-section search, and then fitted
//! jointly with everything else.
//!
//! Backlash is lost motion (a play operator): the table stands still after a reversal until the
//! drive has taken up the gap. The linear columns above are its steady state; inside the dead
//! zone (an angle acos(1 − b/R) after the reversal, < 1° for usual gaps) the table actually
//! stays where it stopped. That dead-zone difference depends on b itself, so it is computed from
//! the current estimate and subtracted from the data, and the fit is repeated (a fixed-point
//! iteration that converges in a few steps because the zone is short).
//!
//! ## Known limits
//! - The model is first order in e/R. Servo lag is not: with lags τ₁ ≠ τ₂ the second-order terms
//!   (the radial effect of the lag angle φᵢ = ωτᵢ and the square of the tangential lag Rφ over
//!   2R) add −(3/4)R(φ₁² − φ₂²)·cos 2θ, which reads as a scale mismatch. It is not separable,
//!   because it needs the absolute lags, which a ballbar cannot see. At R = 100 mm, 1000 mm/min,
//!   τ = 16/14 ms it is −2.5 ppm (6 % of the 40 ppm injected in the `circular-test` scenario).
//! - The reversal angles are the commanded ones: a servo lag moves the actual reversal by ωτ
//!   (0.15° in the scenario), which leaves a few residual samples at each backlash step.
//! - Reversal spikes come out 11–16 % low on the simulator (`circular-test-arc`, and
//!   `crates/mtec-measure/tests/circular_faults.rs`): the column is 1 at the reversal sample
//!   itself, where the axis has not yet reversed (it lags by ωτ) and the data hold no spike;
//!   that one sample carries 1/8 of the column's weight at 0.2° sampling and w = 3°. Making
//!   the column 0 there was tried and is worse: the backlash dead-zone mismatch at the same
//!   sample then leaks into the spike.
//!
//! ## Contributions and thresholds
//! A fault's contribution to circularity is the peak-to-valley of its fitted pattern over both
//! directions after removing the pattern's own least-squares circle (1, cos θ, sin θ): what it
//! adds to the bidirectional circular deviation. The centre offset is removed by the reference
//! circle and contributes 0. A fault is reported as present when its contribution is at least
//! [`DiagnosticsConfig::threshold_um`] (default 0.3 µm: well above what 0.1–0.3 µm ballbar noise
//! produces over a few hundred samples per direction, well below the faults that matter in a
//! machine acceptance) and its coefficient exceeds 3 standard errors; the centre offset when
//! its magnitude reaches the threshold.

use super::trace::{CircularTrace, Travel};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::f64::consts::PI;

/// Settings of the diagnostic fit.
#[derive(Debug, Clone)]
pub struct DiagnosticsConfig {
    /// Contribution (µm) from which a fault is reported as present.
    pub threshold_um: f64,
    /// Angular decay constant of reversal spikes (deg).
    pub spike_width_deg: f64,
    /// Smallest cyclic pitch searched (mm).
    pub min_pitch_mm: f64,
}

impl Default for DiagnosticsConfig {
    fn default() -> Self {
        DiagnosticsConfig {
            threshold_um: 0.3,
            spike_width_deg: 3.0,
            min_pitch_mm: 1.0,
        }
    }
}

/// Why the diagnostics cannot be fitted.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum DiagnosticsError {
    #[error("the diagnostics need at least {need} samples per direction ({have} in `{dir}`): the fault patterns cannot be told apart on so few points")]
    TooFewSamples {
        need: usize,
        have: usize,
        dir: &'static str,
    },
    #[error("the fault patterns cannot be separated on this trace (condition number {0:.3e}); sample the whole circle densely in both directions")]
    IllConditioned(f64),
}

/// One fitted fault.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Diagnostic {
    /// Stable identifier, e.g. `scale_mismatch`, `backlash_X_pos`, `cyclic_Y`.
    pub id: String,
    /// Human-readable name.
    pub label: String,
    /// The fitted value in `unit` (for cyclic errors the amplitude); `None` when the trace does
    /// not determine it (see `determined`).
    pub value: Option<f64>,
    pub unit: String,
    /// Standard error of `value` from the residual variance.
    pub std_error: Option<f64>,
    /// Whether the trace determines the fault: its pattern is not reproduced by the others over
    /// the angles sampled (variance inflation factor at most [`MAX_VIF`]).
    pub determined: bool,
    /// Why there is no value, e.g. "not determined by a 220° arc".
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Variance inflation factor of the fault's column (1 = independent of the others).
    pub vif: f64,
    /// Peak-to-valley the fault adds to the bidirectional circularity (µm).
    pub contribution_um: f64,
    /// Share of the sum of all contributions (%).
    pub contribution_percent: f64,
    /// Above the threshold and statistically significant.
    pub present: bool,
    /// Pitch of a cyclic error (mm).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_mm: Option<f64>,
}

/// The diagnostic report: faults ranked by contribution (largest first).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Diagnostics {
    pub faults: Vec<Diagnostic>,
    /// Radius deviation (bar length / mean scale), µm; not a fault of the circularity.
    pub radius_deviation_um: f64,
    /// RMS of what the model leaves unexplained (µm).
    pub residual_rms_um: f64,
    pub threshold_um: f64,
    /// Notes on what could not be evaluated (e.g. servo mismatch in ms without a feed).
    pub notes: Vec<String>,
}

impl Diagnostics {
    /// The fault with this id.
    pub fn get(&self, id: &str) -> Option<&Diagnostic> {
        self.faults.iter().find(|d| d.id == id)
    }
    /// Faults reported as present, ranked.
    pub fn present(&self) -> impl Iterator<Item = &Diagnostic> {
        self.faults.iter().filter(|d| d.present)
    }
}

/// Largest variance inflation factor of a determined fault: its column must keep at least
/// 1/√VIF = 10 % of its norm outside the span of the other columns. On the full circle every
/// fault stays below 11 (servo mismatch, against the backlash patterns); on a partial arc the
/// faults whose patterns the others reproduce go above (docs/methods.md §5).
pub const MAX_VIF: f64 = 100.0;

/// A reversal counts as traced when it lies this far (deg) inside a partial arc's ends.
pub const REVERSAL_MARGIN_DEG: f64 = 5.0;

/// Minimum samples per direction for the diagnostic fit.
pub const MIN_SAMPLES_PER_DIRECTION: usize = 90;

/// One sample in the form the basis functions use.
#[derive(Debug, Clone, Copy)]
struct Pt {
    theta: f64,
    d: f64,
    dl_um: f64,
}

/// A column of the design matrix with what its coefficient means.
struct Term {
    id: String,
    label: String,
    unit: String,
    col: Vec<f64>,
}

fn sgn(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Travel (rad, ≥ 0) from a reversal at `theta_r` to the sample, in the direction of travel.
fn travel_since(p: &Pt, theta_r: f64) -> f64 {
    (p.d * (p.theta - theta_r)).rem_euclid(2.0 * PI)
}

fn linear_terms(
    pts: &[Pt],
    r_um: f64,
    axes: [&str; 2],
    feed_mm_min: Option<f64>,
    spike_w: f64,
) -> Vec<Term> {
    let [a1, a2] = axes;
    let mk = |id: String, label: String, unit: &str, f: &dyn Fn(&Pt) -> f64| Term {
        id,
        label,
        unit: unit.to_string(),
        col: pts.iter().map(f).collect(),
    };
    let spike = move |p: &Pt, reversals: [f64; 2]| -> f64 {
        reversals
            .iter()
            .map(|&r| {
                let t = travel_since(p, r);
                if t < 8.0 * spike_w {
                    (-t / spike_w).exp()
                } else {
                    0.0
                }
            })
            .sum()
    };
    let mut t = vec![
        mk("radius".into(), "Radius deviation".into(), "um", &|_| 1.0),
        mk(
            format!("centre_offset_{a1}"),
            format!("Centre offset {a1}"),
            "um",
            &|p| p.theta.cos(),
        ),
        mk(
            format!("centre_offset_{a2}"),
            format!("Centre offset {a2}"),
            "um",
            &|p| p.theta.sin(),
        ),
        // dl = R(s₁ − s₂)/2 · cos 2θ, s in ppm → ×1e-6
        mk(
            "scale_mismatch".into(),
            format!("Scale mismatch {a1}/{a2}"),
            "ppm",
            &|p| r_um * 1e-6 / 2.0 * (2.0 * p.theta).cos(),
        ),
        // e₁ = α y → dl = αR/2 · sin 2θ, α in µm/m → ×1e-6
        mk(
            "squareness".into(),
            format!("Squareness {a1}{a2}"),
            "um/m",
            &|p| r_um * 1e-6 / 2.0 * (2.0 * p.theta).sin(),
        ),
    ];
    match feed_mm_min {
        // eᵢ = −τᵢvᵢ → dl = d·v_f·(τ₁ − τ₂)/2 · sin 2θ; v_f mm/s × 1 ms = v_f µm
        Some(f) => {
            let v = f / 60.0;
            t.push(mk(
                "servo_mismatch".into(),
                format!("Servo mismatch {a1}−{a2}"),
                "ms",
                &|p| p.d * v / 2.0 * (2.0 * p.theta).sin(),
            ))
        }
        None => t.push(mk(
            "servo_mismatch".into(),
            format!("Servo mismatch {a1}−{a2} (amplitude; give the feed for ms)"),
            "um",
            &|p| p.d * (2.0 * p.theta).sin(),
        )),
    }
    // e₁ = −sgn(v₁) g(x)/2 with v₁ = −d ω R sin θ, g = b⁺(1 + x/R)/2 + b⁻(1 − x/R)/2
    // → dl = d·sgn(sin θ)·cos θ·[b⁺(1 + cos θ) + b⁻(1 − cos θ)]/4
    t.push(mk(
        format!("backlash_{a1}_pos"),
        format!("Backlash {a1} positive"),
        "um",
        &|p| p.d * sgn(p.theta.sin()) * p.theta.cos() * (1.0 + p.theta.cos()) / 4.0,
    ));
    t.push(mk(
        format!("backlash_{a1}_neg"),
        format!("Backlash {a1} negative"),
        "um",
        &|p| p.d * sgn(p.theta.sin()) * p.theta.cos() * (1.0 - p.theta.cos()) / 4.0,
    ));
    // e₂ = −sgn(v₂) h(y)/2 with v₂ = d ω R cos θ → dl = −d·sgn(cos θ)·sin θ·[...]/4
    t.push(mk(
        format!("backlash_{a2}_pos"),
        format!("Backlash {a2} positive"),
        "um",
        &|p| -p.d * sgn(p.theta.cos()) * p.theta.sin() * (1.0 + p.theta.sin()) / 4.0,
    ));
    t.push(mk(
        format!("backlash_{a2}_neg"),
        format!("Backlash {a2} negative"),
        "um",
        &|p| -p.d * sgn(p.theta.cos()) * p.theta.sin() * (1.0 - p.theta.sin()) / 4.0,
    ));
    // e₂ = −sgn(v₁) p/2 → dl = sin θ · d·sgn(sin θ)·p/2 = d·|sin θ|·p/2
    t.push(mk(
        format!("lateral_play_{a1}"),
        format!("Lateral play {a1}"),
        "um",
        &|p| p.d * p.theta.sin().abs() / 2.0,
    ));
    // e₁ = −sgn(v₂) p/2 → dl = cos θ · (−d·sgn(cos θ))·p/2 = −d·|cos θ|·p/2
    t.push(mk(
        format!("lateral_play_{a2}"),
        format!("Lateral play {a2}"),
        "um",
        &|p| -p.d * p.theta.cos().abs() / 2.0,
    ));
    // axis 1 reverses at θ = 0 and π, axis 2 at π/2 and 3π/2
    t.push(mk(
        format!("reversal_spike_{a1}"),
        format!("Reversal spike {a1}"),
        "um",
        &|p| spike(p, [0.0, PI]),
    ));
    t.push(mk(
        format!("reversal_spike_{a2}"),
        format!("Reversal spike {a2}"),
        "um",
        &|p| spike(p, [PI / 2.0, 1.5 * PI]),
    ));
    // e₂ = S (x/R)² → dl = sin θ cos² θ · S
    t.push(mk(
        format!("straightness_{a1}"),
        format!("Straightness {a1}"),
        "um",
        &|p| p.theta.sin() * p.theta.cos().powi(2),
    ));
    // e₁ = S (y/R)² → dl = cos θ sin² θ · S
    t.push(mk(
        format!("straightness_{a2}"),
        format!("Straightness {a2}"),
        "um",
        &|p| p.theta.cos() * p.theta.sin().powi(2),
    ));
    t
}

/// Cyclic-error columns of axis `axis` (0 or 1) at spatial frequency k (1/mm).
fn cyclic_cols(pts: &[Pt], r_mm: f64, axis: usize, k: f64) -> [Vec<f64>; 2] {
    let (mut c, mut s) = (Vec::with_capacity(pts.len()), Vec::with_capacity(pts.len()));
    for p in pts {
        let (proj, pos) = if axis == 0 {
            (p.theta.cos(), r_mm * p.theta.cos())
        } else {
            (p.theta.sin(), r_mm * p.theta.sin())
        };
        let ph = 2.0 * PI * k * pos;
        c.push(proj * ph.cos());
        s.push(proj * ph.sin());
    }
    [c, s]
}

/// Variance of `r` explained by the two columns (2×2 least squares).
fn explained(c: &[f64], s: &[f64], r: &[f64]) -> f64 {
    let (mut gcc, mut gss, mut gcs, mut bc, mut bs) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..r.len() {
        gcc += c[i] * c[i];
        gss += s[i] * s[i];
        gcs += c[i] * s[i];
        bc += c[i] * r[i];
        bs += s[i] * r[i];
    }
    let det = gcc * gss - gcs * gcs;
    if det <= 1e-12 * (gcc * gss).max(1e-300) {
        return 0.0;
    }
    // bᵀ G⁻¹ b
    (gss * bc * bc - 2.0 * gcs * bc * bs + gcc * bs * bs) / det
}

/// Spatial frequency (1/mm) of the cyclic error of `axis` that best explains the residual.
fn scan_pitch(pts: &[Pt], r_mm: f64, axis: usize, resid: &[f64], k_lo: f64, k_hi: f64) -> f64 {
    let n = pts.len();
    let pos: Vec<f64> = pts
        .iter()
        .map(|p| {
            r_mm * if axis == 0 {
                p.theta.cos()
            } else {
                p.theta.sin()
            }
        })
        .collect();
    let proj: Vec<f64> = pts
        .iter()
        .map(|p| {
            if axis == 0 {
                p.theta.cos()
            } else {
                p.theta.sin()
            }
        })
        .collect();
    // phase over the travel 2R changes by < 0.5 rad between grid points
    let dk = 0.5 / (2.0 * PI * 2.0 * r_mm);
    let steps = ((k_hi - k_lo) / dk).ceil() as usize;
    // z_i = exp(i 2π k x_i), advanced by w_i = exp(i 2π dk x_i) each step
    let mut zr: Vec<f64> = pos.iter().map(|x| (2.0 * PI * k_lo * x).cos()).collect();
    let mut zi: Vec<f64> = pos.iter().map(|x| (2.0 * PI * k_lo * x).sin()).collect();
    let wr: Vec<f64> = pos.iter().map(|x| (2.0 * PI * dk * x).cos()).collect();
    let wi: Vec<f64> = pos.iter().map(|x| (2.0 * PI * dk * x).sin()).collect();
    let (mut best_k, mut best_v) = (k_lo, -1.0);
    let mut c = vec![0.0; n];
    let mut s = vec![0.0; n];
    for step in 0..=steps {
        let k = k_lo + step as f64 * dk;
        for i in 0..n {
            c[i] = proj[i] * zr[i];
            s[i] = proj[i] * zi[i];
        }
        let v = explained(&c, &s, resid);
        if v > best_v {
            best_v = v;
            best_k = k;
        }
        for i in 0..n {
            let (a, b) = (zr[i] * wr[i] - zi[i] * wi[i], zr[i] * wi[i] + zi[i] * wr[i]);
            zr[i] = a;
            zi[i] = b;
        }
    }
    // golden-section refinement on [k − dk, k + dk]
    let f = |k: f64| {
        let [c, s] = cyclic_cols(pts, r_mm, axis, k);
        explained(&c, &s, resid)
    };
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = ((best_k - dk).max(k_lo), (best_k + dk).min(k_hi));
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..40 {
        if f1 > f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2);
        }
    }
    0.5 * (a + b)
}

/// Least-squares solution, residual, coefficient standard errors and collinearity.
struct Fit {
    coef: Vec<f64>,
    std_err: Vec<f64>,
    resid: Vec<f64>,
    /// Variance inflation factor of each column: [(AᵀA)⁻¹]_jj with unit-norm columns,
    /// = 1/(1 − R²_j), R²_j the share of column j the other columns reproduce; infinite for a
    /// column that is zero on these samples.
    vif: Vec<f64>,
}

/// Singular values below this fraction of the largest are treated as zero in the solve.
const RANK_TOL: f64 = 1e-10;

fn solve(cols: &[&[f64]], y: &[f64]) -> Result<Fit, DiagnosticsError> {
    let n = y.len();
    let p = cols.len();
    // scale columns to unit norm for conditioning; a column that vanishes on these samples
    // (a fault the trace never excites, e.g. a reversal outside a partial arc) stays zero
    let norms: Vec<f64> = cols
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    let biggest = norms.iter().copied().fold(0.0, f64::max);
    let live: Vec<bool> = norms.iter().map(|&m| m > 1e-9 * biggest).collect();
    let a = DMatrix::from_fn(
        n,
        p,
        |i, j| {
            if live[j] {
                cols[j][i] / norms[j]
            } else {
                0.0
            }
        },
    );
    let svd = a.clone().svd(true, true);
    let smax = svd.singular_values.max();
    if !smax.is_finite() || smax == 0.0 {
        return Err(DiagnosticsError::IllConditioned(f64::NAN));
    }
    let yv = DVector::from_column_slice(y);
    // pseudo-inverse: directions the columns cannot tell apart get no coefficient
    let x = svd
        .solve(&yv, RANK_TOL * smax)
        .map_err(|_| DiagnosticsError::IllConditioned(f64::NAN))?;
    let resid_v = &yv - &a * &x;
    let rank = svd
        .singular_values
        .iter()
        .filter(|&&s| s > RANK_TOL * smax)
        .count();
    let dof = (n as f64 - rank as f64).max(1.0);
    let sigma2 = resid_v.norm_squared() / dof;
    // (AᵀA)⁻¹ = V Σ⁻² Vᵀ (Var x̂ = σ² (AᵀA)⁻¹); a vanishing singular value counts as 1e-8·s_max
    let v_t = svd.v_t.as_ref().expect("v_t was requested");
    let vif: Vec<f64> = (0..p)
        .map(|j| {
            if !live[j] {
                return f64::INFINITY;
            }
            (0..p)
                .map(|k| (v_t[(k, j)] / svd.singular_values[k].max(1e-8 * smax)).powi(2))
                .sum()
        })
        .collect();
    let std_err = (0..p)
        .map(|j| {
            if live[j] {
                (sigma2 * vif[j]).sqrt() / norms[j]
            } else {
                f64::INFINITY
            }
        })
        .collect();
    Ok(Fit {
        coef: (0..p)
            .map(|j| if live[j] { x[j] / norms[j] } else { 0.0 })
            .collect(),
        std_err,
        resid: resid_v.iter().copied().collect(),
        vif,
    })
}

/// Index of a term by id.
fn idx(terms: &[Term], id: &str) -> usize {
    terms
        .iter()
        .position(|t| t.id == id)
        .expect("term ids are fixed in linear_terms")
}

/// Difference between the play-operator (lost-motion) error of one axis and its steady-state
/// column, from the current backlash estimates: non-zero only in the dead zone after a reversal
/// where the table stands still.
fn dead_zone_um(pts: &[Pt], r_um: f64, axis: usize, b_pos: f64, b_neg: f64) -> Vec<f64> {
    pts.iter()
        .map(|p| {
            let (proj, reversals) = if axis == 0 {
                (p.theta.cos(), [(0.0, b_pos, 1.0), (PI, b_neg, -1.0)])
            } else {
                (
                    p.theta.sin(),
                    [(PI / 2.0, b_pos, 1.0), (1.5 * PI, b_neg, -1.0)],
                )
            };
            for (theta_r, b, end) in reversals {
                if b <= 0.0 {
                    continue;
                }
                let t = travel_since(p, theta_r);
                // the command comes back by R(1 − cos t); the gap b is taken up when it reaches b
                let back = r_um * (1.0 - t.cos());
                if t < PI / 2.0 && back < b {
                    // held at the reversal: e = ±(R(1 − cos t) − b/2) (sign of the axis end);
                    // steady state there: e = ∓... = ±b/2 · (moving away from the end)
                    let e_held = end * (back - b / 2.0);
                    let e_steady = end * (b / 2.0);
                    return proj * (e_held - e_steady);
                }
            }
            0.0
        })
        .collect()
}

/// Fits the diagnostics of a trace.
pub fn diagnose(
    trace: &CircularTrace,
    cfg: &DiagnosticsConfig,
) -> Result<Diagnostics, DiagnosticsError> {
    for (t, name) in [(Travel::Ccw, "ccw"), (Travel::Cw, "cw")] {
        let have = trace.samples(t).len();
        if have < MIN_SAMPLES_PER_DIRECTION {
            return Err(DiagnosticsError::TooFewSamples {
                need: MIN_SAMPLES_PER_DIRECTION,
                have,
                dir: name,
            });
        }
    }
    let pts: Vec<Pt> = [Travel::Ccw, Travel::Cw]
        .iter()
        .flat_map(|&t| {
            trace.samples(t).iter().map(move |s| Pt {
                theta: s.angle_deg.to_radians(),
                d: t.sign(),
                dl_um: s.dl_um,
            })
        })
        .collect();
    let r_mm = trace.radius_mm;
    let r_um = r_mm * 1000.0;
    let axes = trace.plane.axes();
    let terms = linear_terms(
        &pts,
        r_um,
        axes,
        trace.feed_mm_min,
        cfg.spike_width_deg.to_radians(),
    );
    let y: Vec<f64> = pts.iter().map(|p| p.dl_um).collect();
    let bl = [
        idx(&terms, &format!("backlash_{}_pos", axes[0])),
        idx(&terms, &format!("backlash_{}_neg", axes[0])),
        idx(&terms, &format!("backlash_{}_pos", axes[1])),
        idx(&terms, &format!("backlash_{}_neg", axes[1])),
    ];
    let corrected = |coef: &[f64]| -> Vec<f64> {
        let z1 = dead_zone_um(&pts, r_um, 0, coef[bl[0]], coef[bl[1]]);
        let z2 = dead_zone_um(&pts, r_um, 1, coef[bl[2]], coef[bl[3]]);
        (0..y.len()).map(|i| y[i] - z1[i] - z2[i]).collect()
    };

    // 1. linear terms, with the dead-zone iteration
    let base: Vec<&[f64]> = terms.iter().map(|t| t.col.as_slice()).collect();
    let mut fit = solve(&base, &y)?;
    for _ in 0..4 {
        fit = solve(&base, &corrected(&fit.coef))?;
    }
    // 2. cyclic pitches from the residual, axis 1 then axis 2
    let k_lo = 1.0 / (r_mm / 2.0);
    let k_hi = 1.0 / cfg.min_pitch_mm;
    let mut pitch_k = [0.0; 2];
    let mut resid = fit.resid.clone();
    for (axis, k) in pitch_k.iter_mut().enumerate() {
        if k_hi <= k_lo {
            *k = k_lo;
            continue;
        }
        *k = scan_pitch(&pts, r_mm, axis, &resid, k_lo, k_hi);
        let [c, s] = cyclic_cols(&pts, r_mm, axis, *k);
        if let Ok(f) = solve(&[&c, &s], &resid) {
            resid = f.resid;
        }
    }
    // 3. joint fit with the cyclic columns
    let cyc: Vec<[Vec<f64>; 2]> = (0..2)
        .map(|a| cyclic_cols(&pts, r_mm, a, pitch_k[a]))
        .collect();
    let mut all: Vec<&[f64]> = base.clone();
    for c in &cyc {
        all.push(&c[0]);
        all.push(&c[1]);
    }
    let mut fit = solve(&all, &corrected(&fit.coef))?;
    for _ in 0..3 {
        fit = solve(&all, &corrected(&fit.coef))?;
    }

    // contributions: peak-to-valley of each pattern after removing its own LSQ circle
    let circle_cols: Vec<&[f64]> = vec![&terms[0].col, &terms[1].col, &terms[2].col];
    let contribution = |pattern: Vec<f64>| -> f64 {
        match solve(&circle_cols, &pattern) {
            Ok(f) => {
                let mx = f.resid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let mn = f.resid.iter().copied().fold(f64::INFINITY, f64::min);
                mx - mn
            }
            Err(_) => 0.0,
        }
    };
    let mut faults = Vec::new();
    let mut notes = Vec::new();
    let why_not = match &trace.arc {
        Some(arc) => format!("not determined by a {:.0}° arc", arc.span_deg),
        None => "not determined by this trace".to_string(),
    };
    let undetermined = |id: String, label: String, unit: String, vif: f64| Diagnostic {
        id,
        label,
        value: None,
        unit,
        std_error: None,
        determined: false,
        note: Some(why_not.clone()),
        vif,
        contribution_um: 0.0,
        contribution_percent: 0.0,
        present: false,
        pitch_mm: None,
    };
    // a fault defined by an axis reversal needs that reversal on the arc
    let reversal_missing = |id: &str| -> bool {
        let Some(arc) = &trace.arc else {
            return false;
        };
        let on_arc = |deg: f64| {
            let u = arc.along(deg);
            u >= REVERSAL_MARGIN_DEG && u <= arc.span_deg - REVERSAL_MARGIN_DEG
        };
        let [a1, a2] = axes;
        let needs: &[f64] = if id == format!("backlash_{a1}_pos") {
            &[0.0]
        } else if id == format!("backlash_{a1}_neg") {
            &[180.0]
        } else if id == format!("backlash_{a2}_pos") {
            &[90.0]
        } else if id == format!("backlash_{a2}_neg") {
            &[270.0]
        } else if id == format!("reversal_spike_{a1}") {
            &[0.0, 180.0]
        } else if id == format!("reversal_spike_{a2}") {
            &[90.0, 270.0]
        } else {
            return false;
        };
        !needs.iter().any(|&d| on_arc(d))
    };
    for (j, t) in terms.iter().enumerate().skip(1) {
        let value = fit.coef[j];
        let se = fit.std_err[j];
        if fit.vif[j] > MAX_VIF || reversal_missing(&t.id) {
            faults.push(undetermined(
                t.id.clone(),
                t.label.clone(),
                t.unit.clone(),
                fit.vif[j],
            ));
            continue;
        }
        let is_centre = t.id.starts_with("centre_offset");
        let contrib = if is_centre {
            0.0
        } else {
            contribution(t.col.iter().map(|c| c * value).collect())
        };
        let present = if is_centre {
            value.abs() >= cfg.threshold_um
        } else {
            contrib >= cfg.threshold_um && value.abs() > 3.0 * se
        };
        faults.push(Diagnostic {
            id: t.id.clone(),
            label: t.label.clone(),
            value: Some(value),
            unit: t.unit.clone(),
            std_error: Some(se),
            determined: true,
            note: None,
            vif: fit.vif[j],
            contribution_um: contrib,
            contribution_percent: 0.0,
            present,
            pitch_mm: None,
        });
    }
    let nb = terms.len();
    for axis in 0..2 {
        let (ja, jb) = (nb + 2 * axis, nb + 2 * axis + 1);
        let vif = fit.vif[ja].max(fit.vif[jb]);
        let (id, label) = (
            format!("cyclic_{}", axes[axis]),
            format!("Cyclic error {}", axes[axis]),
        );
        if vif > MAX_VIF {
            faults.push(undetermined(id, label, "um".into(), vif));
            continue;
        }
        let (a, b) = (fit.coef[ja], fit.coef[jb]);
        let (sa, sb) = (fit.std_err[ja], fit.std_err[jb]);
        let amp = a.hypot(b);
        let se = if amp > 0.0 {
            ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp
        } else {
            sa.max(sb)
        };
        let pattern: Vec<f64> = (0..pts.len())
            .map(|i| a * cyc[axis][0][i] + b * cyc[axis][1][i])
            .collect();
        let contrib = contribution(pattern);
        faults.push(Diagnostic {
            id,
            label,
            value: Some(amp),
            unit: "um".into(),
            std_error: Some(se),
            determined: true,
            note: None,
            vif,
            contribution_um: contrib,
            contribution_percent: 0.0,
            present: contrib >= cfg.threshold_um && amp > 3.0 * se,
            pitch_mm: Some(1.0 / pitch_k[axis]),
        });
    }
    if let Some(arc) = &trace.arc {
        let (mut collinear, mut off_arc) = (Vec::new(), Vec::new());
        for f in faults.iter().filter(|f| !f.determined) {
            if f.vif > MAX_VIF {
                collinear.push(f.id.as_str());
            } else {
                off_arc.push(f.id.as_str());
            }
        }
        if !collinear.is_empty() {
            notes.push(format!(
                "partial arc of {:.0}°: {} not determined: over these angles the other faults reproduce their patterns (variance inflation > {MAX_VIF}); trace the full circle for them",
                arc.span_deg,
                collinear.join(", ")
            ));
        }
        if !off_arc.is_empty() {
            notes.push(format!(
                "partial arc of {:.0}°: {} not determined: the axis reversal that shows them is not on the arc",
                arc.span_deg,
                off_arc.join(", ")
            ));
        }
    }
    if trace.feed_mm_min.is_none() {
        notes.push(
            "no feed given (# feed_mm_min = ... or --feed-mm-min): servo mismatch is reported as an amplitude in um, not in ms".into(),
        );
    }
    let total: f64 = faults.iter().map(|f| f.contribution_um).sum();
    for f in &mut faults {
        f.contribution_percent = if total > 0.0 {
            100.0 * f.contribution_um / total
        } else {
            0.0
        };
    }
    faults.sort_by(|a, b| {
        b.contribution_um
            .total_cmp(&a.contribution_um)
            .then(b.determined.cmp(&a.determined))
            .then(
                b.value
                    .unwrap_or(0.0)
                    .abs()
                    .total_cmp(&a.value.unwrap_or(0.0).abs()),
            )
    });
    let rms = (fit.resid.iter().map(|r| r * r).sum::<f64>() / fit.resid.len() as f64).sqrt();
    Ok(Diagnostics {
        faults,
        radius_deviation_um: fit.coef[0],
        residual_rms_um: rms,
        threshold_um: cfg.threshold_um,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::circular::trace::{Plane, Sample};

    fn trace_from(f: impl Fn(f64, f64) -> f64, n: usize) -> CircularTrace {
        let dir = |d: f64| -> Vec<Sample> {
            (0..n)
                .map(|k| {
                    let a = 360.0 * k as f64 / n as f64;
                    Sample {
                        angle_deg: a,
                        dl_um: f(a.to_radians(), d),
                    }
                })
                .collect()
        };
        CircularTrace {
            radius_mm: 100.0,
            plane: Plane::XY,
            feed_mm_min: Some(1000.0),
            arc: None,
            ccw: dir(1.0),
            cw: dir(-1.0),
        }
    }

    /// Worked by hand: an elliptical trace dl = 2 cos 2θ µm in both directions at R = 100 mm is
    /// a scale mismatch R(s₁ − s₂)/2 = 2 µm → s₁ − s₂ = 4 µm / 100 mm = 40 ppm; it adds its
    /// peak-to-valley 2·2 = 4 µm to the circularity; nothing else is present.
    #[test]
    fn pure_scale_mismatch_by_hand() {
        let t = trace_from(|th, _| 2.0 * (2.0 * th).cos(), 720);
        let d = diagnose(&t, &DiagnosticsConfig::default()).unwrap();
        let s = d.get("scale_mismatch").unwrap();
        assert!((s.value.unwrap() - 40.0).abs() < 1e-6, "{s:?}");
        assert!((s.contribution_um - 4.0).abs() < 1e-6, "{s:?}");
        assert_eq!(d.faults[0].id, "scale_mismatch");
        assert_eq!(
            d.present().count(),
            1,
            "{:?}",
            d.present().collect::<Vec<_>>()
        );
    }

    /// Worked by hand: dl = d·1.5 sin 2θ + 0.8 sin 2θ. The part that changes sign with the
    /// direction is servo mismatch: d·v_f·Δτ/2 = 1.5 µm with v_f = 1000/60 mm/s → Δτ = 0.18 ms;
    /// the part that does not is squareness: αR/2 = 0.8 µm → α = 1.6 µm / 100 mm = 16 µm/m.
    /// Contributions: 2·1.5 = 3 µm and 2·0.8 = 1.6 µm.
    #[test]
    fn servo_mismatch_and_squareness_by_hand() {
        let t = trace_from(|th, d| (d * 1.5 + 0.8) * (2.0 * th).sin(), 720);
        let d = diagnose(&t, &DiagnosticsConfig::default()).unwrap();
        let servo = d.get("servo_mismatch").unwrap();
        assert!((servo.value.unwrap() - 0.18).abs() < 1e-9, "{servo:?}");
        assert!((servo.contribution_um - 3.0).abs() < 1e-6, "{servo:?}");
        let sq = d.get("squareness").unwrap();
        assert!((sq.value.unwrap() - 16.0).abs() < 1e-6, "{sq:?}");
        assert!((sq.contribution_um - 1.6).abs() < 1e-6, "{sq:?}");
        let ids: Vec<&str> = d.present().map(|f| f.id.as_str()).collect();
        assert_eq!(ids, ["servo_mismatch", "squareness"]);
    }

    #[test]
    fn too_few_samples_is_refused() {
        let t = trace_from(|_, _| 0.0, 36);
        assert!(matches!(
            diagnose(&t, &DiagnosticsConfig::default()),
            Err(DiagnosticsError::TooFewSamples { .. })
        ));
    }
}
