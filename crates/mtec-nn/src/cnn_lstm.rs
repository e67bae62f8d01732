//! CNN-LSTM sequence model (CPU): for each time step a 1-D convolution over the feature
//! vector (temperatures, angle/position), ReLU and max pooling extract local features; an LSTM
//! runs over a window of `window` time steps; a dense layer maps its last hidden state to the
//! error channels.
//!
//! Shapes: window [B, W, F] → [B·W, 1, F] → Conv1d(1→C, k, same padding) → ReLU →
//! MaxPool(2) (as `max_pool2d((1,2))` on [B·W, C, 1, F]: candle has no `max_pool1d`) →
//! [B, W, C·⌊F/2⌋] → LSTM(H) → h_W [B, H] → Linear(H → O). Parameter names and layouts are
//! PyTorch's (`conv.weight`, `lstm.weight_ih_l0`, gate order i, f, g, o, `fc.weight`), so the
//! same network can be rebuilt in PyTorch (`bench/cnn_lstm.sh`). Training and prediction run
//! on the hand-written forward/backward kernel of [`crate::cnn_lstm_kernel`] (with its Adam,
//! the algorithm candle-nn's `AdamW` computes); the candle version of the forward pass is kept
//! for the tests, as the reference the kernel is checked against.
//!
//! Decisions where the source is silent:
//! - Features and targets are z-scored with the training rows' mean/std; the loss is the MSE in
//!   normalised units.
//! - A window ending at row t uses rows t−W+1..=t; rows before the start of a sequence repeat
//!   its first row (the machine was at its initial state before the log started).
//! - Early stopping holds out the last `validation_fraction` of the scored rows of every
//!   training sequence (a block at the end of each series, never random rows), or one whole
//!   training experiment (`validation_experiment`), and keeps the weights of the best
//!   validation epoch.
//! - Initialisation as PyTorch's defaults (uniform ±1/√fan_in), drawn from a seeded StdRng;
//!   mini-batch order from a seeded shuffle: the same seed gives the same weights.
//!
//! File format `mtec.cnn-lstm/1` (JSON): `format`, `architecture` (window, conv_channels,
//! kernel, lstm_hidden), `feature_names`, `target_names`, `feature_offset/scale`,
//! `target_offset/scale`, `weights` (name → `{shape, data}` row-major f32), `provenance`.

use crate::bpnn::Affine;
use crate::cnn_lstm_kernel::{Adam, Dims, Params, Workspace};
use crate::dataset::{Sequence, ThermalDataset};
use crate::error::{NnError, Result};
use crate::progress::{Epoch, Monitor, StopReason};
use crate::rng;
#[cfg(test)]
use candle_core::Tensor;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Instant;

pub const FORMAT: &str = "mtec.cnn-lstm/1";

/// The network's shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Architecture {
    /// Time steps per window.
    pub window: usize,
    /// Convolution filters C.
    pub conv_channels: usize,
    /// Convolution kernel size k (odd: "same" padding k/2).
    pub kernel: usize,
    /// LSTM hidden size H.
    pub lstm_hidden: usize,
}

/// How to train.
#[derive(Debug, Clone)]
pub struct CnnLstmConfig {
    pub architecture: Architecture,
    pub max_epochs: usize,
    pub batch_size: usize,
    pub learning_rate: f64,
    /// Cosine decay of the step size over `max_epochs`, from `learning_rate` to
    /// `learning_rate × final_learning_rate_fraction` (1 = constant step size).
    pub final_learning_rate_fraction: f64,
    pub validation_fraction: f64,
    /// Early stopping on this whole training experiment instead of every sequence's tail
    /// (`validation_fraction` is then unused); it must be one of the training experiments.
    pub validation_experiment: Option<u32>,
    /// Epochs without validation improvement before stopping.
    pub patience: usize,
    /// Decoupled weight decay of Adam (AdamW, Loshchilov & Hutter 2019): every step also
    /// multiplies each parameter by 1 − lr·weight_decay (0 = Adam).
    pub weight_decay: f64,
    pub seed: u64,
}

