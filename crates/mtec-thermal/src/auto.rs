//! `auto`: choose the model family by forward validation, nested, with the one-standard-error
//! rule.
//!
//! Candidates: `mlr`, `ridge`, `lagged-ridge` and `dynamic` ([`crate::stepwise`]: forward
//! selection of at most `max_sensors` temperature sensors, the heat input not counted),
//! `heat-input` ([`crate::heat_input`]) when the data has the input column, and `exp-ambient`
//! when the caller supplies its fitter (its columns exist), and every kind that offers itself
//! ([`crate::kind::Kind::auto_candidate`]: `pls`), and the candidates of other crates a caller
//! adds ([`Auto::fit_with_extra`]: the networks of mtec-nn, when the user asks for them).
//!
//! Auto does not know the registry of the kinds (it is one of them): the kinds that may offer a
//! candidate are passed in ([`Auto::fit_with`], a list of [`Offer`]s). `Auto::fit_auto` and
//! auto's [`Fit`], which pass every kind of the registry, are defined in [`crate::registry`].
//! A candidate of another crate fits to a model type of the caller's (`M`: any [`Predict`] that
//! a [`ThermalModel`] converts into), so auto's own candidates are scored and chosen with it on
//! the same folds.
//!
//! 1. Forward folds of the training rows ([`crate::validate::forward_folds_of`]).
//! 2. Each candidate is fitted on each fold's training rows, with every choice it makes
//!    (sensors, time constants, k, α …) made again inside those rows by their own forward folds
//!    (nested), and scored on the fold's block.
//! 3. A candidate worse than no compensation on any fold (fold RMSE above the RMS of the
//!    measured drift there) is flagged and never chosen; so is one that failed.
//! 4. One-standard-error rule (Hastie, Tibshirani & Friedman, *Elements of Statistical
//!    Learning*, 2nd ed., §7.10.1): among the rest, the simplest candidate whose mean fold RMSE
//!    is within one standard error (sd of its fold RMSEs / √folds) of the best mean.
//!    Simplicity order: mlr, ridge and pls, heat-input, lagged-ridge, dynamic, exp-ambient (a
//!    tie in rank goes to the lower mean).
//! 5. The chosen candidate is refitted on every training row (its choices made again there).

use crate::data::{input_column, ThermalData};
use crate::error::ThermalError;
use crate::exp_ambient::ExpAmbient;
use crate::fit::{Fit, Predict};
use crate::heat_input::HeatInput;
use crate::model::ThermalModel;
use crate::options::BlockSpec;
use crate::stepwise::{Family, Stepwise};
use crate::validate::{forward_cv, forward_folds_of, ForwardCv};
use serde::{Deserialize, Serialize};

/// Default number of temperature sensors a candidate may use.
pub const DEFAULT_MAX_SENSORS: usize = 6;

/// The auto fitter (module docs).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Auto {
    /// Candidate temperature sensors (every `_c` sensor when empty).
    pub sensors: Vec<String>,
    /// Heat-input column (`spindle_rpm`); heat-input and dynamic run only when the data has it.
    pub input: String,
    pub max_sensors: usize,
    pub block_min: Option<f64>,
    /// The exp-ambient fitter, when its columns exist.
    pub exp_ambient: Option<ExpAmbient>,
}

impl Default for Auto {
    fn default() -> Self {
        Auto {
            sensors: Vec::new(),
            input: "spindle_rpm".into(),
            max_sensors: DEFAULT_MAX_SENSORS,
            block_min: None,
            exp_ambient: None,
        }
    }
}

/// The forward score of one candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    pub family: String,
    /// Simplicity rank (0 simplest) used by the one-standard-error rule.
    pub complexity: usize,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub forward: Option<ForwardCv>,
    /// Why the candidate could not be fitted.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
    /// 1-based folds where it was worse than no compensation.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub worse_than_uncompensated: Vec<usize>,
    pub chosen: bool,
}

impl CandidateScore {
    /// Fit on every fold and never worse than no compensation.
    pub fn eligible(&self) -> bool {
        self.forward.is_some() && self.worse_than_uncompensated.is_empty()
    }
}

