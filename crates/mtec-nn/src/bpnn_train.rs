//! Training a [`Bpnn`]: normalisation, seeded initialisation, Levenberg–Marquardt or Adam,
//! early stopping on a validation split.
//!
//! Decisions where the source is silent:
//! - Inputs are scaled to [−1, 1] by their min/max, outputs z-scored; the loss is the mean
//!   squared error in normalised output units, so every output counts equally.
//! - The validation split is a seeded random subset of the rows (`validation_fraction`,
//!   default 15 %) when the caller gives none; grid points are not a time series, so random
//!   rows are legitimate here (for time series pass explicit validation rows, see
//!   [`train_bpnn_with_validation`]).
//! - Early stopping: training stops when the validation MSE has not improved for `patience`
//!   iterations/epochs (6 for LM as in MATLAB `trainlm`'s `max_fail`, 50 for Adam) and the
//!   weights of the best validation epoch are returned.
//! - Initial weights: Glorot-uniform, drawn from `StdRng::seed_from_u64(seed)`. Both optimisers
//!   are deterministic on the CPU, so the same data and seed give bit-identical weights.
//! - Levenberg–Marquardt uses the analytic Jacobian of the network (back-propagation of each
//!   residual, checked against finite differences in the tests); Adam runs on candle autograd
//!   (candle's AdamW with weight decay 0 is Adam, Kingma & Ba 2015).

use crate::bpnn::{param_count, Activation, Affine, Bpnn};
use crate::error::{NnError, Result};
use crate::lm::{self, Control, LmConfig, LmProblem};
use crate::progress::{Epoch, Monitor, Quiet, StopReason};
use crate::rng;
use candle_core::{Device, Tensor, Var};
use candle_nn::optim::{AdamW, Optimizer as _, ParamsAdamW};
use nalgebra::{DMatrix, DVector};
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

/// Which optimiser trains the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Optimizer {
    /// Levenberg–Marquardt on all parameters (best for small nets: ≲ a few hundred parameters).
    LevenbergMarquardt,
    /// Adam with mini-batches (any size).
    Adam,
}

/// How to train a BPNN.
#[derive(Debug, Clone)]
pub struct BpnnTrainConfig {
    pub hidden: usize,
    pub activation: Activation,
    pub optimizer: Optimizer,
    /// LM iterations or Adam epochs.
    pub max_epochs: usize,
    /// Adam step size (normalised units).
    pub learning_rate: f64,
    /// Adam mini-batch size; `None` = full batch.
    pub batch_size: Option<usize>,
    /// Share of rows held out for early stopping when no validation rows are given.
    pub validation_fraction: f64,
    /// Time series ([`crate::baseline::train_bpnn_baseline`]): early stopping on this whole
    /// training experiment instead of every sequence's tail. Unused for plain rows.
    pub validation_experiment: Option<u32>,
    /// Epochs without validation improvement before stopping; `None` = 6 (LM) or 50 (Adam).
    pub patience: Option<usize>,
    /// Levenberg–Marquardt only: λ of the penalty λ·‖w‖² on the weights (not the biases),
    /// added to the squared normalised residuals (ridge-type weight decay; 0 = none).
    pub weight_decay: f64,
    pub seed: u64,
}

impl Default for BpnnTrainConfig {
    fn default() -> Self {
        BpnnTrainConfig {
            hidden: 10,
            activation: Activation::Sigmoid,
            optimizer: Optimizer::LevenbergMarquardt,
            max_epochs: 1000,
            learning_rate: 0.01,
            batch_size: None,
            validation_fraction: 0.15,
            validation_experiment: None,
            patience: None,
            weight_decay: 0.0,
            seed: 42,
        }
    }
}

/// What happened during training (losses are MSE in normalised output units).
#[derive(Debug, Clone, Serialize)]
pub struct TrainReport {
    pub epochs: usize,
    pub best_epoch: usize,
    pub train_mse: f64,
    pub validation_mse: Option<f64>,
    pub stop_reason: StopReason,
    /// (train MSE, validation MSE) per epoch.
    pub history: Vec<(f64, Option<f64>)>,
}

/// Trains on rows `x` → `y`, holding out a seeded random `validation_fraction` of the rows for
/// early stopping.
pub fn train_bpnn(
    x: &[Vec<f64>],
    y: &[Vec<f64>],
    config: &BpnnTrainConfig,
) -> Result<(Bpnn, TrainReport)> {
    train_bpnn_monitored(x, y, config, &mut Quiet)
}

