//! The neural models' command-line options. The models (`mtec-nn`, candle: over half of a cold
//! release build, docs/building.md) are the cargo feature `neural`, off by default; the options
//! are parsed either way, a build without them refuses with exit 2 saying how to get them.

/// Options of the neural models (ignored by the regression models).
#[derive(clap::Args, Debug, Clone)]
pub struct NnArgs {
    /// cnn-lstm: column that splits an experiment into sequences (e.g. `angle_deg`: one time
    /// series per angle); default: one sequence per experiment.
    #[arg(long)]
    pub sequence_by: Option<String>,
    /// Extra feature columns after the sensors (e.g. `angle_deg`, `ambient_c`, `position_mm`).
    /// `cos_K(COL)` / `sin_K(COL)` is cos/sin of K times the angle column COL (degrees).
    #[arg(long, value_delimiter = ',')]
    pub features: Vec<String>,
    /// Each --features angle column (`*_deg`) as harmonics cos_k(COL), sin_k(COL), k = 1..N:
    /// continuous across 0°/360°, as the static motions of a rotary axis are (3 is a good start).
    #[arg(long, value_name = "N")]
    pub angle_harmonics: Option<u8>,
    /// The sensors as rises over the first row of each sequence (experiment): thermal errors are
    /// defined against the first (static) measurement, so a warmer room does not throw the model.
    #[arg(long)]
    pub rises: bool,
    /// The targets as their change since each sequence's first row; predict adds it back.
    #[arg(long)]
    pub changes: bool,
    /// Largest number of training epochs (cnn-lstm, bpnn: Levenberg–Marquardt iterations).
    #[arg(long)]
    pub epochs: Option<usize>,
    /// Epochs without improvement of the validation loss before stopping.
    #[arg(long)]
    pub patience: Option<usize>,
    /// cnn-lstm: time steps per window, in rows of the log (interval recorded) [default: 16]
    #[arg(long)]
    pub window: Option<usize>,
    /// cnn-lstm: convolution filters [default: 16].
    #[arg(long)]
    pub conv_channels: Option<usize>,
    /// cnn-lstm: LSTM hidden units [default: 32].
    #[arg(long)]
    pub lstm_hidden: Option<usize>,
    /// cnn-lstm: Adam step size [default: 0.003].
    #[arg(long)]
    pub learning_rate: Option<f64>,
    /// cnn-lstm: cosine decay of the step size to this fraction of it (1: constant) [default: 1]
    #[arg(long, value_name = "F")]
    pub final_lr_fraction: Option<f64>,
    /// cnn-lstm: mini-batch size [default: 64].
    #[arg(long)]
    pub batch_size: Option<usize>,
    /// bpnn: hidden units [default: 10].
    #[arg(long)]
    pub hidden: Option<usize>,
    /// Weight decay λ ≥ 0 (bpnn: λ·‖w‖² in Levenberg–Marquardt; cnn-lstm: AdamW) [default: 0].
    #[arg(long, value_name = "LAMBDA")]
    pub weight_decay: Option<f64>,
    /// Seed of the weight initialisation and batch order (same seed, same weights).
    #[arg(long, default_value_t = 42)]
    pub seed: u64,
    /// auto: these networks (bpnn, cnn-lstm; the options above) are candidates too, scored on
    /// the same forward folds (one training per fold: slow); a chosen one is its own file.
    #[arg(long, value_delimiter = ',', value_name = "NETS")]
    pub with_networks: Vec<String>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

impl NnArgs {
    /// The options as the library takes them.
    pub fn options(&self) -> mtec_workflow::ops::thermal::NetworkOptions {
        mtec_workflow::ops::thermal::NetworkOptions {
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
            weight_decay: self.weight_decay,
            seed: self.seed,
            with_networks: self.with_networks.clone(),
        }
    }

    /// A network option given to a model that does not read it is refused (exit 2).
    pub fn refuse_unused(&self, model: &str) -> Result<(), crate::error::CliError> {
        self.options().refuse_unused(model)
    }
}

#[cfg(feature = "neural")]
impl NnArgs {
    /// The network and its training as `mtec_nn` takes them, for `--model` `model` (auto's
    /// networks: bpnn's options); candle then runs on one thread.
    pub fn fit_options(&self, model: &str) -> mtec_nn::thermal_log::NnFitOptions {
        single_candle_thread();
        self.options().fit_options(model)
    }
}

/// candle sizes its thread pool once, from the environment: one thread is ~8x faster for these
/// nets (`mtec_nn::threads`); set before the first candle op, while there is no other thread.
#[cfg(feature = "neural")]
pub(crate) fn single_candle_thread() {
    for (var, value) in mtec_nn::threads::single_thread_settings() {
        std::env::set_var(var, value);
    }
}