impl Default for CnnLstmConfig {
    /// The "source-sized" network: 16 filters of width 3, LSTM of 32 units over 16 time steps.
    fn default() -> Self {
        CnnLstmConfig {
            architecture: Architecture {
                window: 16,
                conv_channels: 16,
                kernel: 3,
                lstm_hidden: 32,
            },
            max_epochs: 60,
            batch_size: 64,
            learning_rate: 3e-3,
            final_learning_rate_fraction: 1.0,
            validation_fraction: 0.15,
            validation_experiment: None,
            patience: 15,
            weight_decay: 0.0,
            seed: 42,
        }
    }
}

/// What happened during training (losses are MSE in normalised units).
#[derive(Debug, Clone, Serialize)]
pub struct CnnLstmReport {
    pub epochs: usize,
    pub best_epoch: usize,
    pub train_loss: f64,
    pub validation_loss: Option<f64>,
    pub stop_reason: StopReason,
    pub seconds: f64,
    pub seconds_per_epoch: f64,
    pub train_windows: usize,
    pub validation_windows: usize,
    pub parameters: usize,
    /// (train loss, validation loss) per epoch.
    pub history: Vec<(f64, Option<f64>)>,
}

/// A tensor stored in the model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoredTensor {
    pub shape: Vec<usize>,
    pub data: Vec<f32>,
}

/// A trained CNN-LSTM with its normalisation; see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CnnLstm {
    pub format: String,
    pub architecture: Architecture,
    pub feature_names: Vec<String>,
    pub target_names: Vec<String>,
    pub feature_offset: Vec<f64>,
    pub feature_scale: Vec<f64>,
    pub target_offset: Vec<f64>,
    pub target_scale: Vec<f64>,
    pub weights: BTreeMap<String, StoredTensor>,
    #[serde(default)]
    pub provenance: serde_json::Value,
}

/// The parameter shapes of the architecture for F features and O outputs, PyTorch names.
fn param_shapes(
    a: &Architecture,
    n_features: usize,
    n_out: usize,
) -> Vec<(&'static str, Vec<usize>, f64)> {
    let (c, k, h) = (a.conv_channels, a.kernel, a.lstm_hidden);
    let d = c * (n_features / 2);
    let conv_bound = 1.0 / (k as f64).sqrt();
    let lstm_bound = 1.0 / (h as f64).sqrt();
    let fc_bound = 1.0 / (h as f64).sqrt();
    vec![
        ("conv.weight", vec![c, 1, k], conv_bound),
        ("conv.bias", vec![c], conv_bound),
        ("lstm.weight_ih_l0", vec![4 * h, d], lstm_bound),
        ("lstm.weight_hh_l0", vec![4 * h, h], lstm_bound),
        ("lstm.bias_ih_l0", vec![4 * h], lstm_bound),
        ("lstm.bias_hh_l0", vec![4 * h], lstm_bound),
        ("fc.weight", vec![n_out, h], fc_bound),
        ("fc.bias", vec![n_out], fc_bound),
    ]
}

/// Largest window (rows) and layer width a CNN-LSTM may be given.
pub const MAX_WINDOW: usize = 10_000;
pub const MAX_UNITS: usize = 1000;

/// Largest step size (Adam or AdamW) a network may be trained with: beyond 1 the weights of
/// these z-scored problems diverge in the first steps.
pub const MAX_LEARNING_RATE: f64 = 1.0;

/// Most epochs (or LM iterations) a network may be asked for: 10⁶ epochs of the smallest
/// network here take days; a typing slip of 10⁹ would run for years without a word.
pub const MAX_EPOCHS: usize = 1_000_000;

fn check_architecture(a: &Architecture, n_features: usize) -> Result<()> {
    if a.window == 0 || a.conv_channels == 0 || a.lstm_hidden == 0 {
        return Err(NnError::Config(
            "window, conv_channels and lstm_hidden must be at least 1".into(),
        ));
    }
    // the bounds of a network this machine can train (the source's: window 16, 16 filters,
    // LSTM 32): a size of 10⁹ asked for gigabytes and aborted the process
    for (name, v, max) in [
        ("window", a.window, MAX_WINDOW),
        ("conv_channels", a.conv_channels, MAX_UNITS),
        ("lstm_hidden", a.lstm_hidden, MAX_UNITS),
    ] {
        if v > max {
            return Err(NnError::Config(format!("{name} {v}: at most {max}")));
        }
    }
    if a.kernel.is_multiple_of(2) {
        return Err(NnError::Config(format!(
            "the kernel size must be odd (same padding), got {}",
            a.kernel
        )));
    }
    // candle 0.11's Conv1d gradient underflows (panics) when the input is shorter than the
    // kernel, so fewer features than the kernel width is refused here, not left to candle
    if n_features < a.kernel.max(2) {
        return Err(NnError::Config(format!(
            "the convolution over the features needs at least {} features (kernel {}, pooling 2); the data have {n_features}",
            a.kernel.max(2),
            a.kernel
        )));
    }
    Ok(())
}

