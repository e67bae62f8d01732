//! A realistic ground truth for a three-axis machine: not a low-order polynomial but what ball
//! screws and guideways show (issue 19), in the magnitudes of [`crate::truth`]:
//! - a smooth part: the cubic of [`crate::truth::geometric_truth`]'s shapes (0.55–0.8 of the peak);
//! - a long sinusoid (0.15–0.35 of the peak, period 0.6–1.5 of the travel): the bending of a
//!   guideway or a ball screw's cumulative lead error, which no cubic follows;
//! - on every positioning error the ball screw's pitch error: a sinusoid of the screw lead
//!   (`period_mm` of the axis, 10 mm when not given), 0.3–0.7 µm amplitude;
//! - a local feature: a Gaussian bump (0.3–0.8 µm or µrad, σ 8–25 mm) where two guideway
//!   segments join or a scraped spot sits;
//! - waviness: the short ripple of [`crate::truth::RIPPLE`] (period 8–25 mm).
//!
//! Conventions as in [`crate::truth`]: zero at the axis origin (every part shifted to start at
//! zero; the waviness also faded in over the first 20 mm as in [`crate::truth`]),
//! straightness measured from its least-squares reference line. Stored as 0.5 mm tables.

use crate::truth::{location_constants, peak_and_sign, remove_ls_slope, RIPPLE};
use mtec_model::{motion_elements, ErrorFunction, ErrorSet, Machine};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::f64::consts::TAU;

/// Screw lead assumed for an axis whose machine file gives no `period_mm`.
pub const DEFAULT_LEAD_MM: f64 = 10.0;

/// Scale factors of the parts of the realistic truth (1 each: [`realistic_truth`]); for
/// studying what limits an identification.
#[derive(Debug, Clone, Copy)]
pub struct Mix {
    pub long: f64,
    pub pitch: f64,
    pub bump: f64,
    pub ripple: f64,
}

impl Default for Mix {
    fn default() -> Self {
        Mix {
            long: 1.0,
            pitch: 1.0,
            bump: 1.0,
            ripple: 1.0,
        }
    }
}

/// The realistic truth, deterministic by seed.
pub fn realistic_truth(machine: &Machine, seed: u64) -> ErrorSet {
    realistic_truth_with(machine, seed, Mix::default())
}

/// The realistic truth with its parts scaled by `mix`.
pub fn realistic_truth_with(machine: &Machine, seed: u64, mix: Mix) -> ErrorSet {
    let mut rng = StdRng::seed_from_u64(seed ^ 0x7265_616c);
    let mut set = ErrorSet::new(format!("mtec-sim realistic ground truth, seed {seed}"));
    for &axis in machine.axes.iter().filter(|a| !a.is_rotary()) {
        let [lo, hi] = machine.travel(axis);
        let len = hi - lo;
        let lead = machine.specs[&axis].period_mm.unwrap_or(DEFAULT_LEAD_MM);
        for el in motion_elements(axis) {
            let d = el.direction;
            let positioning = d == axis;
            let straightness = !d.is_rotary() && d != axis;
            let (peak, sign) = peak_and_sign(&mut rng, axis, d);
            let (a1, a2, a3) = if positioning {
                (
                    rng.random_range(0.6..1.0),
                    rng.random_range(-0.3..0.3),
                    rng.random_range(-0.3..0.3),
                )
            } else {
                (
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-0.5..0.5),
                )
            };
            let cubic = |s: f64| a1 * s + a2 * s * s + a3 * s * s * s;
            let long_period = rng.random_range(0.6..1.5) * len;
            let long_phase = rng.random_range(0.0..TAU);
            let long = |q: f64| (TAU * (q - lo) / long_period + long_phase).sin();
            let long_share = rng.random_range(0.15..0.35);
            let smooth_share = rng.random_range(0.55..0.8);
            let pitch_amp = if positioning {
                rng.random_range(0.3..0.7)
            } else {
                0.0
            };
            let pitch_phase = rng.random_range(0.0..TAU);
            let bump_amp =
                rng.random_range(0.3..0.8) * if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let bump_at = lo + rng.random_range(0.15..0.85) * len;
            let bump_sd = rng.random_range(8.0..25.0);
            let ripple_period = rng.random_range(8.0..25.0);
            let ripple_phase = rng.random_range(0.0..TAU);
            // the smooth part scaled to its share of the peak (before the ripples)
            let norm = |f: &dyn Fn(f64) -> f64| {
                (0..=200)
                    .map(|k| (f(lo + len * k as f64 / 200.0) - f(lo)).abs())
                    .fold(1e-9, f64::max)
            };
            let (nc, nl) = (norm(&|q| cubic((q - lo) / len)), norm(&long));
            let positions: Vec<f64> = (0..=(2.0 * len).round() as usize)
                .map(|k| lo + 0.5 * k as f64)
                .collect();
            let values: Vec<f64> = positions
                .iter()
                .map(|&q| {
                    let s = (q - lo) / len;
                    let smooth = smooth_share * cubic(s) / nc
                        + mix.long * long_share * (long(q) - long(lo)) / nl;
                    let fade = (1.0 - (-(q - lo) / 20.0).exp()).powi(2);
                    let periodic = |amp: f64, period: f64, phase: f64| {
                        amp * ((TAU * (q - lo) / period + phase).sin() - phase.sin())
                    };
                    let bump = |x: f64| bump_amp * (-0.5 * ((x - bump_at) / bump_sd).powi(2)).exp();
                    sign * peak * smooth
                        + mix.pitch * periodic(pitch_amp, lead, pitch_phase)
                        + mix.ripple * periodic(RIPPLE, ripple_period, ripple_phase) * fade
                        + mix.bump * (bump(q) - bump(lo))
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