/// [`train_bpnn`] reporting every epoch to `monitor`, which may stop it.
pub fn train_bpnn_monitored(
    x: &[Vec<f64>],
    y: &[Vec<f64>],
    config: &BpnnTrainConfig,
    monitor: &mut dyn Monitor,
) -> Result<(Bpnn, TrainReport)> {
    check_rows(x, y)?;
    let mut idx: Vec<usize> = (0..x.len()).collect();
    let mut r = rng::seeded(config.seed ^ SPLIT_STREAM);
    idx.shuffle(&mut r);
    let n_val = ((x.len() as f64) * config.validation_fraction).round() as usize;
    let n_val = if x.len() - n_val < 2 { 0 } else { n_val };
    let (val_idx, train_idx) = idx.split_at(n_val);
    let pick =
        |ids: &[usize], rows: &[Vec<f64>]| ids.iter().map(|&i| rows[i].clone()).collect::<Vec<_>>();
    let (xt, yt) = (pick(train_idx, x), pick(train_idx, y));
    let (xv, yv) = (pick(val_idx, x), pick(val_idx, y));
    train_bpnn_with_validation_monitored(&xt, &yt, &xv, &yv, config, monitor)
}

/// Separates the split's random stream from the initialisation's.
const SPLIT_STREAM: u64 = 0x5eed_5917;

/// Trains on `xt` → `yt` with explicit validation rows (`xv` may be empty: no early stopping).
pub fn train_bpnn_with_validation(
    xt: &[Vec<f64>],
    yt: &[Vec<f64>],
    xv: &[Vec<f64>],
    yv: &[Vec<f64>],
    config: &BpnnTrainConfig,
) -> Result<(Bpnn, TrainReport)> {
    train_bpnn_with_validation_monitored(xt, yt, xv, yv, config, &mut Quiet)
}

