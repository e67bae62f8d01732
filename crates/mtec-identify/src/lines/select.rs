//! The degree of the error functions chosen by cross-validation over the measured points.
//!
//! Leave-points-out: fold f holds out the points with step index ≡ f (mod 3) of every channel
//! and every run (the reference point stays in), fits the rest (alignment slopes included) and
//! predicts the held-out readings. The score of a choice is the RMS of those prediction errors
//! over the folds (µm). It tests the functions *between* measured positions, where the
//! volumetric prediction at any other point needs them: a degree too low misses the machine's
//! shape, a degree too high oscillates between the points it fits.
//!
//! Why not leave-one-run-out: repeat runs measure the same positions, so holding out a run only
//! tests the noise. On `vmc-9line-realistic` it chose degree 9 for every kind on 5 of 5 seeds
//! (it predicts the held-out run best), and the volumetric prediction was then up to 1.75 µm RMS
//! on an axis; leave-points-out chose 4–7 and ≤ 0.75 µm (docs/methods.md §3).
//!
//! Search: one basis per *kind* of element (positioning, straightness, angular): a Legendre
//! degree of [`CANDIDATES`] or a cubic spline with [`KNOT_CANDIDATES`] interior knots at the
//! quantiles of the measured positions ([`super::spline`]), by coordinate descent from the best
//! common Legendre degree: each kind in turn takes the candidate that scores best with the
//! other two fixed, until no kind changes (at most [`SWEEPS`] passes). A larger model (more
//! coefficients; a spline after a polynomial of the same size) must lower the score by 1 % to
//! be taken.

use super::data::LineData;
use super::identifiability;
use super::model::{design_matrix, Basis, ElementKind, Layout, ModelError};
use super::solve;
use mtec_model::{ErrorElement, Machine};
use serde::Serialize;
use std::collections::BTreeMap;

/// Degrees tried (2 stays available as an explicit `--degree 2`).
pub const CANDIDATES: std::ops::RangeInclusive<usize> = 3..=9;
/// Interior knot counts of the splines tried (4..9 coefficients, the sizes of degrees 4..9).
pub const KNOT_CANDIDATES: std::ops::RangeInclusive<usize> = 1..=6;

/// Half-decade exponents e of the smoothing penalties λ = 10^(e/2) tried (10⁻⁶ .. 10²).
pub const PENALTY_CANDIDATES: std::ops::RangeInclusive<i32> = -12..=4;

/// Which bases the selection may choose from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// Legendre degrees [`CANDIDATES`] (the default).
    Legendre,
    /// Legendre degrees and cubic splines with [`KNOT_CANDIDATES`] interior knots.
    WithSplines,
    /// Smoothing splines with a penalty of [`PENALTY_CANDIDATES`].
    Smoothing,
    /// Per kind the better of the Legendre choice and the smoothing choice.
    Hybrid,
    /// Smoothing splines, the penalty per kind and then per element.
    SmoothingPerElement,
    /// Legendre degrees per kind and then per element.
    LegendrePerElement,
    /// Smoothing splines with the penalty per kind chosen by generalised cross-validation
    /// (a study).
    SmoothingGcv,
}

/// Every basis a kind may take, in the order tried (splines only when asked: see
/// docs/methods.md §3 for why the default does not try them).
fn candidates(family: Family) -> Vec<Basis> {
    match family {
        Family::Legendre | Family::LegendrePerElement => CANDIDATES.map(Basis::Legendre).collect(),
        Family::WithSplines => CANDIDATES
            .map(Basis::Legendre)
            .chain(KNOT_CANDIDATES.map(Basis::Spline))
            .collect(),
        Family::Smoothing | Family::Hybrid | Family::SmoothingPerElement | Family::SmoothingGcv => {
            PENALTY_CANDIDATES.rev().map(Basis::Smooth).collect()
        }
    }
}

/// The order of parsimony: size, then a polynomial before a spline.
fn larger(a: Basis, b: Basis) -> bool {
    (a.size(), matches!(a, Basis::Spline(_))) > (b.size(), matches!(b, Basis::Spline(_)))
}
/// Passes of the coordinate descent.
const SWEEPS: usize = 2;
/// A choice must lower the score by this fraction to replace a lower degree (parsimony: a
/// tie goes to the simpler model).
const MIN_GAIN: f64 = 0.01;

/// The basis per kind of element: positioning, straightness, angular.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct KindDegrees {
    pub positioning: Basis,
    pub straightness: Basis,
    pub angular: Basis,
}

