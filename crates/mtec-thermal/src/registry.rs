//! The registry of thermal model kinds: which kinds exist, what options each takes and how each
//! is built from the options of a fit.
//!
//! Every kind is a fitter type (its options as plain data, `Serialize`/`Deserialize`) that
//! implements [`Kind`] ([`crate::kind`]); the [`registry!`] list below turns them into [`ModelSpec`], an enum
//! tagged by the kind's name (`{"model": "ridge", "k": 0.1, ...}`), and [`KINDS`], the table the
//! command line takes its `--model` values and help from. A new kind is one file (the fitter,
//! its `Fit` and its `Kind`) plus one line in `registry!`; it fits to one of the stored forms of
//! [`ThermalModel`] (a new stored form is a new variant there).

use crate::auto::{Auto, AutoFit, Offer, DEFAULT_MAX_SENSORS};
use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::exp_ambient::ExpAmbient;
use crate::fit::Fit;
use crate::heat_input::HeatInput;
use crate::lag_select::LagSelect;
use crate::linear_model::{Mlr, Ridge, RidgeSelect};
use crate::model::ThermalModel;
use crate::options::BlockSpec;
use crate::pls::Pls;
use serde::{Deserialize, Serialize};

// The options, the kind trait and auto's candidate type were defined here; they live in the
// modules below this one now and keep these paths.
pub use crate::auto::AutoCandidate;
pub use crate::kind::{validate_forward, AsModel, Kind, Owned, Validated};
pub use crate::options::FitOptions;

// the usage checks of the options, against the kinds listed here
impl FitOptions {
    /// Whether the options fit together with `kind` (a usage error otherwise, phrased with the
    /// command-line option names).
    pub fn check(&self, kind: &KindInfo) -> Result<(), String> {
        if let Some(b) = self.block_min {
            if !(b > 0.0 && b.is_finite()) {
                return Err("--block-min must be a number of minutes > 0".into());
            }
        }
        if self.max_sensors == Some(0) {
            return Err("--max-sensors must be at least 1".into());
        }
        if self.max_sensors.is_some() && !kind.takes_max_sensors {
            return Err(format!(
                "--max-sensors goes with --model {}",
                names_where(|k| k.takes_max_sensors)
            ));
        }
        (kind.check)(self)?;
        // heat-input, lag-select and pls fitted without their lag and said nothing
        if self.lag && !kind.takes_lag {
            return Err(format!(
                "--lag goes with --model {} (the others choose their dynamics themselves or have none)",
                names_where(|k| k.takes_lag)
            ));
        }
        if !self.up_sensors.is_empty() && !kind.takes_sensor_groups {
            return Err(format!(
                "--up-sensors and --nut-sensors go with --model {}",
                names_where(|k| k.takes_sensor_groups)
            ));
        }
        if let Some(k) = self.k {
            // correlation form: the diagonal of XᵀX is 1, so at k = 100 every coefficient is
            // shrunk a hundredfold and the model is the mean (a larger k was accepted and wrote
            // a constant model)
            if !((0.0..=100.0).contains(&k) && kind.takes_k) {
                return Err(format!(
                    "--k must be a number from 0 to 100 and goes with --model {}",
                    names_where(|k| k.takes_k)
                ));
            }
        }
        Ok(())
    }
}

/// The kinds for which `f` holds, as "a or b".
fn names_where(f: impl Fn(&KindInfo) -> bool) -> String {
    KINDS
        .iter()
        .filter(|k| f(k))
        .map(|k| k.name)
        .collect::<Vec<_>>()
        .join(" or ")
}

fn auto_candidate_of<K: Kind + 'static>(auto: &Auto, data: &ThermalData) -> Option<AutoCandidate> {
    K::auto_candidate(auto, data).map(|(rank, k)| {
        let fitter: Box<dyn Fit<Model = ThermalModel>> = Box::new(Owned(k));
        (rank, fitter)
    })
}