/// [`train_bpnn_with_validation`] reporting every epoch to `monitor`, which may stop it.
pub fn train_bpnn_with_validation_monitored(
    xt: &[Vec<f64>],
    yt: &[Vec<f64>],
    xv: &[Vec<f64>],
    yv: &[Vec<f64>],
    config: &BpnnTrainConfig,
    monitor: &mut dyn Monitor,
) -> Result<(Bpnn, TrainReport)> {
    check_rows(xt, yt)?;
    if !xv.is_empty() {
        check_rows(xv, yv)?;
        if xv[0].len() != xt[0].len() || yv[0].len() != yt[0].len() {
            return Err(NnError::Data(
                "validation rows have another width than training rows".into(),
            ));
        }
    }
    if config.hidden == 0 || config.hidden > crate::cnn_lstm::MAX_UNITS {
        return Err(NnError::Config(format!(
            "hidden size {}: must be 1 to {}",
            config.hidden,
            crate::cnn_lstm::MAX_UNITS
        )));
    }
    if config.max_epochs == 0 || config.max_epochs > crate::cnn_lstm::MAX_EPOCHS {
        return Err(NnError::Config(format!(
            "max_epochs {}: must be 1 to {}",
            config.max_epochs,
            crate::cnn_lstm::MAX_EPOCHS
        )));
    }
    if !(config.learning_rate > 0.0 && config.learning_rate <= crate::cnn_lstm::MAX_LEARNING_RATE) {
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
    if config.weight_decay > 0.0 && config.optimizer == Optimizer::Adam {
        return Err(NnError::Config(
            "weight decay is a Levenberg–Marquardt option (Adam would ignore it)".into(),
        ));
    }
    let (n_in, n_out) = (xt[0].len(), yt[0].len());
    let in_norm = Affine::min_max(xt, n_in);
    let out_norm = Affine::z_score(yt, n_out);
    let normalise =
        |rows: &[Vec<f64>], a: &Affine| rows.iter().map(|r| a.forward(r)).collect::<Vec<_>>();
    let train = Normalised {
        x: normalise(xt, &in_norm),
        y: normalise(yt, &out_norm),
    };
    let val = Normalised {
        x: normalise(xv, &in_norm),
        y: normalise(yv, &out_norm),
    };
    let theta0 = glorot_init(n_in, config.hidden, n_out, config.seed);
    let template = Bpnn::from_params(
        n_in,
        config.hidden,
        n_out,
        config.activation,
        &in_norm,
        &out_norm,
        &theta0,
    );
    let (theta, report) = match config.optimizer {
        Optimizer::LevenbergMarquardt => train_lm(&template, &train, &val, theta0, config, monitor),
        Optimizer::Adam => train_adam(&template, &train, &val, theta0, config, monitor)?,
    };
    let mut net = template;
    net.set_params(&theta);
    net.provenance = serde_json::json!({
        "trainer": match config.optimizer { Optimizer::LevenbergMarquardt => "levenberg-marquardt", Optimizer::Adam => "adam" },
        "seed": config.seed,
        "epochs": report.epochs,
        "best_epoch": report.best_epoch,
        "train_rows": xt.len(),
        "validation_rows": xv.len(),
        "stop_reason": report.stop_reason,
    });
    Ok((net, report))
}

fn check_rows(x: &[Vec<f64>], y: &[Vec<f64>]) -> Result<()> {
    if x.is_empty() {
        return Err(NnError::Data("no training rows".into()));
    }
    if x.len() != y.len() {
        return Err(NnError::Data(format!(
            "{} input rows but {} target rows",
            x.len(),
            y.len()
        )));
    }
    let (ni, no) = (x[0].len(), y[0].len());
    if ni == 0 || no == 0 {
        return Err(NnError::Data(
            "rows must have at least one input and one output".into(),
        ));
    }
    for (k, (a, b)) in x.iter().zip(y).enumerate() {
        if a.len() != ni || b.len() != no {
            return Err(NnError::Data(format!(
                "row {k} has another width than row 0"
            )));
        }
        if a.iter().chain(b).any(|v| !v.is_finite()) {
            return Err(NnError::Data(format!("row {k} holds a non-finite value")));
        }
    }
    Ok(())
}

struct Normalised {
    x: Vec<Vec<f64>>,
    y: Vec<Vec<f64>>,
}

/// Glorot-uniform weights (bound √(6/(fan_in+fan_out))), zero biases, in θ layout.
fn glorot_init(n_in: usize, n_h: usize, n_out: usize, seed: u64) -> Vec<f64> {
    let mut r = rng::seeded(seed);
    let mut theta = Vec::with_capacity(param_count(n_in, n_h, n_out));
    theta.extend(rng::uniform(
        &mut r,
        n_h * n_in,
        (6.0 / (n_in + n_h) as f64).sqrt(),
    ));
    theta.extend(std::iter::repeat_n(0.0, n_h));
    theta.extend(rng::uniform(
        &mut r,
        n_out * n_h,
        (6.0 / (n_h + n_out) as f64).sqrt(),
    ));
    theta.extend(std::iter::repeat_n(0.0, n_out));
    theta
}

/// Mean squared error of `net` (normalised units) on normalised rows.
fn mse(net: &Bpnn, data: &Normalised) -> f64 {
    if data.x.is_empty() {
        return f64::NAN;
    }
    let mut hidden = vec![0.0; net.n_hidden()];
    let mut yn = vec![0.0; net.n_out()];
    let mut s = 0.0;
    for (x, y) in data.x.iter().zip(&data.y) {
        net.forward_normalised(x, &mut hidden, &mut yn);
        s += yn.iter().zip(y).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
    }
    s / (data.x.len() * net.n_out()) as f64
}

/// Residuals e = ŷ − y over all rows and outputs, and their analytic Jacobian; with a weight
/// decay λ > 0 followed by √λ·w for every weight (‖e‖² then holds the penalty λ‖w‖²).
struct BpnnLeastSquares<'a> {
    net: Bpnn,
    data: &'a Normalised,
    decay: f64,
}

impl BpnnLeastSquares<'_> {
    fn with(&self, theta: &[f64]) -> Bpnn {
        let mut n = self.net.clone();
        n.set_params(theta);
        n
    }

    /// The indices in θ of the weights (W1, then W2; the biases excluded), when decayed.
    fn decayed(&self) -> Vec<usize> {
        if self.decay <= 0.0 {
            return Vec::new();
        }
        let (n_in, n_h, n_out) = (self.net.n_in(), self.net.n_hidden(), self.net.n_out());
        let off_w2 = n_h * n_in + n_h;
        (0..n_h * n_in)
            .chain(off_w2..off_w2 + n_out * n_h)
            .collect()
    }
}