impl KindDegrees {
    pub fn all(d: Basis) -> KindDegrees {
        KindDegrees {
            positioning: d,
            straightness: d,
            angular: d,
        }
    }
    /// The basis of an element (a squareness is a constant whatever it says).
    pub fn of(&self, e: &ErrorElement) -> Basis {
        match super::model::element_kind(e) {
            ElementKind::Positioning => self.positioning,
            ElementKind::Straightness => self.straightness,
            ElementKind::Angular | ElementKind::Squareness => self.angular,
        }
    }
    fn get(&self, k: usize) -> Basis {
        [self.positioning, self.straightness, self.angular][k]
    }
    fn with(mut self, k: usize, d: Basis) -> KindDegrees {
        match k {
            0 => self.positioning = d,
            1 => self.straightness = d,
            _ => self.angular = d,
        }
        self
    }
}

/// One scored choice.
#[derive(Debug, Clone, Serialize)]
pub struct Trial {
    pub degrees: KindDegrees,
    /// Cross-validated RMS prediction error of the held-out readings, µm.
    pub cv_rms_um: f64,
}

/// The outcome of the selection.
#[derive(Debug, Clone, Serialize)]
pub struct Selection {
    pub chosen: KindDegrees,
    pub cv_rms_um: f64,
    /// Every choice scored, in the order tried.
    pub trials: Vec<Trial>,
    /// Elements whose basis differs from their kind's (per-element selection), by name.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub per_element: BTreeMap<String, Basis>,
}

impl Selection {
    /// The basis chosen for an element.
    pub fn of(&self, e: &ErrorElement) -> Basis {
        self.per_element
            .get(&e.name())
            .copied()
            .unwrap_or(self.chosen.of(e))
    }
}

/// Leave-points-out score (µm): fold f holds out the points with step index ≡ f (mod
/// [`POINT_FOLDS`]) of every channel (the reference point stays), fits the rest (alignment slopes
/// included) and predicts them: it tests the functions *between* the measured positions, which
/// repeat runs at the same positions cannot.
pub fn point_cv_score(
    machine: &Machine,
    data: &LineData,
    degrees: KindDegrees,
    pitch: bool,
) -> Result<Option<f64>, ModelError> {
    point_cv_score_of(machine, data, &|e| degrees.of(e), pitch, None)
}

/// [`point_cv_score`] with a basis per element; `structural` are the elements the design
/// cannot identify ([`super::structural_drops`]), needed when a basis is a smoothing spline
/// (computed if None).
pub fn point_cv_score_of(
    machine: &Machine,
    data: &LineData,
    deg: &dyn Fn(&ErrorElement) -> Basis,
    pitch: bool,
    structural: Option<&[super::Dropped]>,
) -> Result<Option<f64>, ModelError> {
    let layout = match Layout::with_bases(machine, data, deg, pitch) {
        // a knot count the measured positions cannot support is no candidate
        Err(ModelError::Knots(..)) => return Ok(None),
        l => l?,
    };
    let (mut a, mut y) = design_matrix(machine, &layout, data);
    let mut fold_of = Vec::with_capacity(y.len());
    for c in &data.channels {
        for k in 0..c.readings_um.len() {
            fold_of.push(if k == 0 { usize::MAX } else { k % POINT_FOLDS });
        }
    }
    // what the whole design cannot identify, once: a fold keeps the same positions, so the
    // same elements are dropped and each fold needs only its QR
    let dropped = if layout.blocks.iter().any(|b| b.penalty.is_some()) {
        // a smoothing spline's penalty rows stay in every fold (they are no readings)
        let dropped = match structural {
            Some(d) => d.to_vec(),
            None => super::structural_drops(machine, data, pitch)?,
        };
        let (aa, ya) = super::model::penalised(a, y, &layout, 1.0);
        fold_of.resize(ya.len(), usize::MAX);
        (a, y) = (aa, ya);
        dropped
    } else {
        let Ok(full) = identifiability::analyse(&a, &y, &layout) else {
            return Ok(None);
        };
        full.dropped
    };
    let (mut ss, mut n) = (0.0, 0usize);
    for f in 0..POINT_FOLDS {
        let train: Vec<usize> = (0..y.len()).filter(|&i| fold_of[i] != f).collect();
        let test: Vec<usize> = (0..y.len()).filter(|&i| fold_of[i] == f).collect();
        let at = a.select_rows(train.iter());
        let yt = y.select_rows(train.iter());
        let Ok(an) = identifiability::analyse_with(&at, &yt, &layout, Some(&dropped)) else {
            return Ok(None);
        };
        let fit = solve::solve(&at, &yt, &an);
        for &i in &test {
            let e = y[i] - (a.row(i) * &fit.theta)[0];
            ss += e * e;
            n += 1;
        }
    }
    Ok(Some((ss / n.max(1) as f64).sqrt()))
}