/// The network in candle (the reference of the kernel's tests): its tensors by name.
#[cfg(test)]
pub(crate) struct Net {
    arch: Architecture,
    p: BTreeMap<String, Tensor>,
}

#[cfg(test)]
impl Net {
    pub(crate) fn new(arch: Architecture, p: BTreeMap<String, Tensor>) -> Self {
        Net { arch, p }
    }

    /// Forward pass of windows x [B, W, F] (normalised) → [B, O].
    pub(crate) fn forward(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        let (b, w, f) = x.dims3()?;
        let a = &self.arch;
        let c = a.conv_channels;
        let p = |n: &str| &self.p[n];
        // 1-D convolution over the feature vector of each time step
        let z = x
            .reshape((b * w, 1, f))?
            .conv1d(p("conv.weight"), a.kernel / 2, 1, 1, 1)?;
        let z = z
            .broadcast_add(&p("conv.bias").reshape((1, c, 1))?)?
            .relu()?;
        // max pooling by 2 along the features: [B·W, C, 1, F] → [B·W, C, 1, ⌊F/2⌋]
        let z = z.reshape((b * w, c, 1, f))?.max_pool2d((1, 2))?;
        let seq = z.reshape((b * w, c * (f / 2)))?;
        self.lstm_head(&seq, b, w)
    }

    /// The LSTM and dense layers on the pooled features [B·W, D] (rows window-major).
    pub(crate) fn lstm_head(
        &self,
        seq: &Tensor,
        b: usize,
        w: usize,
    ) -> candle_core::Result<Tensor> {
        let h = self.arch.lstm_hidden;
        let p = |n: &str| &self.p[n];
        // LSTM (Hochreiter & Schmidhuber 1997; PyTorch's gate order i, f, g, o):
        // the input projection of all steps at once, then the recurrence step by step.
        let xp = seq
            .matmul(&p("lstm.weight_ih_l0").t()?)?
            .broadcast_add(p("lstm.bias_ih_l0"))?
            .broadcast_add(p("lstm.bias_hh_l0"))?
            .reshape((b, w, 4 * h))?;
        let w_hh_t = p("lstm.weight_hh_l0").t()?;
        let mut hs = Tensor::zeros((b, h), seq.dtype(), seq.device())?;
        let mut cs = Tensor::zeros((b, h), seq.dtype(), seq.device())?;
        for t in 0..w {
            let gates = (xp.narrow(1, t, 1)?.squeeze(1)? + hs.matmul(&w_hh_t)?)?;
            let i = candle_nn::ops::sigmoid(&gates.narrow(1, 0, h)?)?;
            let fg = candle_nn::ops::sigmoid(&gates.narrow(1, h, h)?)?;
            let g = gates.narrow(1, 2 * h, h)?.tanh()?;
            let o = candle_nn::ops::sigmoid(&gates.narrow(1, 3 * h, h)?)?;
            cs = ((fg * &cs)? + (i * g)?)?; // c_t = f ⊙ c_{t−1} + i ⊙ g
            hs = (o * cs.tanh()?)?; // h_t = o ⊙ tanh(c_t)
        }
        hs.matmul(&p("fc.weight").t()?)?.broadcast_add(p("fc.bias"))
    }
}

/// Windows of normalised features [N, W, F] (flattened) and normalised targets [N, O], plus
/// each window's (experiment index, sequence index, row) for mapping predictions back.
struct Windows {
    x: Vec<f32>,
    y: Vec<f32>,
    n: usize,
}

