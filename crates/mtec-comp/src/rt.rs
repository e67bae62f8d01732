//! Real-time evaluation: one correction per interpolation cycle, no allocation per call.
//!
//! A [`Compensator`] owns a loaded [`ErrorModel`] and the correction settings. Its
//! [`Compensator::correction_um`] solves p + e(p) = target (see [`crate::correction`]) using only
//! the stack: the models shipped here (grid maps) evaluate without allocating, the solver keeps
//! its state in a few `[f64; 3]`, and errors are plain values. A test with a counting global
//! allocator checks this. The C ABI for controller components (e.g. a LinuxCNC HAL component) is
//! in the separate `mtec-rt` crate.

use crate::correction::{command_for_target, CorrectionError, CorrectionOptions};
use crate::ErrorModel;
use mtec_io::InputError;
use std::path::Path;

/// A loaded model ready to be evaluated every servo / interpolation cycle.
pub struct Compensator {
    model: Box<dyn ErrorModel>,
    opts: CorrectionOptions,
}

impl Compensator {
    /// A compensator over `model` with these correction settings.
    pub fn new(model: Box<dyn ErrorModel>, opts: CorrectionOptions) -> Compensator {
        Compensator { model, opts }
    }

    /// Loads any model file mtec reads (see [`crate::load::load_error_model`]).
    pub fn load(path: &Path, opts: CorrectionOptions) -> Result<Compensator, InputError> {
        Ok(Compensator::new(crate::load::load_error_model(path)?, opts))
    }

    /// Correction c = p − target (µm) to add to the axis commands so the tool reaches `target_mm`.
    #[inline]
    pub fn correction_um(&self, target_mm: [f64; 3]) -> Result<[f64; 3], CorrectionError> {
        let p = command_for_target(self.model.as_ref(), target_mm, &self.opts)?;
        Ok([
            (p[0] - target_mm[0]) * 1e3,
            (p[1] - target_mm[1]) * 1e3,
            (p[2] - target_mm[2]) * 1e3,
        ])
    }

    /// The corrected command p (mm) for `target_mm`.
    #[inline]
    pub fn command_mm(&self, target_mm: [f64; 3]) -> Result<[f64; 3], CorrectionError> {
        command_for_target(self.model.as_ref(), target_mm, &self.opts)
    }

    /// The machine-state inputs the model reads (empty for a static model), in the order
    /// [`Compensator::update_state`] takes them.
    pub fn state_inputs(&self) -> &[String] {
        self.model.state_inputs()
    }

    /// Advances the model's state by `dt_s` seconds with new readings (see
    /// [`ErrorModel::update_state`]); corrections then use the new state. No allocation.
    #[inline]
    pub fn update_state(
        &mut self,
        readings: &[f64],
        dt_s: f64,
    ) -> Result<crate::StateStatus, crate::StateError> {
        self.model.update_state(readings, dt_s)
    }

    /// The model's provenance line.
    pub fn describe(&self) -> String {
        self.model.describe()
    }

    /// The correction settings.
    pub fn options(&self) -> &CorrectionOptions {
        &self.opts
    }
}
