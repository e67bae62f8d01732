//! What a thermal model kind is: the [`Kind`] trait every kind implements (its name, the options
//! it takes, how it is built from [`FitOptions`], what it fits to, whether it is an `auto`
//! candidate, its validated fit), and the fit of a kind with its forward validation
//! ([`Validated`]). The list of the kinds is the registry ([`crate::registry`]), above every kind.

use crate::auto::{Auto, CandidateScore};
use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::fit::Fit;
use crate::model::ThermalModel;
use crate::options::{BlockSpec, FitOptions};
use crate::validate::{duty_cycle_blocks, forward_cv, forward_folds, ForwardCv};

/// A model fitted on training rows, with its forward validation on them.
#[derive(Debug, Clone)]
pub struct Validated {
    pub model: ThermalModel,
    /// `None`: the training rows hold fewer than two blocks, or the validation failed (said in
    /// `warnings`).
    pub validation: Option<ForwardCv>,
    /// `auto`: every candidate's forward score.
    pub candidates: Vec<CandidateScore>,
    /// What the validation found (the model's own warnings are not repeated here).
    pub warnings: Vec<String>,
}

/// A thermal model kind: a fitter (its options) that the registry can build and fit.
pub trait Kind: Sized {
    /// The `--model` value and the serde tag.
    const NAME: &'static str;
    /// One line for `--model`'s help (`""`: none).
    const HELP: &'static str = "";
    /// Takes `--k`.
    const TAKES_K: bool = false;
    /// Takes `--lag` (a first-order lag feature per sensor).
    const TAKES_LAG: bool = false;
    /// Takes `--max-sensors`.
    const TAKES_MAX_SENSORS: bool = false;
    /// Takes `--up-sensors`/`--nut-sensors`.
    const TAKES_SENSOR_GROUPS: bool = false;
    /// Needs the heat-source column (`FitOptions::input`) in the log.
    const REQUIRES_INPUT: bool = false;
    /// A usage check of the options particular to the kind.
    fn check(_options: &FitOptions) -> Result<(), String> {
        Ok(())
    }
    /// The fitter the options describe (`data` for what the log has, e.g. auto's candidates).
    fn from_options(options: &FitOptions, data: &ThermalData) -> Result<Self, ThermalError>;
    /// Fits to the rows `rows` of `data` (the kind's [`Fit`], as the stored form).
    fn fit_model(&self, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError>;
    /// `auto`'s candidate of this kind, built from auto's options: its simplicity rank for the
    /// one-standard-error rule (auto's own families rank 0 mlr, 1 ridge, 2 heat-input,
    /// 3 lagged-ridge, 4 dynamic, 5 exp-ambient) and the fitter; `None` (the default): not a
    /// candidate, or the data lack what it needs.
    fn auto_candidate(_auto: &Auto, _data: &ThermalData) -> Option<(usize, Self)> {
        None
    }
    /// Fits on `train` and validates forward on the blocks of `train` (the default fits, then
    /// refits on every fold; `auto` overrides it with its nested choice).
    fn fit_validated(
        &self,
        data: &ThermalData,
        train: &[usize],
        blocks: &BlockSpec,
    ) -> Result<Validated, ThermalError> {
        let model = self.fit_model(data, train)?;
        let (validation, warnings) = validate_forward(&AsModel(self), data, train, blocks);
        Ok(Validated {
            model,
            validation,
            candidates: Vec::new(),
            warnings,
        })
    }
}

/// A kind as a fitter of the stored form.
pub struct AsModel<'a, K>(pub &'a K);

/// A kind's fitter, owned, as a fitter of the stored form (`auto`'s registered candidates).
pub struct Owned<K>(pub K);

impl<K: Kind> Fit for Owned<K> {
    type Model = ThermalModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError> {
        self.0.fit_model(data, rows)
    }
}

impl<K: Kind> Fit for AsModel<'_, K> {
    type Model = ThermalModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError> {
        self.0.fit_model(data, rows)
    }
}

/// Forward validation of `fitter` on the rows `train` (`None`: fewer than two blocks, or the
/// validation failed), and the warning that says so.
pub fn validate_forward<F: Fit>(
    fitter: &F,
    data: &ThermalData,
    train: &[usize],
    blocks: &BlockSpec,
) -> (Option<ForwardCv>, Vec<String>) {
    let folds = forward_folds(&duty_cycle_blocks(data, train, blocks));
    if folds.is_empty() {
        return (None, vec!["no forward validation: the training rows hold fewer than two blocks, so the model carries no uncertainty (use a longer record, experiments, or --block-min)".into()]);
    }
    match forward_cv(fitter, data, &folds) {
        Ok(v) => (Some(v), Vec::new()),
        Err(e) => (None, vec![format!("forward validation failed: {e}")]),
    }
}