impl Windows {
    fn new() -> Self {
        Windows {
            x: Vec::new(),
            y: Vec::new(),
            n: 0,
        }
    }
    fn push(&mut self, seq: &Sequence, t: usize, window: usize, fnorm: &Affine, tnorm: &Affine) {
        for k in 0..window {
            let row = (t + k + 1).saturating_sub(window);
            let f = fnorm.forward(&seq.features[row]);
            self.x.extend(f.iter().map(|v| *v as f32));
        }
        self.y
            .extend(tnorm.forward(&seq.targets[t]).iter().map(|v| *v as f32));
        self.n += 1;
    }
    /// The mean squared error of the network on these windows, in chunks of the workspace.
    fn mse(&self, ws: &mut Workspace<f32>, p: &Params<f32>) -> f64 {
        let (wf, no) = (self.x.len() / self.n.max(1), p.dims.outputs);
        let mut sum = 0.0;
        for start in (0..self.n).step_by(ws.capacity()) {
            let end = (start + ws.capacity()).min(self.n);
            let y = ws.forward(p, &self.x[start * wf..end * wf]);
            for (a, b) in y.iter().zip(&self.y[start * no..end * no]) {
                sum += ((a - b) as f64).powi(2);
            }
        }
        sum / (self.n * no).max(1) as f64
    }
}

/// The kernel's dimensions of an architecture for F features and O outputs.
fn dims_of(a: &Architecture, n_features: usize, n_out: usize) -> Dims {
    Dims {
        window: a.window,
        features: n_features,
        channels: a.conv_channels,
        kernel: a.kernel,
        hidden: a.lstm_hidden,
        outputs: n_out,
    }
}

/// Windows per forward call when evaluating (validation loss, prediction).
const EVAL_CHUNK: usize = 512;

fn all_rows(d: &ThermalDataset, targets: bool) -> Vec<Vec<f64>> {
    d.experiments
        .iter()
        .flat_map(|e| &e.sequences)
        .flat_map(|s| {
            let rows = if targets { &s.targets } else { &s.features };
            s.scored_rows().map(move |t| rows[t].clone())
        })
        .collect()
}

/// A validation experiment must be one of the training experiments, and not the only one.
pub(crate) fn check_validation_experiment(train: &ThermalDataset, v: Option<u32>) -> Result<()> {
    let Some(v) = v else { return Ok(()) };
    let ids: Vec<u32> = train.experiments.iter().map(|e| e.id).collect();
    if !ids.contains(&v) || ids.len() < 2 {
        return Err(NnError::Config(format!(
            "the validation experiment {v} must be one of at least two training experiments (training: {ids:?})"
        )));
    }
    Ok(())
}

/// Trains a CNN-LSTM on every experiment of `train` (the training representation of
/// [`crate::thermal_fit::NeuralFit`], which is how a caller trains one; and
/// [`crate::harmonic_net`]'s sequence stage).
pub(crate) fn train_cnn_lstm(
    train: &ThermalDataset,
    config: &CnnLstmConfig,
) -> Result<(CnnLstm, CnnLstmReport)> {
    train_cnn_lstm_monitored(train, config, &mut crate::progress::Quiet)
}

