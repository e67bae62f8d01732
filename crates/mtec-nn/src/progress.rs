//! What a training tells its caller while it runs, and how the caller stops it: a [`Monitor`]
//! passed in (argmin-style observer). The training never draws or prints anything itself; the
//! command line draws its progress line from [`Epoch`], a test collects them, Python forwards
//! them.

use serde::{Serialize, Serializer};
use std::fmt;

/// One finished epoch (Levenberg–Marquardt: one accepted iteration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Epoch<'a> {
    /// Which training (`CNN-LSTM`, `BPNN (LM)`, `BPNN (Adam)`).
    pub model: &'a str,
    /// 1-based.
    pub epoch: usize,
    pub max_epochs: usize,
    /// Training loss (MSE in normalised units).
    pub loss: f64,
    /// Validation loss, when there are validation rows.
    pub validation_loss: Option<f64>,
}

impl fmt::Display for Epoch<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} epoch {}/{} loss {:.4e}",
            self.model, self.epoch, self.max_epochs, self.loss
        )?;
        if let Some(v) = self.validation_loss {
            write!(f, " val {v:.4e}")?;
        }
        Ok(())
    }
}

/// Receives the epochs of a training and may ask it to stop. Every method has a default that
/// ignores it.
pub trait Monitor {
    /// An epoch has finished.
    fn epoch(&mut self, _epoch: &Epoch) {}
    /// The training has ended, for `reason`.
    fn finished(&mut self, _reason: &StopReason) {}
    /// True when the caller asks the training to stop after the current epoch (it then keeps
    /// the best epoch's weights and reports [`StopReason::User`]).
    fn stop_requested(&self) -> bool {
        false
    }
}

/// A monitor that ignores everything (the training runs to its own end).
#[derive(Debug, Default, Clone, Copy)]
pub struct Quiet;

impl Monitor for Quiet {}

/// A closure called with every epoch is a monitor.
impl<F: FnMut(&Epoch)> Monitor for F {
    fn epoch(&mut self, epoch: &Epoch) {
        self(epoch)
    }
}

/// Why a training (or a Levenberg–Marquardt minimisation) stopped. Serialised as its sentence
/// (the model files' `stop_reason`).
#[derive(Debug, Clone, PartialEq)]
pub enum StopReason {
    /// The largest number of epochs ran.
    MaxEpochs(usize),
    /// The largest number of Levenberg–Marquardt iterations ran.
    MaxIterations(usize),
    /// The validation loss did not improve for `patience` epochs.
    EarlyStop { patience: usize, best_epoch: usize },
    /// The caller asked to stop ([`Monitor::stop_requested`]).
    User { epoch: usize, best_epoch: usize },
    /// The loss became NaN or infinite.
    Diverged,
    /// Levenberg–Marquardt: the gradient fell below the threshold.
    SmallGradient(f64),
    /// Levenberg–Marquardt: no damping μ up to its maximum gave a step (the Cholesky factor
    /// failed throughout).
    DampingExceeded,
    /// Levenberg–Marquardt: no damping μ up to its maximum lowered the error further.
    NoFurtherDecrease,
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopReason::MaxEpochs(n) => write!(f, "maximum of {n} epochs"),
            StopReason::MaxIterations(n) => write!(f, "maximum of {n} iterations"),
            StopReason::EarlyStop {
                patience,
                best_epoch,
            } => write!(
                f,
                "early stop: no validation improvement for {patience} epochs (best epoch {best_epoch})"
            ),
            StopReason::User { epoch, best_epoch } => write!(
                f,
                "stopped by the user after epoch {epoch}; keeping the best epoch {best_epoch}"
            ),
            StopReason::Diverged => write!(f, "training diverged (non-finite loss)"),
            StopReason::SmallGradient(g) => write!(f, "gradient below {g:e}"),
            StopReason::DampingExceeded => write!(f, "damping μ exceeded its maximum"),
            StopReason::NoFurtherDecrease => {
                write!(f, "damping μ exceeded its maximum (no further decrease)")
            }
        }
    }
}

impl Serialize for StopReason {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sentences are the ones the model files carried when the reason was a string.
    #[test]
    fn reasons_read_as_before() {
        assert_eq!(
            StopReason::MaxEpochs(60).to_string(),
            "maximum of 60 epochs"
        );
        assert_eq!(
            StopReason::EarlyStop {
                patience: 15,
                best_epoch: 7
            }
            .to_string(),
            "early stop: no validation improvement for 15 epochs (best epoch 7)"
        );
        assert_eq!(
            serde_json::to_value(StopReason::User {
                epoch: 3,
                best_epoch: 2
            })
            .unwrap(),
            "stopped by the user after epoch 3; keeping the best epoch 2"
        );
        assert_eq!(
            StopReason::SmallGradient(1e-9).to_string(),
            format!("gradient below {:e}", 1e-9)
        );
    }
}