/// The chosen model, its forward validation and every candidate's score.
#[derive(Debug, Clone)]
pub struct AutoFit<M = ThermalModel> {
    pub model: M,
    pub family: String,
    pub validation: ForwardCv,
    pub candidates: Vec<CandidateScore>,
}

/// A candidate offered to auto by a kind ([`crate::kind::Kind::auto_candidate`]): its simplicity
/// rank and its fitter.
pub type AutoCandidate = (usize, Box<dyn Fit<Model = ThermalModel>>);

/// A kind that may offer auto a candidate: its name, and how the candidate is built from auto's
/// options and the data (`None`: not a candidate there). The registry makes the list.
pub type Offer = (
    &'static str,
    fn(&Auto, &ThermalData) -> Option<AutoCandidate>,
);

/// A candidate of another crate ([`Auto::fit_with_extra`]): its name, simplicity rank (after
/// auto's own, e.g. 6 bpnn, 7 cnn-lstm) and fitter.
pub type ExtraCandidate<M> = (String, usize, Box<dyn Fit<Model = M>>);

/// A [`ThermalModel`] fitter as a fitter of the caller's model type `M`.
struct Into<C, M>(C, std::marker::PhantomData<fn() -> M>);

impl<C: Fit<Model = ThermalModel>, M: Predict + From<ThermalModel>> Fit for Into<C, M> {
    type Model = M;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<M, ThermalError> {
        self.0.fit_rows(data, rows).map(M::from)
    }
}

/// A candidate fitter as a [`ThermalModel`] fitter.
enum Candidate {
    Stepwise(Stepwise),
    HeatInput(HeatInput),
    ExpAmbient(ExpAmbient),
    /// A candidate a kind offered ([`Offer`]).
    Registered(Box<dyn Fit<Model = ThermalModel>>),
}

impl Fit for Candidate {
    type Model = ThermalModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(match self {
            Candidate::Stepwise(s) => ThermalModel::Linear(s.fit_rows(data, rows)?),
            Candidate::HeatInput(h) => ThermalModel::HeatInput(h.fit_rows(data, rows)?),
            Candidate::ExpAmbient(e) => ThermalModel::ExpAmbient(Box::new(e.fit_rows(data, rows)?)),
            Candidate::Registered(f) => f.fit_rows(data, rows)?,
        })
    }
}

impl Auto {
    fn candidates(&self, data: &ThermalData, offers: &[Offer]) -> Vec<(String, usize, Candidate)> {
        let has_input = input_column(data, &self.input).is_some();
        let step = |family: Family| Stepwise {
            family,
            sensors: self.sensors.clone(),
            input: has_input.then(|| self.input.clone()),
            max_sensors: self.max_sensors,
            block_min: self.block_min,
        };
        let mut out = vec![
            ("mlr".to_string(), 0, Candidate::Stepwise(step(Family::Mlr))),
            (
                "ridge".to_string(),
                1,
                Candidate::Stepwise(step(Family::Ridge)),
            ),
        ];
        if has_input {
            out.push((
                "heat-input".into(),
                2,
                Candidate::HeatInput(HeatInput {
                    input: self.input.clone(),
                    block_min: self.block_min,
                    ..Default::default()
                }),
            ));
        }
        out.push((
            "lagged-ridge".into(),
            3,
            Candidate::Stepwise(step(Family::LaggedRidge)),
        ));
        if has_input {
            out.push((
                "dynamic".into(),
                4,
                Candidate::Stepwise(step(Family::Dynamic)),
            ));
        }
        if let Some(e) = &self.exp_ambient {
            out.push(("exp-ambient".into(), 5, Candidate::ExpAmbient(e.clone())));
        }
        // every kind that offers itself as a candidate
        for (name, offer) in offers {
            if let Some((rank, fitter)) = offer(self, data) {
                out.push((name.to_string(), rank, Candidate::Registered(fitter)));
            }
        }
        out
    }

    /// Scores every candidate (auto's own and those the `offers` make) on the forward folds of
    /// `rows`, chooses one, refits it on `rows`. `Auto::fit_auto` ([`crate::registry`]) offers
    /// every kind of the registry.
    pub fn fit_with(
        &self,
        data: &ThermalData,
        rows: &[usize],
        offers: &[Offer],
    ) -> Result<AutoFit, ThermalError> {
        self.fit_with_extra(data, rows, offers, Vec::new())
    }