/// What the command line needs to know of a kind.
#[derive(Debug, Clone, Copy)]
pub struct KindInfo {
    pub name: &'static str,
    pub help: &'static str,
    pub takes_k: bool,
    pub takes_lag: bool,
    pub takes_max_sensors: bool,
    pub takes_sensor_groups: bool,
    pub requires_input: bool,
    pub check: fn(&FitOptions) -> Result<(), String>,
    /// The kind as an `auto` candidate ([`Kind::auto_candidate`]).
    pub auto: fn(&Auto, &ThermalData) -> Option<AutoCandidate>,
}

impl KindInfo {
    const fn of<K: Kind + 'static>() -> KindInfo {
        KindInfo {
            name: K::NAME,
            help: K::HELP,
            takes_k: K::TAKES_K,
            takes_lag: K::TAKES_LAG,
            takes_max_sensors: K::TAKES_MAX_SENSORS,
            takes_sensor_groups: K::TAKES_SENSOR_GROUPS,
            requires_input: K::REQUIRES_INPUT,
            check: K::check,
            auto: auto_candidate_of::<K>,
        }
    }
}

/// Every kind's offer of an `auto` candidate ([`Kind::auto_candidate`]; most decline).
pub fn auto_offers() -> Vec<Offer> {
    KINDS.iter().map(|k| (k.name, k.auto)).collect()
}

/// The kind named `name`.
pub fn kind(name: &str) -> Option<&'static KindInfo> {
    KINDS.iter().find(|k| k.name == name)
}

/// The registry: one line per kind, `Variant(FitterType)`; the variant's kebab-case name is the
/// serde tag and must equal `FitterType::NAME` (a test checks it).
macro_rules! registry {
    ($($variant:ident($ty:ty)),* $(,)?) => {
        /// A thermal model kind with its options, tagged by the kind's name.
        #[derive(Debug, Clone, Serialize, Deserialize)]
        #[serde(tag = "model", rename_all = "kebab-case")]
        pub enum ModelSpec {
            $($variant($ty)),*
        }

        /// Every kind, in the order `--model` lists them.
        pub const KINDS: &[KindInfo] = &[$(KindInfo::of::<$ty>()),*];

        impl ModelSpec {
            /// The spec of kind `name` built from `options` (`Invalid` for an unknown name or
            /// options the kind cannot use, e.g. exp-ambient without its two sensors).
            pub fn from_options(
                name: &str,
                options: &FitOptions,
                data: &ThermalData,
            ) -> Result<ModelSpec, ThermalError> {
                $(
                    if name == <$ty as Kind>::NAME {
                        return Ok(ModelSpec::$variant(<$ty as Kind>::from_options(options, data)?));
                    }
                )*
                Err(ThermalError::Invalid(format!("no thermal model kind `{name}`")))
            }

            /// The kind's name.
            pub fn name(&self) -> &'static str {
                match self {
                    $(ModelSpec::$variant(_) => <$ty as Kind>::NAME),*
                }
            }

            /// Fits on `train` with forward validation on its blocks.
            pub fn fit_validated(
                &self,
                data: &ThermalData,
                train: &[usize],
                blocks: &BlockSpec,
            ) -> Result<Validated, ThermalError> {
                match self {
                    $(ModelSpec::$variant(k) => k.fit_validated(data, train, blocks)),*
                }
            }
        }

        impl Fit for ModelSpec {
            type Model = ThermalModel;
            fn fit_rows(
                &self,
                data: &ThermalData,
                rows: &[usize],
            ) -> Result<ThermalModel, ThermalError> {
                match self {
                    $(ModelSpec::$variant(k) => k.fit_model(data, rows)),*
                }
            }
        }

        #[cfg(test)]
        fn defaults() -> Vec<(&'static str, ModelSpec)> {
            vec![$((<$ty as Kind>::NAME, ModelSpec::$variant(<$ty>::default()))),*]
        }
    };
}

registry! {
    Auto(Auto),
    Mlr(Mlr),
    Ridge(Ridge),
    RidgeSelect(RidgeSelect),
    ExpAmbient(ExpAmbient),
    LagSelect(LagSelect),
    HeatInput(HeatInput),
    Pls(Pls),
}

