//! CNN-LSTM against the BPNN baseline on rotary-axis thermal data of the `dbb-rotary` shape
//! (4 experiments × angles × time; T1..T9 and the angle in; EXC, EYC, EZC, EAC, EBC out), from the
//! analytic thermal model in `mtec_nn::synthetic` (first-order lags of a heat input, errors
//! linear in structurally lagged temperatures + harmonics of the angle). Trained on experiments
//! 1, 2, 4 and tested on experiment 3, as in the source: both networks through `NeuralFit`
//! (mtec-thermal's `Fit`/`Predict` on `ThermalData`), scored with mtec-thermal's `Metrics`.

use mtec_nn::synthetic::{rotary_thermal, RotaryThermalSpec};
use mtec_nn::thermal_fit::{target_metrics, Network, NeuralThermalModel, Training};
use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_nn::{CnnLstm, NeuralFit, Quiet};
use mtec_thermal::validate::rows_of_experiments;
use mtec_thermal::{Fit, Metrics, ThermalData};

/// The inputs: the nine sensors (every `_c` column), then the angle as cos and sin.
fn fit_of(options: NnFitOptions) -> NeuralFit {
    NeuralFit {
        options,
        sensors: vec![],
        inputs: vec!["cos_angle".into(), "sin_angle".into()],
    }
}

/// Conv1d 8×3, LSTM 16 over 16 steps, batch 64, step size 5e-3, seed 5.
fn small(epochs: usize) -> NeuralFit {
    let mut o = NnFitOptions::new(NnKind::CnnLstm);
    (o.window, o.conv_channels, o.lstm_hidden) = (Some(16), Some(8), Some(16));
    (o.epochs, o.batch_size, o.learning_rate) = (Some(epochs), Some(64), Some(5e-3));
    (o.patience, o.seed) = (Some(15), 5);
    fit_of(o)
}

/// Every test starts here: one candle thread (`mtec_nn::threads`, set once before any training).
fn data() -> ThermalData {
    for (var, value) in mtec_nn::threads::single_thread_settings() {
        std::env::set_var(var, value);
    }
    rotary_thermal(&RotaryThermalSpec {
        angles: 4,
        ..RotaryThermalSpec::default()
    })
}

fn rows(d: &ThermalData, ids: &[&str]) -> Vec<usize> {
    let ids: Vec<String> = ids.iter().map(|s| s.to_string()).collect();
    rows_of_experiments(d, &ids).unwrap()
}

/// RMSE over all channels together (√ of the mean of the squared per-channel RMSEs).
fn overall_rmse(m: &[(String, Metrics)]) -> f64 {
    (m.iter().map(|(_, m)| m.rmse_um.powi(2)).sum::<f64>() / m.len() as f64).sqrt()
}

