//! Ground-truth geometric errors of the virtual machine, with realistic magnitudes:
//! positioning 10–20 µm over the travel, straightness 2–8 µm, angular 5–30 µrad,
//! squareness 10–50 µrad (issue #2; typical of a mid-size vertical machining centre).
//!
//! Conventions the truth follows (the same the identification uses): every error motion is zero
//! at the axis origin (the travel's lower end); a straightness function is measured from its
//! least-squares reference line over the travel (ISO 230-1), so its least-squares slope is zero
//! (that slope belongs to squareness or to the axis that defines the frame).
//! Each function is a smooth polynomial part plus a small short-period ripple (ball-screw
//! lead error, guideway waviness) that no low-degree polynomial represents, stored as a
//! 1 mm piecewise-linear table.

use mtec_model::{
    location_elements, motion_elements, Axis, ErrorElement, ErrorFunction, ErrorSet, Machine,
    ThermalTerm,
};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// Ripple amplitude (µm or µrad) of the short-period part.
pub const RIPPLE: f64 = 0.08;

/// The truth of a three-axis machine (any linear axes in its chain), deterministic by seed.
pub fn geometric_truth(machine: &Machine, seed: u64) -> ErrorSet {
    let mut rng = StdRng::seed_from_u64(seed ^ 0x6d74_6563);
    let mut set = ErrorSet::new(format!("mtec-sim ground truth, seed {seed}"));
    for &axis in machine.axes.iter().filter(|a| !a.is_rotary()) {
        let [lo, hi] = machine.travel(axis);
        let len = hi - lo;
        for el in motion_elements(axis) {
            let d = el.direction;
            let positioning = d == axis;
            let straightness = !d.is_rotary() && d != axis;
            let (peak, sign) = peak_and_sign(&mut rng, axis, d);
            // shape in s = (q − lo)/len ∈ [0, 1]
            let (a1, a2, a3) = if positioning {
                (
                    rng.random_range(0.6..1.0),
                    rng.random_range(-0.3..0.3),
                    rng.random_range(-0.3..0.3),
                )
            } else if straightness {
                (
                    0.0,
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            } else {
                (
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-0.5..0.5),
                )
            };
            let period_mm = rng.random_range(8.0..25.0);
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            // a straightness bow has no least-squares slope over the travel (ISO 230-1 reference
            // line): s^p − b_p·s with b_p = 6p/((p+1)(p+2)) the least-squares slope of s^p
            let (b2, b3) = if straightness { (1.0, 0.9) } else { (0.0, 0.0) };
            let shape = |s: f64| a1 * s + a2 * (s * s - b2 * s) + a3 * (s * s * s - b3 * s);
            let norm = (0..=100)
                .map(|k| shape(k as f64 / 100.0).abs())
                .fold(1e-9, f64::max);
            let positions: Vec<f64> = (0..=(len.round() as usize))
                .map(|k| lo + k as f64)
                .collect();
            let values: Vec<f64> = positions
                .iter()
                .map(|&q| {
                    let s = (q - lo) / len;
                    let smooth = sign * peak * shape(s) / norm;
                    // ripple faded in so that it starts with zero value and zero slope (conventions hold)
                    let w = std::f64::consts::TAU * (q - lo) / period_mm;
                    let fade = (1.0 - (-(q - lo) / 20.0).exp()).powi(2);
                    let ripple = RIPPLE * ((w + phase).sin() - phase.sin()) * fade;
                    smooth + ripple
                })
                .collect();
            let values = if straightness {
                remove_ls_slope(&positions, values)
            } else {
                values
            };
            set.insert(el, ErrorFunction::table(positions, values));
        }
        location_constants(&mut set, axis, &mut rng);
    }
    set
}

/// The peak magnitude over the travel of a motion element of `axis` in direction `d`
/// (positioning 10–20 µm, straightness 2–8 µm, roll 5–15 µrad, pitch and yaw 5–30 µrad), and
/// its sign: the first two draws of every element in both truths.
pub(crate) fn peak_and_sign(rng: &mut StdRng, axis: Axis, d: Axis) -> (f64, f64) {
    let peak = if d == axis {
        rng.random_range(10.0..20.0)
    } else if !d.is_rotary() {
        rng.random_range(2.0..8.0)
    } else if d.index() == axis.index() {
        rng.random_range(5.0..15.0) // roll
    } else {
        rng.random_range(5.0..30.0)
    };
    let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
    (peak, sign)
}

/// The location errors of `axis` (squareness and zero offsets): constants of 10–50 µrad or
/// µm with a random sign.
pub(crate) fn location_constants(set: &mut ErrorSet, axis: Axis, rng: &mut StdRng) {
    for el in location_elements(axis) {
        let v = rng.random_range(10.0..50.0) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        set.insert(el, ErrorFunction::constant(v));
    }
}

/// Straightness is measured from its least-squares reference line (ISO 230-1): the slope of
/// the least-squares line through (q, f(q)) is removed (here: the ripple's, the smooth bow has
/// none), the value at the origin kept at zero.
pub(crate) fn remove_ls_slope(q: &[f64], f: Vec<f64>) -> Vec<f64> {
    let n = q.len() as f64;
    let (qm, fm) = (q.iter().sum::<f64>() / n, f.iter().sum::<f64>() / n);
    let sqq: f64 = q.iter().map(|v| (v - qm).powi(2)).sum();
    let sqf: f64 = q.iter().zip(&f).map(|(a, b)| (a - qm) * (b - fm)).sum();
    let slope = sqf / sqq;
    q.iter()
        .zip(f)
        .map(|(a, b)| b - slope * (a - q[0]))
        .collect()
}

/// Adds ball-screw expansion to the positioning error of every linear axis: 11.5 µm/(m·K) of
/// the temperature rise of sensor `<axis>_nut` (e.g. `x_nut`) above `ref_c`, growing from the
/// axis origin (where the screw is held by its fixed bearing).
pub fn with_ball_screw_expansion(mut set: ErrorSet, machine: &Machine, ref_c: f64) -> ErrorSet {
    for &axis in machine.axes.iter().filter(|a| !a.is_rotary()) {
        let el = ErrorElement::motion(axis, axis);
        let sensor = format!("{}_nut", axis.letter().to_ascii_lowercase());
        let lo = machine.travel(axis)[0];
        let f = set
            .get(&el)
            .cloned()
            .unwrap_or_else(|| ErrorFunction::constant(0.0));
        set.insert(
            el,
            f.with_thermal(ThermalTerm {
                sensor,
                ref_c,
                per_k: -0.0115 * lo,
                per_k_per_mm: 0.0115,
            }),
        );
    }
    set
}
