//! The neural models' options of `thermal fit|cv` (bpnn, cnn-lstm, and auto's
//! `--with-networks`), in every build: a build without the cargo feature `neural` must still
//! refuse an option no chosen model reads, and name it.

use crate::unused::{refuse_unused, Given};
use crate::Result;

/// What the networks are trained with; `None`: the network's default (`mtec_nn`).
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkOptions {
    /// cnn-lstm: column that splits an experiment into sequences (one time series per value).
    pub sequence_by: Option<String>,
    /// Extra feature columns after the sensors (`cos_K(COL)`, `sin_K(COL)` of angle columns).
    pub features: Vec<String>,
    /// Each angle feature column as the harmonics k = 1..N.
    pub angle_harmonics: Option<u8>,
    /// The sensors as rises over each sequence's first row.
    pub rises: bool,
    /// The targets as their change since each sequence's first row.
    pub changes: bool,
    /// Largest number of epochs (bpnn: Levenberg–Marquardt iterations).
    pub epochs: Option<usize>,
    /// Epochs without improvement of the validation loss before stopping.
    pub patience: Option<usize>,
    /// cnn-lstm: time steps per window (rows of the log).
    pub window: Option<usize>,
    /// cnn-lstm: convolution filters.
    pub conv_channels: Option<usize>,
    /// cnn-lstm: LSTM hidden units.
    pub lstm_hidden: Option<usize>,
    /// cnn-lstm: Adam step size.
    pub learning_rate: Option<f64>,
    /// cnn-lstm: cosine decay of the step size to this fraction of it.
    pub final_lr_fraction: Option<f64>,
    /// cnn-lstm: mini-batch size.
    pub batch_size: Option<usize>,
    /// bpnn: hidden units.
    pub hidden: Option<usize>,
    /// Weight decay λ ≥ 0 (bpnn: λ·‖w‖²; cnn-lstm: AdamW); `None`: 0.
    pub weight_decay: Option<f64>,
    /// Seed of the weight initialisation and batch order.
    pub seed: u64,
    /// auto: these networks (`bpnn`, `cnn-lstm`) are candidates too.
    pub with_networks: Vec<String>,
}

impl NetworkOptions {
    /// Every option at the network's default, seed 42 (the command line's).
    pub fn new() -> NetworkOptions {
        NetworkOptions {
            sequence_by: None,
            features: Vec::new(),
            angle_harmonics: None,
            rises: false,
            changes: false,
            epochs: None,
            patience: None,
            window: None,
            conv_channels: None,
            lstm_hidden: None,
            learning_rate: None,
            final_lr_fraction: None,
            batch_size: None,
            hidden: None,
            weight_decay: None,
            seed: 42,
            with_networks: Vec::new(),
        }
    }

    /// A network option given to a model that does not read it is refused (a usage error), not
    /// ignored: no network outside bpnn and cnn-lstm (auto: those of `with_networks`).
    pub fn refuse_unused(&self, model: &str) -> Result<()> {
        let (nets, cnn, bp): (&[&str], &[&str], &[&str]) =
            (&["bpnn", "cnn-lstm"], &["cnn-lstm"], &["bpnn"]);
        let chosen: Vec<&str> = match model {
            "auto" => self.with_networks.iter().map(String::as_str).collect(),
            m => vec![m],
        };
        let o = |option, given, read_by: &[&str]| Given::among(option, given, read_by, &chosen);
        let options = [
            o("--sequence-by", self.sequence_by.is_some(), nets),
            o("--features", !self.features.is_empty(), nets),
            o("--angle-harmonics", self.angle_harmonics.is_some(), nets),
            o("--rises", self.rises, nets),
            o("--changes", self.changes, nets),
            o("--epochs", self.epochs.is_some(), nets),
            o("--patience", self.patience.is_some(), nets),
            o("--weight-decay", self.weight_decay.is_some(), nets),
            o("--window", self.window.is_some(), cnn),
            o("--conv-channels", self.conv_channels.is_some(), cnn),
            o("--lstm-hidden", self.lstm_hidden.is_some(), cnn),
            o("--learning-rate", self.learning_rate.is_some(), cnn),
            o("--final-lr-fraction", self.final_lr_fraction.is_some(), cnn),
            o("--batch-size", self.batch_size.is_some(), cnn),
            o("--hidden", self.hidden.is_some(), bp),
        ];
        refuse_unused(&format!("--model {model}"), &options)
    }

    /// The network and its training as `mtec_nn` takes them, for the model `model` (auto's
    /// networks: bpnn's options).
    #[cfg(feature = "neural")]
    pub fn fit_options(&self, model: &str) -> mtec_nn::thermal_log::NnFitOptions {
        use mtec_nn::thermal_log::{NnFitOptions, NnKind};
        let kind = NnKind::from_name(model).unwrap_or(NnKind::Bpnn);
        NnFitOptions {
            sequence_by: self.sequence_by.clone(),
            features: self.features.clone(),
            angle_harmonics: self.angle_harmonics,
            rises: self.rises,
            changes: self.changes,
            epochs: self.epochs,
            patience: self.patience,
            window: self.window,
            conv_channels: self.conv_channels,
            lstm_hidden: self.lstm_hidden,
            learning_rate: self.learning_rate,
            final_lr_fraction: self.final_lr_fraction,
            batch_size: self.batch_size,
            hidden: self.hidden,
            weight_decay: self.weight_decay.unwrap_or(0.0),
            seed: self.seed,
            ..NnFitOptions::new(kind)
        }
    }
}

impl Default for NetworkOptions {
    fn default() -> Self {
        NetworkOptions::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_no_chosen_network_reads_is_refused() {
        let mut o = NetworkOptions::new();
        assert!(o.refuse_unused("mlr").is_ok());
        o.window = Some(8);
        assert!(o.refuse_unused("cnn-lstm").is_ok());
        let e = o.refuse_unused("bpnn").unwrap_err().to_string();
        assert!(e.contains("--window") && e.contains("cnn-lstm"), "{e}");
        // auto reads what its --with-networks read
        assert!(o.refuse_unused("auto").is_err());
        o.with_networks = vec!["cnn-lstm".into()];
        assert!(o.refuse_unused("auto").is_ok());
        o.window = None;
        o.hidden = Some(5);
        assert!(o.refuse_unused("auto").is_err());
    }
}