// ---- auto with every kind of the registry (auto itself does not know them) ----

impl Auto {
    /// Scores every candidate, auto's own and every kind of the registry that offers itself, on
    /// the forward folds of `rows`, chooses one, refits it on `rows` ([`Auto::fit_with`]).
    pub fn fit_auto(&self, data: &ThermalData, rows: &[usize]) -> Result<AutoFit, ThermalError> {
        self.fit_with(data, rows, &auto_offers())
    }
}

/// `Auto` as a fitter of [`ThermalModel`] (for validating the whole procedure, nested once more).
impl Fit for Auto {
    type Model = ThermalModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<ThermalModel, ThermalError> {
        self.fit_auto(data, rows).map(|a| a.model)
    }
}

// ---- the kinds of this crate ----

impl Kind for Auto {
    const NAME: &'static str = "auto";
    const HELP: &'static str = "Chooses the family by nested forward validation (see `fit --help`)";
    const TAKES_MAX_SENSORS: bool = true;
    fn check(o: &FitOptions) -> Result<(), String> {
        if o.lag || !o.up_sensors.is_empty() {
            return Err("--model auto chooses lags itself (no --lag) and takes exp-ambient as a candidate only from --sensors UP,NUT".into());
        }
        Ok(())
    }
    /// exp-ambient is a candidate when the data has its columns and `sensors` names its two
    /// sensors.
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        self.fit_rows(d, r)
    }
    fn from_options(o: &FitOptions, data: &ThermalData) -> Result<Self, ThermalError> {
        let exp = data.ambient_c.is_some() && data.position_mm.is_some() && o.sensors.len() == 2;
        Ok(Auto {
            sensors: o.sensors.clone(),
            input: o.input.clone(),
            max_sensors: o.max_sensors.unwrap_or(DEFAULT_MAX_SENSORS),
            block_min: o.block_min,
            exp_ambient: exp.then(|| ExpAmbient {
                up_sensor: o.sensors[0].clone(),
                nut_sensor: o.sensors[1].clone(),
                ..Default::default()
            }),
        })
    }
    fn fit_validated(
        &self,
        data: &ThermalData,
        train: &[usize],
        _blocks: &BlockSpec,
    ) -> Result<Validated, ThermalError> {
        let AutoFit {
            model,
            validation,
            candidates,
            ..
        } = self.fit_auto(data, train)?;
        Ok(Validated {
            model,
            validation: Some(validation),
            candidates,
            warnings: Vec::new(),
        })
    }
}

impl Kind for Mlr {
    const NAME: &'static str = "mlr";
    const TAKES_LAG: bool = true;
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::Linear(self.fit_rows(d, r)?))
    }
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        Ok(Mlr {
            sensors: o.sensors.clone(),
            lag: o.lag,
            blocks: o.blocks(),
        })
    }
}

impl Kind for Ridge {
    const NAME: &'static str = "ridge";
    const TAKES_K: bool = true;
    const TAKES_LAG: bool = true;
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::Linear(self.fit_rows(d, r)?))
    }
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        Ok(Ridge {
            sensors: o.sensors.clone(),
            k: o.k,
            lag: o.lag,
            blocks: o.blocks(),
        })
    }
}

impl Kind for RidgeSelect {
    const NAME: &'static str = "ridge-select";
    const TAKES_LAG: bool = true;
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::Linear(self.fit_rows(d, r)?))
    }
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        Ok(RidgeSelect {
            sensors: o.sensors.clone(),
            options: Default::default(),
            lag: o.lag,
        })
    }
}