/// [`train_cnn_lstm`] reporting every epoch to `monitor`, which may stop it (after the current
/// epoch, keeping the best epoch's weights).
pub(crate) fn train_cnn_lstm_monitored(
    train: &ThermalDataset,
    config: &CnnLstmConfig,
    monitor: &mut dyn Monitor,
) -> Result<(CnnLstm, CnnLstmReport)> {
    train.validate()?;
    if !(config.learning_rate > 0.0 && config.learning_rate <= MAX_LEARNING_RATE) {
        return Err(NnError::Config(format!(
            "learning rate {}: must be > 0 and at most 1",
            config.learning_rate
        )));
    }
    if !(config.weight_decay >= 0.0 && config.weight_decay.is_finite()) {
        return Err(NnError::Config(format!(
            "weight decay {}: must be finite and ≥ 0",
            config.weight_decay
        )));
    }
    let arch = config.architecture;
    let (nf, no) = (train.feature_names.len(), train.target_names.len());
    check_architecture(&arch, nf)?;
    if config.batch_size == 0 || config.max_epochs == 0 || config.max_epochs > MAX_EPOCHS {
        return Err(NnError::Config(format!(
            "batch_size must be at least 1 and max_epochs 1 to {MAX_EPOCHS} (got {} and {})",
            config.batch_size, config.max_epochs
        )));
    }
    if !(config.final_learning_rate_fraction > 0.0 && config.final_learning_rate_fraction <= 1.0) {
        return Err(NnError::Config(
            "final_learning_rate_fraction must be in (0, 1]".into(),
        ));
    }
    if !(0.0..0.9).contains(&config.validation_fraction) {
        return Err(NnError::Config(
            "validation_fraction must be in [0, 0.9)".into(),
        ));
    }
    let start = Instant::now();
    let fnorm = Affine::z_score(&all_rows(train, false), nf);
    let tnorm = Affine::z_score(&all_rows(train, true), no);
    check_validation_experiment(train, config.validation_experiment)?;
    // block-wise validation: the tail of each training sequence, or one whole experiment
    let (mut tr, mut va) = (Windows::new(), Windows::new());
    for e in &train.experiments {
        for seq in &e.sequences {
            let split = ThermalDataset::validation_start(
                e.id,
                seq,
                config.validation_fraction,
                config.validation_experiment,
            );
            for t in seq.scored_rows() {
                let target = if t < split { &mut tr } else { &mut va };
                target.push(seq, t, arch.window, &fnorm, &tnorm);
            }
        }
    }
    if tr.n == 0 {
        return Err(NnError::Data(
            "no training windows left after the validation split".into(),
        ));
    }
    let val = (va.n > 0).then_some(&va);
    let dims = dims_of(&arch, nf, no);

    // seeded PyTorch-style initialisation
    let mut r = rng::seeded(config.seed);
    let mut init = BTreeMap::new();
    for (name, shape, bound) in param_shapes(&arch, nf, no) {
        let n: usize = shape.iter().product();
        let data: Vec<f32> = rng::uniform(&mut r, n, bound)
            .into_iter()
            .map(|v| v as f32)
            .collect();
        init.insert(name, data);
    }
    let mut params = Params::<f32>::from_named(dims, |k| init.get(k).map(|v| v.as_slice()))
        .expect("param_shapes and the kernel agree");
    // Adam as candle-nn's AdamW (default β₁, β₂, ε; weight decay 0 unless configured)
    let mut adam = Adam::<f32>::new(params.values.len(), config.weight_decay);
    // every buffer allocated here, once: no allocation per batch
    let batch = config.batch_size.min(tr.n);
    let mut ws = Workspace::<f32>::new(dims, batch);
    let mut eval = Workspace::<f32>::new(dims, EVAL_CHUNK.min(tr.n.max(va.n)));
    let (wf, mut xb, mut yb) = (arch.window * nf, Vec::new(), Vec::new());
    xb.reserve(batch * arch.window * nf);
    yb.reserve(batch * no);
    let mut order: Vec<u32> = (0..tr.n as u32).collect();
    let mut shuffle = rng::seeded(config.seed.wrapping_add(0x9e37_79b9));
    let mut best = (f64::INFINITY, 0usize, snapshot(&params, &arch));
    let mut history = Vec::new();
    let mut stop_reason = StopReason::MaxEpochs(config.max_epochs);
    let mut epochs = 0;
    for epoch in 1..=config.max_epochs {
        epochs = epoch;
        let lr = cosine_step_size(config, epoch);
        order.shuffle(&mut shuffle);
        let mut loss_sum = 0.0;
        for chunk in order.chunks(config.batch_size) {
            xb.clear();
            yb.clear();
            for &i in chunk {
                let i = i as usize;
                xb.extend_from_slice(&tr.x[i * wf..(i + 1) * wf]);
                yb.extend_from_slice(&tr.y[i * no..(i + 1) * no]);
            }
            let loss = ws.loss_and_grad(&params, &xb, &yb);
            adam.step(&mut params.values, &ws.grad, lr);
            loss_sum += loss * chunk.len() as f64;
        }
        let train_loss = loss_sum / tr.n as f64;
        let val_loss = val.map(|v| v.mse(&mut eval, &params));
        history.push((train_loss, val_loss));
        monitor.epoch(&Epoch {
            model: "CNN-LSTM",
            epoch,
            max_epochs: config.max_epochs,
            loss: train_loss,
            validation_loss: val_loss,
        });
        if !train_loss.is_finite() {
            stop_reason = StopReason::Diverged;
            break;
        }
        let watch = val_loss.unwrap_or(train_loss);
        if watch < best.0 {
            best = (watch, epoch, snapshot(&params, &arch));
        }
        if monitor.stop_requested() {
            stop_reason = StopReason::User {
                epoch,
                best_epoch: best.1,
            };
            break;
        }
        if epoch - best.1 >= config.patience {
            stop_reason = StopReason::EarlyStop {
                patience: config.patience,
                best_epoch: best.1,
            };
            break;
        }
    }
    monitor.finished(&stop_reason);
    let seconds = start.elapsed().as_secs_f64();
    let (_, best_epoch, weights) = best;
    let mut model = CnnLstm {
        format: FORMAT.into(),
        architecture: arch,
        feature_names: train.feature_names.clone(),
        target_names: train.target_names.clone(),
        feature_offset: fnorm.offset,
        feature_scale: fnorm.scale,
        target_offset: tnorm.offset,
        target_scale: tnorm.scale,
        weights,
        provenance: serde_json::Value::Null,
    };
    let net = model.params()?;
    let train_loss = tr.mse(&mut eval, &net);
    let validation_loss = val.map(|v| v.mse(&mut eval, &net));
    model.provenance = serde_json::json!({
        "trainer": "adam (mtec cnn_lstm_kernel)",
        "seed": config.seed,
        "epochs": epochs,
        "best_epoch": best_epoch,
        "experiments": train.experiments.iter().map(|e| e.id).collect::<Vec<_>>(),
    });
    let report = CnnLstmReport {
        epochs,
        best_epoch,
        train_loss,
        validation_loss,
        stop_reason,
        seconds,
        seconds_per_epoch: seconds / epochs as f64,
        train_windows: tr.n,
        validation_windows: va.n,
        parameters: model.param_count(),
        history,
    };
    Ok((model, report))
}