impl LmProblem for BpnnLeastSquares<'_> {
    fn residuals(&self, theta: &[f64]) -> DVector<f64> {
        let net = self.with(theta);
        let n_out = net.n_out();
        let decayed = self.decayed();
        let n_fit = self.data.x.len() * n_out;
        let mut e = DVector::zeros(n_fit + decayed.len());
        let root = self.decay.max(0.0).sqrt();
        for (k, &i) in decayed.iter().enumerate() {
            e[n_fit + k] = root * theta[i];
        }
        let mut hidden = vec![0.0; net.n_hidden()];
        let mut yn = vec![0.0; n_out];
        for (r, (x, y)) in self.data.x.iter().zip(&self.data.y).enumerate() {
            net.forward_normalised(x, &mut hidden, &mut yn);
            for o in 0..n_out {
                e[r * n_out + o] = yn[o] - y[o];
            }
        }
        e
    }

    /// Back-propagation of each output (Hagan & Menhaj 1994, the Marquardt sensitivities):
    /// ∂ŷ_o/∂W2[o][h] = s_h, ∂ŷ_o/∂b2[o] = 1, ∂ŷ_o/∂W1[h][i] = W2[o][h]·σ'(a_h)·x_i,
    /// ∂ŷ_o/∂b1[h] = W2[o][h]·σ'(a_h).
    fn jacobian(&self, theta: &[f64]) -> DMatrix<f64> {
        let net = self.with(theta);
        let (n_in, n_h, n_out) = (net.n_in(), net.n_hidden(), net.n_out());
        let (off_b1, off_w2) = (n_h * n_in, n_h * n_in + n_h);
        let off_b2 = off_w2 + n_out * n_h;
        let decayed = self.decayed();
        let n_fit = self.data.x.len() * n_out;
        let mut j = DMatrix::zeros(n_fit + decayed.len(), theta.len());
        let root = self.decay.max(0.0).sqrt();
        for (k, &i) in decayed.iter().enumerate() {
            j[(n_fit + k, i)] = root;
        }
        let mut a = vec![0.0; n_h];
        let mut s = vec![0.0; n_h];
        let mut ds = vec![0.0; n_h];
        for (r, x) in self.data.x.iter().enumerate() {
            for h in 0..n_h {
                a[h] = net.b1[h] + net.w1[h].iter().zip(x).map(|(w, v)| w * v).sum::<f64>();
                s[h] = net.activation.apply(a[h]);
                ds[h] = net.activation.derivative(a[h], s[h]);
            }
            for o in 0..n_out {
                let row = r * n_out + o;
                for h in 0..n_h {
                    let back = net.w2[o][h] * ds[h];
                    for i in 0..n_in {
                        j[(row, h * n_in + i)] = back * x[i];
                    }
                    j[(row, off_b1 + h)] = back;
                    j[(row, off_w2 + o * n_h + h)] = s[h];
                }
                j[(row, off_b2 + o)] = 1.0;
            }
        }
        j
    }
}

/// Early-stopping bookkeeping shared by both optimisers.
struct EarlyStop {
    patience: usize,
    best: f64,
    best_epoch: usize,
    best_theta: Vec<f64>,
    history: Vec<(f64, Option<f64>)>,
}

impl EarlyStop {
    fn new(patience: usize, theta0: &[f64]) -> Self {
        EarlyStop {
            patience,
            best: f64::INFINITY,
            best_epoch: 0,
            best_theta: theta0.to_vec(),
            history: Vec::new(),
        }
    }

    /// Records an epoch; returns a reason to stop when validation has not improved for
    /// `patience` epochs, or when the monitor asks to stop. Without validation rows the
    /// training loss plays its role.
    fn record(
        &mut self,
        epoch: usize,
        theta: &[f64],
        train: f64,
        val: Option<f64>,
        monitor: &dyn Monitor,
    ) -> Option<StopReason> {
        self.history.push((train, val));
        let watch = val.unwrap_or(train);
        if watch < self.best {
            self.best = watch;
            self.best_epoch = epoch;
            self.best_theta = theta.to_vec();
        }
        if monitor.stop_requested() {
            return Some(StopReason::User {
                epoch,
                best_epoch: self.best_epoch,
            });
        }
        if epoch - self.best_epoch >= self.patience {
            return Some(StopReason::EarlyStop {
                patience: self.patience,
                best_epoch: self.best_epoch,
            });
        }
        None
    }
}