/// max y − min y of every target of `d` (the measured change over the test).
fn ranges(d: &ThermalData) -> Vec<f64> {
    (d.targets().iter())
        .map(|(_, y)| {
            let hi = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            hi - y.iter().copied().fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn cnn_lstm_beats_the_bpnn_on_the_held_out_experiment() {
    let d = data();
    let (train, test) = (rows(&d, &["1", "2", "4"]), rows(&d, &["3"]));
    let mut bpnn = NnFitOptions::new(NnKind::Bpnn);
    (bpnn.hidden, bpnn.epochs, bpnn.seed) = (Some(10), Some(50), 5);
    let (cnn, training) = small(60)
        .fit_rows_monitored(&d, &train, &mut Quiet)
        .unwrap();
    let bpnn = fit_of(bpnn).fit_rows(&d, &train).unwrap();
    let t = d.rows(&test);
    let score =
        |m: &NeuralThermalModel| target_metrics(&t, &m.predict_targets(&t).unwrap(), 11).unwrap();
    let (cm, bm, range) = (score(&cnn), score(&bpnn), ranges(&t));
    let (c, b) = (overall_rmse(&cm), overall_rmse(&bm));
    for (((name, m), (_, n)), r) in cm.iter().zip(&bm).zip(&range) {
        eprintln!(
            "{name:9} CNN-LSTM rmse {:.3} mae {:.3} ratio {:.3} | BPNN rmse {:.3} mae {:.3} ratio {:.3} | range {r:.2}",
            m.rmse_um, m.mae_um, m.max_abs_residual_um / r, n.rmse_um, n.mae_um, n.max_abs_residual_um / r
        );
    }
    eprintln!(
        "overall RMSE: CNN-LSTM {c:.3}, BPNN {b:.3}; {:?}",
        training.stop_reason()
    );
    assert!(c < b, "CNN-LSTM {c} must beat BPNN {b}");
    // the largest residual below 40 % of each channel's measured change (max − min)
    for ((name, m), r) in cm.iter().zip(&range) {
        assert!(
            m.max_abs_residual_um < 0.4 * r,
            "{name}: max residual {:.2} of range {r:.2}",
            m.max_abs_residual_um,
        );
    }
}

#[test]
fn training_is_reproducible_and_the_model_file_round_trips() {
    let d = data();
    let (train, test) = (rows(&d, &["1", "2", "4"]), rows(&d, &["3"]));
    let weights = |m: &NeuralThermalModel| match &m.network {
        Network::CnnLstm(n) => n.weights.clone(),
        Network::Bpnn(_) => panic!("a CNN-LSTM"),
    };
    let (a, ra) = small(3).fit_rows_monitored(&d, &train, &mut Quiet).unwrap();
    let b = small(3).fit_rows(&d, &train).unwrap();
    assert!(
        weights(&a) == weights(&b),
        "same seed must give identical weights"
    );
    let Training::CnnLstm(ra) = ra else {
        panic!("a CNN-LSTM report")
    };
    assert_eq!(ra.epochs, 3);
    let mut other = small(3);
    other.options.seed = 6;
    assert!(weights(&a) != weights(&other.fit_rows(&d, &train).unwrap()));

    // weights are f32 and round-trip exactly; the f64 normalisation to the last bit or so
    // (serde_json's default float parser), so predictions agree to far below a nanometre
    let text = a.to_json(&d, serde_json::json!({}));
    let net = CnnLstm::from_json(&text).unwrap();
    let Network::CnnLstm(fitted) = &a.network else {
        unreachable!()
    };
    assert!(net.weights == fitted.weights && net.architecture == fitted.architecture);
    for (p, q) in net.feature_offset.iter().zip(&fitted.feature_offset) {
        assert!((p - q).abs() <= 1e-12 * q.abs().max(1.0));
    }
    let (back, _) = NeuralThermalModel::from_network(Network::CnnLstm(net)).unwrap();
    let t = d.rows(&test);
    let (pb, pa) = (
        back.predict_targets(&t).unwrap(),
        a.predict_targets(&t).unwrap(),
    );
    assert_eq!(pb.len(), test.len());
    for (rb, ra) in pb.iter().zip(&pa) {
        for (u, v) in rb.iter().zip(ra) {
            assert!((u - v).abs() < 1e-4, "{u} vs {v}");
        }
    }

    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["weights"]["fc.weight"]["shape"] = serde_json::json!([2, 2]);
    assert!(CnnLstm::from_json(&v.to_string()).is_err());
    v["format"] = "mtec.cnn-lstm/9".into();
    assert!(CnnLstm::from_json(&v.to_string()).is_err());
}

/// A batch size of 0 and a final step-size fraction outside (0, 1] are refused with the
/// option's name (an even kernel: `cnn_lstm`'s unit tests).
#[test]
fn bad_configurations_are_refused() {
    let d = data();
    let all: Vec<usize> = (0..d.len()).collect();
    let mut zero = small(1);
    zero.options.batch_size = Some(0);
    assert!(zero.fit_rows(&d, &all).is_err());
    for f in [0.0, 1.5, f64::NAN] {
        let mut decay = small(1);
        decay.options.final_lr_fraction = Some(f);
        let e = decay.fit_rows(&d, &all).unwrap_err();
        assert!(
            e.to_string().contains("final_learning_rate_fraction"),
            "{e}"
        );
    }
}