    /// [`Auto::fit_with`] with the `extra` candidates of another crate, which fit to `M`: every
    /// candidate is scored on the same forward folds of `rows` and the rule chooses among all.
    pub fn fit_with_extra<M: Predict + From<ThermalModel> + 'static>(
        &self,
        data: &ThermalData,
        rows: &[usize],
        offers: &[Offer],
        extra: Vec<ExtraCandidate<M>>,
    ) -> Result<AutoFit<M>, ThermalError> {
        let spec = BlockSpec {
            block_min: self.block_min,
            input: Some(self.input.clone()),
        };
        let folds = forward_folds_of(data, rows, &spec);
        if folds.is_empty() {
            return Err(ThermalError::Undetermined(
                "auto: forward validation needs at least two blocks in the training rows (a longer record, experiments, or --block-min)".into(),
            ));
        }
        let mut cands: Vec<ExtraCandidate<M>> = self
            .candidates(data, offers)
            .into_iter()
            .map(|(name, rank, c)| {
                let f: Box<dyn Fit<Model = M>> = Box::new(Into(c, std::marker::PhantomData));
                (name, rank, f)
            })
            .collect();
        cands.extend(extra);
        let mut scores: Vec<CandidateScore> = Vec::new();
        for (name, complexity, c) in &cands {
            let (forward, error) = match forward_cv(c, data, &folds) {
                Ok(f) => (Some(f), None),
                Err(e) => (None, Some(e.to_string())),
            };
            scores.push(CandidateScore {
                family: name.clone(),
                complexity: *complexity,
                worse_than_uncompensated: forward
                    .as_ref()
                    .map(|f| f.folds_worse_than_uncompensated())
                    .unwrap_or_default(),
                forward,
                error,
                chosen: false,
            });
        }
        let pick = one_standard_error(&scores).ok_or_else(|| {
            let list: Vec<String> = scores
                .iter()
                .map(|s| match (&s.forward, &s.error) {
                    (Some(f), _) => format!(
                        "{} {:.2} µm (worse than no compensation on fold {:?})",
                        s.family, f.pooled_rmse_um, s.worse_than_uncompensated
                    ),
                    (None, Some(e)) => format!("{}: {e}", s.family),
                    (None, None) => s.family.clone(),
                })
                .collect();
            ThermalError::Undetermined(format!(
                "auto: no candidate is better than no compensation on every forward fold, so none is safe to apply: {}",
                list.join("; ")
            ))
        })?;
        scores[pick].chosen = true;
        let model = cands[pick].2.fit_rows(data, rows)?;
        Ok(AutoFit {
            model,
            family: scores[pick].family.clone(),
            validation: scores[pick].forward.clone().expect("eligible"),
            candidates: scores,
        })
    }
}

/// Index of the candidate the one-standard-error rule picks among the eligible ones (module
/// docs), `None` when none is eligible.
pub fn one_standard_error(scores: &[CandidateScore]) -> Option<usize> {
    let eligible: Vec<usize> = (0..scores.len())
        .filter(|&i| scores[i].eligible())
        .collect();
    let mean = |i: usize| scores[i].forward.as_ref().expect("eligible").mean_rmse_um();
    let best = *eligible
        .iter()
        .min_by(|&&a, &&b| mean(a).total_cmp(&mean(b)))?;
    let limit = mean(best)
        + scores[best]
            .forward
            .as_ref()
            .expect("eligible")
            .rmse_std_error_um;
    eligible
        .into_iter()
        .filter(|&i| mean(i) <= limit)
        .min_by(|&a, &b| {
            scores[a]
                .complexity
                .cmp(&scores[b].complexity)
                .then(mean(a).total_cmp(&mean(b)))
        })
}

/// `Predict` of the chosen model (so an `AutoFit` can be used where a model is).
impl<M: Predict> Predict for AutoFit<M> {
    fn predict(&self, data: &ThermalData) -> Result<Vec<f64>, ThermalError> {
        self.model.predict(data)
    }
    fn predictors(&self) -> usize {
        self.model.predictors()
    }
}