fn train_lm(
    template: &Bpnn,
    train: &Normalised,
    val: &Normalised,
    theta0: Vec<f64>,
    config: &BpnnTrainConfig,
    monitor: &mut dyn Monitor,
) -> (Vec<f64>, TrainReport) {
    let problem = BpnnLeastSquares {
        net: template.clone(),
        data: train,
        decay: config.weight_decay,
    };
    let lm_config = LmConfig {
        max_iterations: config.max_epochs,
        ..LmConfig::default()
    };
    let n_rows = (train.x.len() * template.n_out()) as f64;
    let mut stop = EarlyStop::new(config.patience.unwrap_or(6), &theta0);
    let outcome = lm::minimise(&problem, &theta0, &lm_config, |it, theta, sse| {
        // the data's part of ‖e‖² (without the weight decay's rows)
        let penalty: f64 = (problem.decayed().iter())
            .map(|&i| config.weight_decay * theta[i] * theta[i])
            .sum();
        let train_mse = (sse - penalty) / n_rows;
        let val_mse = (!val.x.is_empty()).then(|| mse(&problem.with(theta), val));
        monitor.epoch(&Epoch {
            model: "BPNN (LM)",
            epoch: it,
            max_epochs: config.max_epochs,
            loss: train_mse,
            validation_loss: val_mse,
        });
        match stop.record(it, theta, train_mse, val_mse, &*monitor) {
            Some(why) => Control::Stop(why),
            None => Control::Continue,
        }
    });
    monitor.finished(&outcome.stop_reason);
    // LM may stop (μ at maximum, gradient) before the first callback: keep the start then.
    let best_theta = if stop.history.is_empty() {
        outcome.theta.clone()
    } else {
        stop.best_theta.clone()
    };
    let best = problem.with(&best_theta);
    let report = TrainReport {
        epochs: outcome.iterations,
        best_epoch: stop.best_epoch,
        train_mse: mse(&best, train),
        validation_mse: (!val.x.is_empty()).then(|| mse(&best, val)),
        stop_reason: outcome.stop_reason,
        history: stop.history,
    };
    (best_theta, report)
}

fn to_tensor(rows: &[Vec<f64>], dev: &Device) -> Result<Tensor> {
    let (n, m) = (rows.len(), rows.first().map_or(0, |r| r.len()));
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Ok(Tensor::from_vec(flat, (n, m), dev)?)
}