/// Step size of `epoch` (1-based): cosine annealing (Loshchilov & Hutter 2017, eq. 5) from
/// `learning_rate` to `learning_rate × final_learning_rate_fraction` over `max_epochs`.
fn cosine_step_size(config: &CnnLstmConfig, epoch: usize) -> f64 {
    let (lr, f) = (config.learning_rate, config.final_learning_rate_fraction);
    let progress = (epoch - 1) as f64 / config.max_epochs.max(1) as f64;
    lr * (f + (1.0 - f) * 0.5 * (1.0 + (std::f64::consts::PI * progress).cos()))
}

/// The parameters as the model file stores them: name → shape and row-major data.
fn snapshot(p: &Params<f32>, arch: &Architecture) -> BTreeMap<String, StoredTensor> {
    let shapes = param_shapes(arch, p.dims.features, p.dims.outputs);
    let parts = crate::cnn_lstm_kernel::named_parts(p, &p.values);
    (shapes.into_iter().zip(parts))
        .map(|((name, shape, _), (kernel_name, data))| {
            debug_assert_eq!(name, kernel_name);
            let data = data.to_vec();
            (name.to_string(), StoredTensor { shape, data })
        })
        .collect()
}

impl CnnLstm {
    /// The stored weights as the kernel's parameters.
    fn params(&self) -> Result<Params<f32>> {
        let dims = dims_of(
            &self.architecture,
            self.feature_names.len(),
            self.target_names.len(),
        );
        Params::from_named(dims, |k| self.weights.get(k).map(|t| t.data.as_slice()))
            .ok_or_else(|| NnError::Model("the weights do not fit the architecture".into()))
    }

    pub fn param_count(&self) -> usize {
        self.weights.values().map(|t| t.data.len()).sum()
    }