/// Generalised cross-validation (Craven & Wahba 1979, eq. 1.6) of a penalised layout, as an RMS
/// in µm: √(m·RSS / (m − tr H)²), H the hat matrix of the readings, tr H = ‖A_s R⁻¹‖²_F with
/// [A_s; P_s] = QR the column-scaled kept augmented design (A_s its reading rows). It treats
/// each reading as its own point: the repeat runs at the same position stay in when one is left
/// out.
pub fn gcv_score_of(
    machine: &Machine,
    data: &LineData,
    deg: &dyn Fn(&ErrorElement) -> Basis,
    pitch: bool,
    structural: &[super::Dropped],
) -> Result<Option<f64>, ModelError> {
    let layout = match Layout::with_bases(machine, data, deg, pitch) {
        Err(ModelError::Knots(..)) => return Ok(None),
        l => l?,
    };
    let (a, y) = design_matrix(machine, &layout, data);
    let m = y.len();
    let (aa, ya) = super::model::penalised(a.clone(), y.clone(), &layout, 1.0);
    let Ok(an) = identifiability::analyse_with(&aa, &ya, &layout, Some(structural)) else {
        return Ok(None);
    };
    let fit = solve::solve(&aa, &ya, &an);
    let rss = (&y - &a * &fit.theta).norm_squared();
    let mut a_s = a.select_columns(an.active.iter());
    for (j, mut c) in a_s.column_iter_mut().enumerate() {
        c /= an.scale[an.active[j]];
    }
    // (A_s R⁻¹)ᵀ = R⁻ᵀ A_sᵀ
    let Some(x) = an
        .kept_r
        .transpose()
        .solve_lower_triangular(&a_s.transpose())
    else {
        return Ok(None);
    };
    let trace = x.norm_squared();
    let m_f = m as f64;
    Ok(Some((m_f * rss).sqrt() / (m_f - trace)))
}

/// Folds of [`point_cv_score`].
pub const POINT_FOLDS: usize = 3;

/// Chooses the degrees by cross-validation over the measured points (Legendre bases).
pub fn select(machine: &Machine, data: &LineData, pitch: bool) -> Result<Selection, ModelError> {
    select_among(machine, data, pitch, Family::Legendre)
}

/// Chooses the penalty of the smoothing splines per kind of element by cross-validation over
/// the measured points: the best common penalty walking down from the stiffest (stopping two
/// half-decades after the score stops falling), then each kind in turn moves its penalty by a
/// half decade while that lowers the score, until no kind moves (at most [`SWEEPS`] passes).
/// As elsewhere a smaller penalty (a more flexible model) must lower the score by [`MIN_GAIN`].
/// With `per_element`, each element then moves its own penalty by half decades from its kind's
/// while that lowers the score by [`MIN_GAIN`] (one pass over the elements).
/// With `gcv` the score is generalised cross-validation ([`gcv_score_of`]) instead of the
/// leave-points-out folds (a study: see docs/methods.md §3).
fn select_smoothing(
    machine: &Machine,
    data: &LineData,
    pitch: bool,
    per_element: bool,
) -> Result<Selection, ModelError> {
    select_smoothing_by(machine, data, pitch, per_element, false)
}