fn train_adam(
    template: &Bpnn,
    train: &Normalised,
    val: &Normalised,
    theta0: Vec<f64>,
    config: &BpnnTrainConfig,
    monitor: &mut dyn Monitor,
) -> Result<(Vec<f64>, TrainReport)> {
    let dev = Device::Cpu;
    let (n_in, n_h, n_out) = (template.n_in(), template.n_hidden(), template.n_out());
    let init = template_with(template, &theta0);
    let w1 = Var::from_tensor(&to_tensor(&init.w1, &dev)?)?;
    let b1 = Var::from_tensor(&Tensor::from_vec(init.b1.clone(), n_h, &dev)?)?;
    let w2 = Var::from_tensor(&to_tensor(&init.w2, &dev)?)?;
    let b2 = Var::from_tensor(&Tensor::from_vec(init.b2.clone(), n_out, &dev)?)?;
    let activation = template.activation;
    let forward = |x: &Tensor| -> candle_core::Result<Tensor> {
        let a = x
            .matmul(&w1.as_tensor().t()?)?
            .broadcast_add(b1.as_tensor())?;
        let s = match activation {
            Activation::Sigmoid => candle_nn::ops::sigmoid(&a)?,
            Activation::Tanh => a.tanh()?,
            Activation::Relu => a.relu()?,
        };
        s.matmul(&w2.as_tensor().t()?)?
            .broadcast_add(b2.as_tensor())
    };
    let xt = to_tensor(&train.x, &dev)?;
    let yt = to_tensor(&train.y, &dev)?;
    let params = ParamsAdamW {
        lr: config.learning_rate,
        weight_decay: 0.0,
        ..ParamsAdamW::default()
    };
    let mut adam = AdamW::new(vec![w1.clone(), b1.clone(), w2.clone(), b2.clone()], params)?;
    let n = train.x.len();
    let batch = config.batch_size.unwrap_or(n).clamp(1, n);
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut shuffle_rng = rng::seeded(config.seed ^ SPLIT_STREAM.rotate_left(17));
    let mut stop = EarlyStop::new(config.patience.unwrap_or(50), &theta0);
    let mut stop_reason = StopReason::MaxEpochs(config.max_epochs);
    let mut epochs = 0;
    let current_theta = || -> Result<Vec<f64>> {
        let mut t = w1.as_tensor().flatten_all()?.to_vec1::<f64>()?;
        t.extend(b1.as_tensor().to_vec1::<f64>()?);
        t.extend(w2.as_tensor().flatten_all()?.to_vec1::<f64>()?);
        t.extend(b2.as_tensor().to_vec1::<f64>()?);
        Ok(t)
    };
    for epoch in 1..=config.max_epochs {
        epochs = epoch;
        if batch < n {
            order.shuffle(&mut shuffle_rng);
        }
        for chunk in order.chunks(batch) {
            let (xb, yb) = if batch < n {
                let ids = Tensor::from_vec(chunk.to_vec(), chunk.len(), &dev)?;
                (xt.index_select(&ids, 0)?, yt.index_select(&ids, 0)?)
            } else {
                (xt.clone(), yt.clone())
            };
            let loss = (forward(&xb)? - yb)?.sqr()?.mean_all()?;
            adam.backward_step(&loss)?;
        }
        let theta = current_theta()?;
        let net = template_with(template, &theta);
        let train_mse = mse(&net, train);
        let val_mse = (!val.x.is_empty()).then(|| mse(&net, val));
        monitor.epoch(&Epoch {
            model: "BPNN (Adam)",
            epoch,
            max_epochs: config.max_epochs,
            loss: train_mse,
            validation_loss: val_mse,
        });
        if !train_mse.is_finite() {
            stop_reason = StopReason::Diverged;
            break;
        }
        if let Some(why) = stop.record(epoch, &theta, train_mse, val_mse, &*monitor) {
            stop_reason = why;
            break;
        }
    }
    monitor.finished(&stop_reason);
    let _ = n_in;
    let best = template_with(template, &stop.best_theta);
    let report = TrainReport {
        epochs,
        best_epoch: stop.best_epoch,
        train_mse: mse(&best, train),
        validation_mse: (!val.x.is_empty()).then(|| mse(&best, val)),
        stop_reason,
        history: stop.history,
    };
    Ok((stop.best_theta, report))
}

