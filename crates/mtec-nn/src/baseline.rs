//! The BPNN on the training representation of [`crate::thermal_fit::NeuralFit`] (which is how
//! a caller trains one): `mtec thermal fit --model bpnn`.
//!
//! The BPNN sees only the features of the current row (no history), as in the source's
//! comparison. Its early-stopping rows are,
//! like the CNN-LSTM's, the tail of every training sequence or one whole training experiment
//! (block-wise, never random rows).

use crate::bpnn::Bpnn;
use crate::bpnn_train::{train_bpnn_with_validation_monitored, BpnnTrainConfig, TrainReport};
use crate::dataset::ThermalDataset;
use crate::error::{NnError, Result};
use crate::progress::Monitor;

/// Trains the BPNN baseline on the scored rows of `train` (current features → targets), holding
/// out the last `config.validation_fraction` of each sequence for early stopping, or the whole
/// experiment `config.validation_experiment`.
#[cfg(test)]
pub(crate) fn train_bpnn_baseline(
    train: &ThermalDataset,
    config: &BpnnTrainConfig,
) -> Result<(Bpnn, TrainReport)> {
    train_bpnn_baseline_monitored(train, config, &mut crate::progress::Quiet)
}

/// [`train_bpnn_baseline`] reporting every epoch to `monitor`, which may stop it.
pub(crate) fn train_bpnn_baseline_monitored(
    train: &ThermalDataset,
    config: &BpnnTrainConfig,
    monitor: &mut dyn Monitor,
) -> Result<(Bpnn, TrainReport)> {
    train.validate()?;
    crate::cnn_lstm::check_validation_experiment(train, config.validation_experiment)?;
    let (mut xt, mut yt, mut xv, mut yv) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (id, seq) in train
        .experiments
        .iter()
        .flat_map(|e| e.sequences.iter().map(move |s| (e.id, s)))
    {
        let split = ThermalDataset::validation_start(
            id,
            seq,
            config.validation_fraction,
            config.validation_experiment,
        );
        for t in seq.scored_rows() {
            let (x, y) = if t < split {
                (&mut xt, &mut yt)
            } else {
                (&mut xv, &mut yv)
            };
            x.push(seq.features[t].clone());
            y.push(seq.targets[t].clone());
        }
    }
    if xt.is_empty() {
        return Err(NnError::Data(
            "no training rows left after the validation split".into(),
        ));
    }
    let (mut net, report) =
        train_bpnn_with_validation_monitored(&xt, &yt, &xv, &yv, config, monitor)?;
    net.input_names = train.feature_names.clone();
    net.output_names = train.target_names.clone();
    Ok((net, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cnn_lstm::{train_cnn_lstm, CnnLstmConfig};
    use crate::dataset::{Experiment, Sequence};

    /// Three experiments of two sequences × 10 rows, 3 features, 1 target.
    fn data() -> ThermalDataset {
        let seq = |e: f64, s: f64| Sequence {
            features: (0..10)
                .map(|t| vec![e + 0.1 * t as f64, s, (t as f64).sin()])
                .collect(),
            targets: (0..10).map(|t| vec![e * s + 0.2 * t as f64]).collect(),
            warmup: 0,
        };
        ThermalDataset {
            feature_names: vec!["t1_c".into(), "t2_c".into(), "u".into()],
            target_names: vec!["exc_um".into()],
            experiments: (1..=3)
                .map(|id| Experiment {
                    id,
                    sequences: vec![seq(id as f64, 1.0), seq(id as f64, 2.0)],
                })
                .collect(),
        }
    }

    /// Early stopping on a whole experiment holds out exactly its 20 rows (not the tails:
    /// round(0.15 · 10) = 2 rows of each of the 6 sequences = 12), for both networks; an id
    /// outside the training experiments is refused.
    #[test]
    fn validation_on_a_whole_experiment() {
        let d = data();
        let bpnn = |v| BpnnTrainConfig {
            max_epochs: 3,
            validation_experiment: v,
            ..BpnnTrainConfig::default()
        };
        let rows = |n: &Bpnn| n.provenance["validation_rows"].as_u64().unwrap();
        assert_eq!(rows(&train_bpnn_baseline(&d, &bpnn(None)).unwrap().0), 12);
        assert_eq!(
            rows(&train_bpnn_baseline(&d, &bpnn(Some(2))).unwrap().0),
            20
        );
        assert!(train_bpnn_baseline(&d, &bpnn(Some(4))).is_err());
        let cnn = |v| CnnLstmConfig {
            max_epochs: 2,
            validation_experiment: v,
            architecture: crate::cnn_lstm::Architecture {
                window: 3,
                conv_channels: 2,
                kernel: 3,
                lstm_hidden: 4,
            },
            ..CnnLstmConfig::default()
        };
        let (_, r) = train_cnn_lstm(&d, &cnn(None)).unwrap();
        assert_eq!((r.train_windows, r.validation_windows), (48, 12));
        let (_, r) = train_cnn_lstm(&d, &cnn(Some(3))).unwrap();
        assert_eq!((r.train_windows, r.validation_windows), (40, 20));
        assert!(train_cnn_lstm(&d, &cnn(Some(7))).is_err());
        // a single training experiment cannot also be the validation one
        assert!(train_cnn_lstm(&d.select(&[1]).unwrap(), &cnn(Some(1))).is_err());
    }
}
