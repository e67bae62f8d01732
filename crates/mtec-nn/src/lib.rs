//! mtec-nn: neural error models trained and evaluated on the CPU.
//!
//! What it is for:
//! - [`bpnn`]: a one-hidden-layer back-propagation network (e.g. 3-10-3, sigmoid) with input and
//!   output normalisation, trained by Levenberg–Marquardt ([`lm`], small nets) or Adam (candle),
//!   early stopping on a validation split, reproducible by seed. The trained network is a plain
//!   Rust struct: evaluating it ([`Bpnn::predict`], [`Bpnn::error_um`]) needs no neural-network
//!   library, so compensation can call it every interpolation cycle. Saved as `mtec.bpnn/1` JSON.
//! - [`grid_fit`]: fits a BPNN to a volumetric error grid (`x_mm,y_mm,z_mm,ex_um,ey_um,ez_um`)
//!   and reports fit-error statistics per axis and the parameter count against the grid size.
//! - [`cnn_lstm`]: a CNN-LSTM (1-D convolution over the feature vector of each time step,
//!   max pooling, LSTM over a window of time steps, dense output) that predicts any set of error
//!   channels from temperatures (+ angle / position), trained on the CPU by its own forward and
//!   backward kernel ([`cnn_lstm_kernel`], checked against candle); saved as
//!   `mtec.cnn-lstm/1` JSON with its weights. Both networks are trained through
//!   [`thermal_fit`] on mtec-thermal's `ThermalData` (the one public time-series data set) and
//!   scored with its `Metrics`; the crate-private `dataset` is their training representation
//!   (experiments × sequences × time × features, the tensors' source).
//! - [`rotary`]: ballbar-identified error motions and a temperature log joined into
//!   `ThermalData` (one sequence per experiment and angle), and predicted motions mapped back
//!   to ballbar readings; [`lagged_linear`], the non-neural reference on the same data;
//!   [`synthetic`], an analytic rotary thermal model of the same shape.
//!
//! - [`thermal_log`]: a rotary thermal log (CSV) read into mtec-thermal's `ThermalData` (several
//!   targets, a sequence column, angle harmonics), which of its columns are features and
//!   targets, and the training configuration of a `thermal fit` on it.
//! - [`thermal_fit`]: the networks as thermal model kinds on `ThermalData`: mtec-thermal's
//!   `Fit`/`Predict`, so they are split, validated and scored (`Metrics`) by the regression
//!   models' own code.
//! - [`progress`]: the [`Monitor`] a caller passes to a training to follow its epochs and stop it,
//!   and the typed [`StopReason`].
//!
//! What it is not for: writing files or drawing progress (the caller does), and GPU training.
//! This is the only crate of the workspace that depends on the neural-network library (candle,
//! see `NN_CHOICE.md`); everything it exports is plain Rust data.

mod baseline;
/// The network as plain data lives in `mtec-comp` (a compensable model, evaluated without
/// candle); re-exported here, where it is trained.
pub mod bpnn {
    pub use mtec_comp::bpnn::*;
}
pub mod bpnn_train;
pub mod cnn_lstm;
pub mod cnn_lstm_kernel;
mod dataset;
pub mod error;
pub mod grid_fit;
pub mod harmonic_net;
pub mod lagged_linear;
pub mod lm;
pub mod progress;
mod rng;
pub mod rotary;
pub mod synthetic;
pub mod thermal_fit;
pub mod thermal_log;
pub mod threads;

pub use bpnn::{Activation, Bpnn};
pub use bpnn_train::{train_bpnn, train_bpnn_monitored, BpnnTrainConfig, Optimizer, TrainReport};
pub use cnn_lstm::{CnnLstm, CnnLstmConfig, CnnLstmReport};
pub use error::NnError;
pub use grid_fit::{fit_grid, fit_grid_monitored, GridFitConfig, GridFitReport};
pub use progress::{Epoch, Monitor, Quiet, StopReason};
pub use thermal_fit::{NeuralFit, NeuralThermalModel};
