//! Training progress on the terminal: an indicatif bar showing epoch, loss and validation loss.

use indicatif::{ProgressBar, ProgressStyle};

pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// A bar over `epochs` epochs, or nothing when `show` is false (tests, `--quiet`).
    pub fn new(show: bool, epochs: usize, what: &str) -> Self {
        if !show {
            return Progress { bar: None };
        }
        let bar = ProgressBar::new(epochs as u64);
        let style =
            ProgressStyle::with_template("{prefix} [{bar:30}] epoch {pos}/{len} {msg} ({elapsed})")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
        bar.set_style(style);
        bar.set_prefix(what.to_string());
        Progress { bar: Some(bar) }
    }

    pub fn epoch(&self, epoch: usize, loss: f64, val_loss: Option<f64>) {
        if let Some(bar) = &self.bar {
            bar.set_position(epoch as u64);
            match val_loss {
                Some(v) => bar.set_message(format!("loss {loss:.4e} val {v:.4e}")),
                None => bar.set_message(format!("loss {loss:.4e}")),
            }
        }
    }

    pub fn finish(&self, why: &str) {
        if let Some(bar) = &self.bar {
            bar.abandon_with_message(why.to_string());
        }
    }
}