impl Kind for ExpAmbient {
    const NAME: &'static str = "exp-ambient";
    const TAKES_SENSOR_GROUPS: bool = true;
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::ExpAmbient(Box::new(self.fit_rows(d, r)?)))
    }
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        if !o.up_sensors.is_empty() {
            return Ok(ExpAmbient {
                up_sensors: o.up_sensors.clone(),
                nut_sensors: o.nut_sensors.clone(),
                ..Default::default()
            });
        }
        let [up, nut] = o.sensors.as_slice() else {
            return Err(ThermalError::Invalid(
                "exp-ambient needs --sensors UP,NUT: the upper-bearing sensor, then the ball-screw-nut sensor (or --up-sensors A,B --nut-sensors C,D for sensor groups)".into(),
            ));
        };
        Ok(ExpAmbient {
            up_sensor: up.clone(),
            nut_sensor: nut.clone(),
            ..Default::default()
        })
    }
}

impl Kind for LagSelect {
    const NAME: &'static str = "lag-select";
    const TAKES_MAX_SENSORS: bool = true;
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::Linear(self.fit_rows(d, r)?))
    }
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        Ok(LagSelect {
            sensors: o.sensors.clone(),
            max_sensors: o.max_sensors.unwrap_or(3),
            block_min: o.block_min,
            input: Some(o.input.clone()),
        })
    }
}

impl Kind for HeatInput {
    const NAME: &'static str = "heat-input";
    const REQUIRES_INPUT: bool = true;
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::HeatInput(self.fit_rows(d, r)?))
    }
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        Ok(HeatInput {
            input: o.input.clone(),
            block_min: o.block_min,
            ..Default::default()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The serde tag of every kind is its `--model` name, and a spec reads back as itself.
    #[test]
    fn tags_are_the_names() {
        for (name, spec) in defaults() {
            let v = serde_json::to_value(&spec).unwrap();
            assert_eq!(v["model"], name);
            assert_eq!(spec.name(), name);
            let back: ModelSpec = serde_json::from_value(v.clone()).unwrap();
            assert_eq!(serde_json::to_value(&back).unwrap(), v);
        }
        let names: Vec<&str> = KINDS.iter().map(|k| k.name).collect();
        assert_eq!(
            names,
            [
                "auto",
                "mlr",
                "ridge",
                "ridge-select",
                "exp-ambient",
                "lag-select",
                "heat-input",
                "pls"
            ]
        );
    }

    /// A spec written by hand takes the kind's defaults for what it leaves out.
    #[test]
    fn partial_spec_takes_defaults() {
        let s: ModelSpec = serde_json::from_str(r#"{"model": "ridge", "k": 0.25}"#).unwrap();
        match s {
            ModelSpec::Ridge(r) => {
                assert_eq!(r.k, Some(0.25));
                assert!(!r.lag && r.sensors.is_empty());
            }
            other => panic!("{other:?}"),
        }
    }

    /// The usage messages name the kinds that take an option, from the registry.
    #[test]
    fn option_checks_name_the_kinds() {
        let mlr = kind("mlr").unwrap();
        let o = FitOptions {
            max_sensors: Some(2),
            ..Default::default()
        };
        assert_eq!(
            o.check(mlr).unwrap_err(),
            "--max-sensors goes with --model auto or lag-select"
        );
        let o = FitOptions {
            k: Some(0.1),
            ..Default::default()
        };
        assert_eq!(
            o.check(mlr).unwrap_err(),
            "--k must be a number from 0 to 100 and goes with --model ridge"
        );
        for bad in [1e9, -0.1, f64::NAN] {
            let o = FitOptions {
                k: Some(bad),
                ..Default::default()
            };
            assert!(o.check(kind("ridge").unwrap()).is_err(), "{bad}");
        }
        assert!(o.check(kind("ridge").unwrap()).is_ok());
        let o = FitOptions {
            lag: true,
            ..Default::default()
        };
        assert!(o.check(kind("auto").unwrap()).is_err());
        for name in ["exp-ambient", "heat-input", "lag-select", "pls"] {
            assert_eq!(
                o.check(kind(name).unwrap()).unwrap_err(),
                "--lag goes with --model mlr or ridge or ridge-select (the others choose their dynamics themselves or have none)",
                "{name}"
            );
        }
        for name in ["mlr", "ridge", "ridge-select"] {
            assert!(o.check(kind(name).unwrap()).is_ok(), "{name}");
        }
    }
}
