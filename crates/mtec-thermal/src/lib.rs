//! mtec-thermal: thermal error models of machine tools, fitted from temperature logs.
//!
//! What it is for: predicting thermal drift (µm) from temperature sensors, with the methods of
//! the source literature — multiple linear regression, ridge regression with variance inflation
//! factors, the ridge trace and sensor elimination by its rules, the comparison table (full MLR,
//! ridge-selected, simple-correlation top-n), and the ambient-adaptive exponential feed-axis
//! model — plus thermal-dynamics features (first-order lags with fitted time constants,
//! temperature rates) so a linear model follows duty cycles it was not trained on,
//! `lag-select`, a forward selection of a few sensors with lags scored on held-out blocks, and
//! `heat-input`, the drift as the lagged response to the spindle power (with longer time
//! constants at rest than while running) plus ambient sensors. The exp-ambient model keeps its
//! time-constant-like parameters positive, reports when the data cannot separate them from the
//! amplitudes, and can take its temperature rises from sensor groups (first principal
//! component).
//! Every model `fit`s and `predict`s through the traits in [`fit`], serialises to versioned
//! JSON (`mtec.thermal-model/1`) and is scored by one [`Metrics`] type.
//!
//! What it is not for: reading files beyond turning a [`mtec_io::Table`] into [`ThermalData`],
//! neural models (`mtec-nn`), or simulating the machine (`mtec-sim`). Validation splits are by
//! whole experiments or time blocks, never random rows (drift is autocorrelated; random rows
//! leak the answer).

// `!(a > b)` is deliberate: it is true for NaN, which must fail the check; index loops read
// like the equations they implement.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod auto;
pub mod data;
pub mod error;
pub mod exp_ambient;
pub mod features;
pub mod fit;
pub mod guard;
pub mod heat_input;
pub mod kind;
pub mod lag_select;
pub mod linear;
pub mod linear_model;
pub mod metrics;
pub mod model;
pub mod model_file;
pub mod options;
pub mod pls;
pub mod registry;
pub mod select;
pub mod stepwise;
pub mod stream;
pub mod summary;
mod tall_qr;
pub mod validate;

pub use data::ThermalData;
pub use error::ThermalError;
pub use exp_ambient::{ExpAmbient, ExpAmbientModel};
pub use features::Feature;
pub use fit::{Fit, Predict};
pub use heat_input::{HeatInput, HeatInputModel};
pub use lag_select::LagSelect;
pub use linear_model::{LinearModel, Mlr, Ridge, RidgeSelect};
pub use metrics::{Metrics, TargetMetrics};
pub use model::ThermalModel;
pub use model_file::{ModelFile, Split, MODEL_FORMAT};
pub use options::FitOptions;
pub use registry::{ModelSpec, KINDS};
pub use select::{select_sensors, RidgeTrace, SelectOptions, Selection};
pub use stream::ThermalStream;
pub use summary::{ModelSummary, Term};