fn select_smoothing_by(
    machine: &Machine,
    data: &LineData,
    pitch: bool,
    per_element: bool,
    gcv: bool,
) -> Result<Selection, ModelError> {
    let structural = super::structural_drops(machine, data, pitch)?;
    let mut trials: Vec<Trial> = Vec::new();
    let mut score = |d: KindDegrees| -> Result<f64, ModelError> {
        if let Some(t) = trials.iter().find(|t| t.degrees == d) {
            return Ok(t.cv_rms_um);
        }
        let s = if gcv {
            gcv_score_of(machine, data, &|e| d.of(e), pitch, &structural)?
        } else {
            point_cv_score_of(machine, data, &|e| d.of(e), pitch, Some(&structural))?
        }
        .unwrap_or(f64::INFINITY);
        trials.push(Trial {
            degrees: d,
            cv_rms_um: s,
        });
        Ok(s)
    };
    let (lo, hi) = (*PENALTY_CANDIDATES.start(), *PENALTY_CANDIDATES.end());
    let mut best = KindDegrees::all(Basis::Smooth(hi));
    let mut best_s = score(best)?;
    let mut worse = 0;
    for e in (lo..hi).rev() {
        let s = score(KindDegrees::all(Basis::Smooth(e)))?;
        if s < best_s * (1.0 - MIN_GAIN) {
            (best, best_s, worse) = (KindDegrees::all(Basis::Smooth(e)), s, 0);
        } else {
            worse += 1;
            if worse == 2 {
                break;
            }
        }
    }
    let exponent = |b: Basis| match b {
        Basis::Smooth(e) => e,
        _ => hi,
    };
    for _ in 0..SWEEPS {
        let mut changed = false;
        for k in 0..3 {
            for step in [1, -1] {
                loop {
                    let e = exponent(best.get(k)) + step;
                    if !PENALTY_CANDIDATES.contains(&e) {
                        break;
                    }
                    let cand = best.with(k, Basis::Smooth(e));
                    let s = score(cand)?;
                    let gain = if step < 0 { 1.0 - MIN_GAIN } else { 1.0 };
                    if s < best_s * gain {
                        (best, best_s, changed) = (cand, s, true);
                    } else {
                        break;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut overrides = BTreeMap::new();
    if per_element {
        let ladder: Vec<Basis> = PENALTY_CANDIDATES.rev().map(Basis::Smooth).collect();
        (overrides, best_s) =
            refine_per_element(machine, data, pitch, best, best_s, &ladder, &structural)?;
    }
    Ok(Selection {
        chosen: best,
        cv_rms_um: best_s,
        trials,
        per_element: overrides,
    })
}

/// Per element, from the per-kind choice `chosen` (score `score`): each element in turn moves
/// one step up or down `ladder` (candidates from the smallest model to the largest) while that
/// lowers the score (a larger model by [`MIN_GAIN`]); one pass over the elements. Returns the
/// elements whose basis differs from their kind's, and the score.
fn refine_per_element(
    machine: &Machine,
    data: &LineData,
    pitch: bool,
    chosen: KindDegrees,
    score: f64,
    ladder: &[Basis],
    structural: &[super::Dropped],
) -> Result<(BTreeMap<String, Basis>, f64), ModelError> {
    let mut overrides: BTreeMap<String, Basis> = BTreeMap::new();
    let mut best_s = score;
    let of = |o: &BTreeMap<String, Basis>, e: &ErrorElement| {
        o.get(&e.name()).copied().unwrap_or(chosen.of(e))
    };
    for el in mtec_model::three_axis_elements() {
        if super::model::element_kind(&el) == ElementKind::Squareness {
            continue;
        }
        for step in [1isize, -1] {
            while let Some(at) = ladder.iter().position(|b| *b == of(&overrides, &el)) {
                let Some(&next) = ladder.get((at as isize + step) as usize) else {
                    break;
                };
                let mut cand = overrides.clone();
                cand.insert(el.name(), next);
                let s =
                    point_cv_score_of(machine, data, &|x| of(&cand, x), pitch, Some(structural))?
                        .unwrap_or(f64::INFINITY);
                let gain = if step > 0 { 1.0 - MIN_GAIN } else { 1.0 };
                if s < best_s * gain {
                    (overrides, best_s) = (cand, s);
                } else {
                    break;
                }
            }
        }
    }
    Ok((overrides, best_s))
}

/// Per kind of element the better of the two selections ([`Family::Legendre`] and
/// [`Family::Smoothing`]): from the one with the lower score, each kind in turn takes the
/// other's basis if that lowers the score by [`MIN_GAIN`] (a smoothing spline is the larger
/// model), until no kind changes (at most [`SWEEPS`] passes).
fn select_hybrid(machine: &Machine, data: &LineData, pitch: bool) -> Result<Selection, ModelError> {
    let poly = select_among(machine, data, pitch, Family::Legendre)?;
    let smooth = select_smoothing(machine, data, pitch, false)?;
    let structural = super::structural_drops(machine, data, pitch)?;
    let mut trials: Vec<Trial> = poly.trials.iter().chain(&smooth.trials).cloned().collect();
    let (mut best, mut best_s) = if smooth.cv_rms_um < poly.cv_rms_um * (1.0 - MIN_GAIN) {
        (smooth.chosen, smooth.cv_rms_um)
    } else {
        (poly.chosen, poly.cv_rms_um)
    };
    for _ in 0..SWEEPS {
        let mut changed = false;
        for k in 0..3 {
            let other = if best.get(k) == poly.chosen.get(k) {
                smooth.chosen.get(k)
            } else {
                poly.chosen.get(k)
            };
            let cand = best.with(k, other);
            let s = match trials.iter().find(|t| t.degrees == cand) {
                Some(t) => t.cv_rms_um,
                None => {
                    let s = point_cv_score_of(
                        machine,
                        data,
                        &|e| cand.of(e),
                        pitch,
                        Some(&structural),
                    )?
                    .unwrap_or(f64::INFINITY);
                    trials.push(Trial {
                        degrees: cand,
                        cv_rms_um: s,
                    });
                    s
                }
            };
            let gain = if matches!(other, Basis::Smooth(_)) {
                1.0 - MIN_GAIN
            } else {
                1.0
            };
            if s < best_s * gain {
                (best, best_s, changed) = (cand, s, true);
            }
        }
        if !changed {
            break;
        }
    }
    Ok(Selection {
        chosen: best,
        cv_rms_um: best_s,
        trials,
        per_element: BTreeMap::new(),
    })
}

/// Chooses the bases of a family by cross-validation over the measured points.
pub fn select_among(
    machine: &Machine,
    data: &LineData,
    pitch: bool,
    family: Family,
) -> Result<Selection, ModelError> {
    if family == Family::Smoothing {
        return select_smoothing(machine, data, pitch, false);
    }
    if family == Family::SmoothingPerElement {
        return select_smoothing(machine, data, pitch, true);
    }
    if family == Family::SmoothingGcv {
        return select_smoothing_by(machine, data, pitch, false, true);
    }
    if family == Family::Hybrid {
        return select_hybrid(machine, data, pitch);
    }
    if family == Family::LegendrePerElement {
        let mut sel = select_among(machine, data, pitch, Family::Legendre)?;
        let structural = super::structural_drops(machine, data, pitch)?;
        let ladder: Vec<Basis> = CANDIDATES.map(Basis::Legendre).collect();
        (sel.per_element, sel.cv_rms_um) = refine_per_element(
            machine,
            data,
            pitch,
            sel.chosen,
            sel.cv_rms_um,
            &ladder,
            &structural,
        )?;
        return Ok(sel);
    }
    let mut trials: Vec<Trial> = Vec::new();
    let score = |d: KindDegrees, trials: &mut Vec<Trial>| -> Result<f64, ModelError> {
        if let Some(t) = trials.iter().find(|t| t.degrees == d) {
            return Ok(t.cv_rms_um);
        }
        let s = point_cv_score(machine, data, d, pitch)?.unwrap_or(f64::INFINITY);
        trials.push(Trial {
            degrees: d,
            cv_rms_um: s,
        });
        Ok(s)
    };
    // best common basis (ascending size: a larger model must gain MIN_GAIN)
    let common: Vec<Basis> = CANDIDATES.map(Basis::Legendre).collect();
    let mut best = KindDegrees::all(common[0]);
    let mut best_s = score(best, &mut trials)?;
    for &d in &common[1..] {
        let s = score(KindDegrees::all(d), &mut trials)?;
        if s < best_s * (1.0 - MIN_GAIN) {
            best = KindDegrees::all(d);
            best_s = s;
        }
    }
    for _ in 0..SWEEPS {
        let mut changed = false;
        for k in 0..3 {
            let mut kind_best = (best.get(k), best_s);
            for d in candidates(family) {
                if d == best.get(k) {
                    continue;
                }
                let s = score(best.with(k, d), &mut trials)?;
                // smaller models win ties; a larger one must gain MIN_GAIN
                let gain = if larger(d, kind_best.0) {
                    1.0 - MIN_GAIN
                } else {
                    1.0
                };
                if s < kind_best.1 * gain {
                    kind_best = (d, s);
                }
            }
            if kind_best.0 != best.get(k) {
                best = best.with(k, kind_best.0);
                best_s = kind_best.1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    Ok(Selection {
        chosen: best,
        cv_rms_um: best_s,
        trials,
        per_element: BTreeMap::new(),
    })
}
