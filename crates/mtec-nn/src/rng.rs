//! Seeded weight initialisation. candle's own random initialisers draw from an unseeded
//! thread RNG on the CPU, so every weight is drawn here from `StdRng::seed_from_u64(seed)`:
//! the same seed gives bit-identical initial weights and (training being deterministic on the
//! CPU) identical trained weights.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

pub fn seeded(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

/// `n` values uniform in [−bound, bound] (Glorot/Kaiming-uniform style initialisation).
pub fn uniform(rng: &mut StdRng, n: usize, bound: f64) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-bound..=bound)).collect()
}