    /// Predictions for the scored rows of every sequence, in dataset order (experiment,
    /// sequence, row): one vector of channels per row, physical units.
    pub(crate) fn predict(&self, data: &ThermalDataset) -> Result<Vec<Vec<f64>>> {
        data.validate()?;
        if data.feature_names != self.feature_names {
            return Err(NnError::Data(format!(
                "the model was trained on features [{}], the data has [{}]",
                self.feature_names.join(", "),
                data.feature_names.join(", ")
            )));
        }
        let fnorm = Affine {
            offset: self.feature_offset.clone(),
            scale: self.feature_scale.clone(),
        };
        let no = self.target_names.len();
        let tnorm = Affine {
            offset: vec![0.0; no],
            scale: vec![1.0; no],
        };
        let net = self.params()?;
        let w = self.architecture.window;
        let mut ws = Workspace::<f32>::new(net.dims, EVAL_CHUNK);
        let mut out = Vec::new();
        for seq in data.experiments.iter().flat_map(|e| &e.sequences) {
            // targets are not used for prediction; a zero row keeps the window code simple
            let blind = Sequence {
                features: seq.features.clone(),
                targets: vec![vec![0.0; no]; seq.len()],
                warmup: seq.warmup,
            };
            let rows: Vec<usize> = seq.scored_rows().collect();
            for chunk in rows.chunks(EVAL_CHUNK) {
                let mut win = Windows::new();
                for &t in chunk {
                    win.push(&blind, t, w, &fnorm, &tnorm);
                }
                for r in ws.forward(&net, &win.x).chunks_exact(no) {
                    out.push(
                        r.iter()
                            .enumerate()
                            .map(|(c, v)| self.target_offset[c] + self.target_scale[c] * *v as f64)
                            .collect(),
                    );
                }
            }
        }
        Ok(out)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a CnnLstm always serialises")
    }

    /// Parses and validates an `mtec.cnn-lstm/1` document.
    pub fn from_json(text: &str) -> Result<CnnLstm> {
        let m: CnnLstm = serde_json::from_str(text).map_err(|e| {
            NnError::Model(format!("line {}, column {}: {e}", e.line(), e.column()))
        })?;
        if m.format != FORMAT {
            return Err(NnError::Model(format!(
                "format is \"{}\", expected \"{FORMAT}\"",
                m.format
            )));
        }
        let (nf, no) = (m.feature_names.len(), m.target_names.len());
        check_architecture(&m.architecture, nf).map_err(|e| NnError::Model(e.to_string()))?;
        if m.feature_offset.len() != nf
            || m.feature_scale.len() != nf
            || m.target_offset.len() != no
            || m.target_scale.len() != no
        {
            return Err(NnError::Model(
                "normalisation vectors do not match the feature/target names".into(),
            ));
        }
        for (name, shape, _) in param_shapes(&m.architecture, nf, no) {
            let t = m
                .weights
                .get(name)
                .ok_or_else(|| NnError::Model(format!("weight \"{name}\" is missing")))?;
            if t.shape != shape || t.data.len() != shape.iter().product::<usize>() {
                return Err(NnError::Model(format!(
                    "weight \"{name}\" has shape {:?}, expected {shape:?}",
                    t.shape
                )));
            }
            if t.data.iter().any(|v| !v.is_finite()) {
                return Err(NnError::Model(format!(
                    "weight \"{name}\" holds a non-finite value"
                )));
            }
        }
        if m.weights.len() != param_shapes(&m.architecture, nf, no).len() {
            return Err(NnError::Model(
                "the file holds weights this architecture does not have".into(),
            ));
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An even kernel has no "same" padding: refused, as is a zero width.
    #[test]
    fn an_even_kernel_is_refused() {
        let a = CnnLstmConfig::default().architecture;
        check_architecture(&a, 11).unwrap();
        let even = Architecture { kernel: 4, ..a };
        let e = check_architecture(&even, 11).unwrap_err();
        assert!(e.to_string().contains("odd"), "{e}");
        assert!(check_architecture(&Architecture { window: 0, ..a }, 11).is_err());
    }

    /// Cosine annealing worked by hand: lr at the first epoch, the midpoint of lr and lr·f half
    /// way, lr·f + (lr − lr·f)·(1 + cos(π·9/10))/2 at the last of ten epochs.
    #[test]
    fn cosine_step_size_by_hand() {
        let c = CnnLstmConfig {
            max_epochs: 10,
            learning_rate: 1e-2,
            final_learning_rate_fraction: 0.1,
            ..CnnLstmConfig::default()
        };
        assert!((cosine_step_size(&c, 1) - 1e-2).abs() < 1e-15);
        assert!((cosine_step_size(&c, 6) - 0.5 * (1e-2 + 1e-3)).abs() < 1e-15);
        let last = 1e-3 + 0.5 * 9e-3 * (1.0 + (0.9 * std::f64::consts::PI).cos());
        assert!((cosine_step_size(&c, 10) - last).abs() < 1e-15);
        let constant = CnnLstmConfig {
            final_learning_rate_fraction: 1.0,
            ..c
        };
        assert!((1..=10).all(|e| cosine_step_size(&constant, e) == 1e-2));
    }
}
