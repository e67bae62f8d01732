//! Instrument models: what each instrument reads from the exact machine, with its noise.

use mtec_model::{Formalism, Order, VolumetricModel};
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

/// A laser interferometer (linear and straightness optics).
#[derive(Debug, Clone, Copy)]
pub struct LaserInterferometer {
    /// Standard deviation of a displacement reading, µm (typ. 0.1–0.3 µm on a machine).
    pub noise_um: f64,
    /// Standard deviation of a straightness reading, µm (straightness optics are noisier).
    pub straightness_noise_um: f64,
    /// Standard deviation of the hand alignment of straightness optics, µrad (a linear trend).
    pub alignment_urad: f64,
}

impl Default for LaserInterferometer {
    fn default() -> Self {
        LaserInterferometer {
            noise_um: 0.15,
            straightness_noise_um: 0.25,
            alignment_urad: 20.0,
        }
    }
}

/// A laser tracker (or any 3-D point measurement) with isotropic noise.
#[derive(Debug, Clone, Copy)]
pub struct Tracker {
    pub noise_um: f64,
}

/// A temperature sensor with noise and an offset of its calibration.
#[derive(Debug, Clone, Copy)]
pub struct TemperatureSensor {
    pub noise_c: f64,
    pub offset_c: f64,
}

impl TemperatureSensor {
    /// A reading of the true temperature.
    pub fn read(&self, true_c: f64, rng: &mut StdRng) -> f64 {
        true_c + self.offset_c + gauss(rng, self.noise_c)
    }
}

/// A normal deviate with standard deviation `sd` (0 gives 0).
pub fn gauss(rng: &mut StdRng, sd: f64) -> f64 {
    if sd <= 0.0 {
        return 0.0;
    }
    Normal::new(0.0, sd).map(|n| n.sample(rng)).unwrap_or(0.0)
}

/// The exact tool-tip error (µm) of the virtual machine at a commanded XYZ point.
pub fn exact_error_um(vm: &VolumetricModel, q: &[f64]) -> [f64; 3] {
    vm.error(q, Formalism::Htm, Order::Exact).position_um
}
