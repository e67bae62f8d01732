//! CNN-LSTM against the BPNN baseline on rotary-axis thermal data of the `dbb-rotary` shape
//! (4 experiments × angles × time; T1..T9 and the angle in; EXC, EYC, EZC, EAC, EBC out), from the
//! analytic thermal model in `mtec_nn::synthetic` (first-order lags of a heat input, errors
//! linear in structurally lagged temperatures + harmonics of the angle). Trained on experiments
//! 1, 2, 4 and tested on experiment 3, as in the source.

use mtec_nn::cnn_lstm::Architecture;
use mtec_nn::synthetic::{rotary_thermal, RotaryThermalSpec};
use mtec_nn::{
    compare_on_split, train_cnn_lstm, BpnnTrainConfig, CnnLstm, CnnLstmConfig, SplitComparison,
};

fn small_config(epochs: usize) -> CnnLstmConfig {
    CnnLstmConfig {
        architecture: Architecture {
            window: 16,
            conv_channels: 8,
            kernel: 3,
            lstm_hidden: 16,
        },
        max_epochs: epochs,
        batch_size: 64,
        learning_rate: 5e-3,
        patience: 15,
        seed: 5,
        ..CnnLstmConfig::default()
    }
}

/// Every test starts here: one candle thread (`mtec_nn::threads`, set once before any training).
fn data() -> mtec_nn::ThermalDataset {
    if let Some((var, value)) = mtec_nn::threads::single_thread_setting() {
        std::env::set_var(var, value);
    }
    rotary_thermal(&RotaryThermalSpec {
        angles: 4,
        ..RotaryThermalSpec::default()
    })
}

#[test]
fn cnn_lstm_beats_the_bpnn_on_the_held_out_experiment() {
    let d = data();
    let bpnn_cfg = BpnnTrainConfig {
        hidden: 10,
        max_epochs: 50,
        seed: 5,
        ..BpnnTrainConfig::default()
    };
    let (_, _, cmp) = compare_on_split(&d, &[1, 2, 4], &[3], &small_config(60), &bpnn_cfg).unwrap();
    let (c, b) = (
        SplitComparison::overall_rmse(&cmp.cnn_lstm),
        SplitComparison::overall_rmse(&cmp.bpnn),
    );
    for (m, n) in cmp.cnn_lstm.iter().zip(&cmp.bpnn) {
        eprintln!(
            "{:9} CNN-LSTM rmse {:.3} mae {:.3} ratio {:.3} | BPNN rmse {:.3} mae {:.3} ratio {:.3} | range {:.2}",
            m.channel, m.rmse, m.mae, m.residual_ratio, n.rmse, n.mae, n.residual_ratio, m.range
        );
    }
    eprintln!(
        "overall RMSE: CNN-LSTM {c:.3}, BPNN {b:.3}; {:?}",
        cmp.cnn_lstm_training.stop_reason
    );
    assert!(c < b, "CNN-LSTM {c} must beat BPNN {b}");
    for m in &cmp.cnn_lstm {
        assert!(
            m.residual_ratio < 0.4,
            "{}: max residual {:.2} of range {:.2}",
            m.channel,
            m.max_abs_residual,
            m.range
        );
    }
}

#[test]
fn training_is_reproducible_and_the_model_file_round_trips() {
    let d = data();
    let (train, test) = d.split(&[1, 2, 4], &[3]).unwrap();
    let cfg = CnnLstmConfig {
        max_epochs: 3,
        ..small_config(3)
    };
    let (a, ra) = train_cnn_lstm(&train, &cfg).unwrap();
    let (b, _) = train_cnn_lstm(&train, &cfg).unwrap();
    assert!(
        a.weights == b.weights,
        "same seed must give identical weights"
    );
    assert_eq!(ra.epochs, 3);
    let other = train_cnn_lstm(
        &train,
        &CnnLstmConfig {
            seed: 6,
            ..cfg.clone()
        },
    )
    .unwrap()
    .0;
    assert!(a.weights != other.weights);

    // weights are f32 and round-trip exactly; the f64 normalisation to the last bit or so
    // (serde_json's default float parser), so predictions agree to far below a nanometre
    let back = CnnLstm::from_json(&a.to_json()).unwrap();
    assert!(back.weights == a.weights && back.architecture == a.architecture);
    for (p, q) in back.feature_offset.iter().zip(&a.feature_offset) {
        assert!((p - q).abs() <= 1e-12 * q.abs().max(1.0));
    }
    let (pb, pa) = (back.predict(&test).unwrap(), a.predict(&test).unwrap());
    assert_eq!(pb.len(), test.scored_rows());
    for (rb, ra) in pb.iter().zip(&pa) {
        for (u, v) in rb.iter().zip(ra) {
            assert!((u - v).abs() < 1e-4, "{u} vs {v}");
        }
    }

    let mut v: serde_json::Value = serde_json::from_str(&a.to_json()).unwrap();
    v["weights"]["fc.weight"]["shape"] = serde_json::json!([2, 2]);
    assert!(CnnLstm::from_json(&v.to_string()).is_err());
    v["format"] = "mtec.cnn-lstm/9".into();
    assert!(CnnLstm::from_json(&v.to_string()).is_err());
}

#[test]
fn bad_configurations_are_refused() {
    let d = data();
    let even = CnnLstmConfig {
        architecture: Architecture {
            kernel: 4,
            ..small_config(1).architecture
        },
        ..small_config(1)
    };
    assert!(train_cnn_lstm(&d, &even).is_err());
    let zero = CnnLstmConfig {
        batch_size: 0,
        ..small_config(1)
    };
    assert!(train_cnn_lstm(&d, &zero).is_err());
    for f in [0.0, 1.5, f64::NAN] {
        let decay = CnnLstmConfig {
            final_learning_rate_fraction: f,
            ..small_config(1)
        };
        let e = train_cnn_lstm(&d, &decay).unwrap_err();
        assert!(
            e.to_string().contains("final_learning_rate_fraction"),
            "{e}"
        );
    }
}