fn template_with(template: &Bpnn, theta: &[f64]) -> Bpnn {
    let mut n = template.clone();
    n.set_params(theta);
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toy(n: usize) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for k in 0..n {
            let a = k as f64 / (n - 1) as f64 * 4.0 - 2.0;
            let b = ((k * 7) % n) as f64 / n as f64 * 2.0 - 1.0;
            x.push(vec![a, b]);
            y.push(vec![(a).sin() + 0.5 * b, a * b]);
        }
        (x, y)
    }

    #[test]
    fn analytic_jacobian_equals_finite_differences() {
        let (x, y) = toy(20);
        for (act, decay) in [
            (Activation::Sigmoid, 0.0),
            (Activation::Tanh, 0.0),
            (Activation::Sigmoid, 0.3),
        ] {
            let inorm = Affine::min_max(&x, 2);
            let onorm = Affine::z_score(&y, 2);
            let data = Normalised {
                x: x.iter().map(|r| inorm.forward(r)).collect(),
                y: y.iter().map(|r| onorm.forward(r)).collect(),
            };
            let theta = glorot_init(2, 4, 2, 3);
            let net = Bpnn::from_params(2, 4, 2, act, &inorm, &onorm, &theta);
            let p = BpnnLeastSquares {
                net,
                data: &data,
                decay,
            };
            let j = p.jacobian(&theta);
            // the decay's rows: one per weight (2·4 + 4·2), none per bias
            assert_eq!(j.nrows(), 20 * 2 + if decay > 0.0 { 16 } else { 0 });
            let e = p.residuals(&theta);
            let penalty: f64 = e.iter().skip(40).map(|v| v * v).sum();
            let weights: f64 = (theta[..8].iter().chain(&theta[12..20]))
                .map(|w| w * w)
                .sum();
            assert!(
                (penalty - decay * weights).abs() < 1e-12,
                "{penalty} vs {weights}"
            );
            let h = 1e-6;
            for k in 0..theta.len() {
                let mut tp = theta.clone();
                tp[k] += h;
                let mut tm = theta.clone();
                tm[k] -= h;
                let col = (p.residuals(&tp) - p.residuals(&tm)) / (2.0 * h);
                for r in 0..col.len() {
                    assert!(
                        (col[r] - j[(r, k)]).abs() < 1e-7,
                        "{act:?} θ{k} row {r}: {} vs {}",
                        col[r],
                        j[(r, k)]
                    );
                }
            }
        }
    }

    /// Weight decay (Levenberg–Marquardt) trades fit for smaller weights: a large λ gives a
    /// smaller ‖w‖ and a larger training error than none; with Adam it is refused, not ignored.
    #[test]
    fn weight_decay_shrinks_the_weights_and_is_refused_with_adam() {
        let (x, y) = toy(60);
        let cfg = |decay| BpnnTrainConfig {
            hidden: 6,
            max_epochs: 100,
            validation_fraction: 0.0,
            weight_decay: decay,
            seed: 5,
            ..BpnnTrainConfig::default()
        };
        let norm = |n: &Bpnn| -> f64 {
            let w1: f64 = n.w1.iter().flatten().map(|w| w * w).sum();
            let w2: f64 = n.w2.iter().flatten().map(|w| w * w).sum();
            w1 + w2
        };
        let (free, rf) = train_bpnn(&x, &y, &cfg(0.0)).unwrap();
        let (decayed, rd) = train_bpnn(&x, &y, &cfg(1.0)).unwrap();
        assert!(
            norm(&decayed) < 0.5 * norm(&free),
            "{} vs {}",
            norm(&decayed),
            norm(&free)
        );
        assert!(rd.train_mse > rf.train_mse, "{rd:?} {rf:?}");
        let adam = BpnnTrainConfig {
            optimizer: Optimizer::Adam,
            ..cfg(0.1)
        };
        let e = train_bpnn(&x, &y, &adam).unwrap_err().to_string();
        assert!(e.contains("Levenberg"), "{e}");
        assert!(train_bpnn(&x, &y, &cfg(-1.0)).is_err());
    }

    #[test]
    fn both_optimisers_fit_a_smooth_function_and_are_reproducible() {
        let (x, y) = toy(120);
        for opt in [Optimizer::LevenbergMarquardt, Optimizer::Adam] {
            let cfg = BpnnTrainConfig {
                hidden: 8,
                optimizer: opt,
                max_epochs: if opt == Optimizer::Adam { 1500 } else { 200 },
                learning_rate: 0.02,
                seed: 7,
                ..BpnnTrainConfig::default()
            };
            let (a, ra) = train_bpnn(&x, &y, &cfg).unwrap();
            let (b, _) = train_bpnn(&x, &y, &cfg).unwrap();
            assert_eq!(
                a.params(),
                b.params(),
                "{opt:?}: same seed must give identical weights"
            );
            // the targets have std ≈ 0.8: a normalised MSE of 1e-2 means a ~0.08 RMS fit
            assert!(ra.train_mse < 1e-2, "{opt:?}: {ra:?}");
            assert!(
                ra.validation_mse.unwrap() < 2e-2,
                "{opt:?}: {:?}",
                ra.validation_mse
            );
            let c = train_bpnn(
                &x,
                &y,
                &BpnnTrainConfig {
                    seed: 8,
                    ..cfg.clone()
                },
            )
            .unwrap()
            .0;
            assert_ne!(
                a.params(),
                c.params(),
                "{opt:?}: another seed, other weights"
            );
        }
    }

    #[test]
    fn bad_training_data_is_refused() {
        let cfg = BpnnTrainConfig::default();
        assert!(train_bpnn(&[], &[], &cfg).is_err());
        assert!(train_bpnn(&[vec![1.0], vec![2.0]], &[vec![1.0]], &cfg).is_err());
        assert!(train_bpnn(&[vec![f64::NAN], vec![2.0]], &[vec![1.0], vec![2.0]], &cfg).is_err());
        let zero = BpnnTrainConfig { hidden: 0, ..cfg };
        assert!(train_bpnn(&[vec![1.0], vec![2.0]], &[vec![1.0], vec![2.0]], &zero).is_err());
    }
}
