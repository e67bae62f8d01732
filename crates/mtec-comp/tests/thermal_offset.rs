//! `thermal_offset`: the state now equals the batch prediction of `mtec-thermal` (a different
//! code path: whole-log filters) at every row of a log; the history each model family needs; the
//! setting data reproduce the model's error line at every position.

use mtec_comp::table::Axis;
use mtec_comp::thermal_offset::{
    self as to, History, LoadOptions, OffsetModel, OutsidePolicy, RunOptions, SettingOptions,
    UpdateOptions,
};
use mtec_io::Table;
use mtec_thermal::heat_input::HeatInputModel;
use mtec_thermal::{linear_model::LinearMethod, Split};
use mtec_thermal::{
    Feature, LinearModel, Metrics, ModelFile, Predict, ThermalData, ThermalModel, MODEL_FORMAT,
};

fn file(model: ThermalModel) -> String {
    serde_json::to_string(&ModelFile {
        format: MODEL_FORMAT.into(),
        target: "ez_um".into(),
        model,
        split: Split::default(),
        train_metrics: Metrics::new(&[0.0, 1.0, 2.0], &[0.0, 1.0, 2.0], 1),
        test_metrics: None,
        validation: None,
        envelope: vec![],
        candidates: vec![],
        warnings: vec![],
    })
    .unwrap()
}

/// e = 1.5 + 4·L₃₅[t1] − 2·t2 + 0.5·L₁₂₀[t2] (µm).
fn lag_model() -> ThermalModel {
    ThermalModel::Linear(LinearModel {
        method: LinearMethod::Mlr,
        features: vec![
            Feature::Lag {
                sensor: "t1_c".into(),
                tau_min: 35.0,
            },
            Feature::Temp {
                sensor: "t2_c".into(),
            },
            Feature::Lag {
                sensor: "t2_c".into(),
                tau_min: 120.0,
            },
        ],
        intercept_um: 1.5,
        coefficients: vec![4.0, -2.0, 0.5],
        std_errors: None,
        ridge: None,
        warnings: vec![],
    })
}

/// A warming day with uneven sampling: t1 steps and relaxes, t2 drifts.
fn log_csv() -> String {
    let mut s = String::from("time_min,t1_c,t2_c\n");
    let mut t = 0.0;
    for i in 0..300 {
        let t1 = 20.0 + if t < 300.0 { 6.0 } else { 2.0 } * (1.0 - (-t / 50.0_f64).exp());
        let t2 = 21.0 + 0.004 * t + 0.3 * (t / 90.0_f64).sin();
        s.push_str(&format!("{t},{t1:.4},{t2:.4}\n"));
        t += if i % 3 == 0 { 1.5 } else { 3.0 };
    }
    s
}

fn setup(model: ThermalModel, csv: &str) -> (tempfile::TempDir, OffsetModel, Table) {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m.json");
    std::fs::write(&m, file(model)).unwrap();
    let t = dir.path().join("log.csv");
    std::fs::write(&t, csv).unwrap();
    let om = OffsetModel::load(
        &m,
        LoadOptions {
            axis: Axis::Z,
            sign: None,
            training: Some(&t),
        },
    )
    .unwrap();
    let log = Table::read(&t).unwrap();
    (dir, om, log)
}

fn opts() -> UpdateOptions {
    UpdateOptions {
        origin_mm: 0.0,
        outside: OutsidePolicy::Refuse,
        max_correction_um: 500.0,
    }
}

#[test]
fn the_state_now_is_the_batch_prediction_at_every_row() {
    let csv = log_csv();
    let (dir, _, full) = setup(lag_model(), &csv);
    let batch = lag_model()
        .predict(&ThermalData::from_table(&full, None, false).unwrap())
        .unwrap();
    // "now" at several rows: the log cut there
    let lines: Vec<&str> = csv.lines().collect();
    for now in [1, 2, 17, 80, 239] {
        let cut = lines[..=now + 1].join("\n") + "\n";
        let p = dir.path().join("cut.csv");
        std::fs::write(&p, &cut).unwrap();
        let log = Table::read(&p).unwrap();
        let (_d, mut om, _) = setup(lag_model(), &csv);
        let run = to::run_log(
            &mut om,
            &log,
            RunOptions {
                starts_at_rest: true,
                zeroed_at_min: None,
            },
        )
        .unwrap();
        let u = to::offset_update(&run, &log, Axis::Z, None, opts()).unwrap();
        assert!(
            (u.drift_um - batch[now]).abs() < 1e-9,
            "row {now}: {} vs batch {}",
            u.drift_um,
            batch[now]
        );
        assert_eq!(u.correction_um, -u.drift_um);
    }
}

#[test]
fn history_each_family_needs() {
    assert_eq!(
        History::of(&lag_model()),
        History::Lags {
            slowest_tau_min: 120.0
        }
    );
    let heat = HeatInputModel {
        input: "spindle_rpm".into(),
        input_ref: 1000.0,
        alpha: 1.5,
        taus_min: vec![10.0, 60.0],
        rest_tau_factor: 3.0,
        ambient_sensors: vec!["t9_c".into()],
        k: 0.0,
        intercept_um: 0.0,
        heat_coefficients_um: vec![1.0, 2.0],
        ambient_coefficients_um_per_c: vec![0.5],
        ambient_lag_min: Some(100.0),
        ambient_lag_coefficients_um_per_c: vec![0.1],
        inner_cv_rmse_um: None,
        warnings: vec![],
    };
    // at rest the lags run 3× slower: 180 min
    assert_eq!(
        History::of(&ThermalModel::HeatInput(heat)),
        History::Lags {
            slowest_tau_min: 180.0
        }
    );
    let plain = ThermalModel::Linear(LinearModel {
        method: LinearMethod::Mlr,
        features: vec![Feature::Temp {
            sensor: "t1_c".into(),
        }],
        intercept_um: 0.0,
        coefficients: vec![1.0],
        std_errors: None,
        ridge: None,
        warnings: vec![],
    });
    assert_eq!(History::of(&plain), History::None);
    // a heat-lag feature needs the slower of its on and off time constants
    let heat_lag = ThermalModel::Linear(LinearModel {
        method: LinearMethod::Mlr,
        features: vec![Feature::HeatLag {
            input: "spindle_rpm".into(),
            alpha: 1.0,
            tau_min: 40.0,
            rest_tau_min: 90.0,
        }],
        intercept_um: 0.0,
        coefficients: vec![1.0],
        std_errors: None,
        ridge: None,
        warnings: vec![],
    });
    assert_eq!(
        History::of(&heat_lag),
        History::Lags {
            slowest_tau_min: 90.0
        }
    );
}

#[test]
fn a_log_too_short_for_the_filters_is_refused_at_its_first_row() {
    let csv = log_csv();
    let short: String = csv.lines().take(60).collect::<Vec<_>>().join("\n") + "\n";
    let (dir, mut om, _) = setup(lag_model(), &csv);
    let p = dir.path().join("short.csv");
    std::fs::write(&p, &short).unwrap();
    let log = Table::read(&p).unwrap();
    let e = to::run_log(&mut om, &log, RunOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("short.csv:2:"), "{msg}");
    assert!(
        msg.contains("tau = 120.0 min") && msg.contains("600 min"),
        "{msg}"
    );
    // the whole log (747 min) is long enough without a start at rest
    let (_d, mut om, full) = setup(lag_model(), &csv);
    assert!(to::run_log(&mut om, &full, RunOptions::default()).is_ok());
}

/// exp-ambient of degree 0 (b_a, b_b, k_a, k_b) from its JSON form.
fn exp_model() -> ThermalModel {
    serde_json::from_str(
        r#"{"kind":"exp-ambient","up_sensor":"up_c","nut_sensor":"nut_c","degree":0,
        "b_a":[-8.0],"ln_b_b":[2.0],"k_a":[0.03],"ln_k_b":[1.0],
        "b_a_sd":[0],"k_a_sd":[0],"ln_b_b_sd":[0],"ln_k_b_sd":[0],"training_levels":[]}"#,
    )
    .unwrap()
}

#[test]
fn setting_data_reproduce_the_error_line_at_every_position() {
    let csv = "time_min,up_c,nut_c,ambient_c\n0,20,20,21\n50,23,26,21\n";
    let (_d, mut om, log) = setup(exp_model(), csv);
    assert!(om.position_dependent());
    let run = to::run_log(
        &mut om,
        &log,
        RunOptions {
            starts_at_rest: true,
            zeroed_at_min: None,
        },
    )
    .unwrap();
    // δ = k·x + b, b = b_a(1 − e^(−ΔT_up/b_b)), k = k_a(1 − e^(−ΔT_nut/k_b))
    let b = -8.0 * (1.0 - (-3.0 / 2.0_f64.exp()).exp());
    let k = 0.03 * (1.0 - (-6.0 / 1.0_f64.exp()).exp());
    let origin = -600.0;
    let s = to::temp_comp_setting(
        &run,
        &log,
        Axis::Z,
        SettingOptions {
            update: UpdateOptions {
                origin_mm: origin,
                ..opts()
            },
            travel_mm: Some([-600.0, 0.0]),
            max_slope: 0.01,
        },
    )
    .unwrap();
    assert_eq!(s.p0_mm, origin);
    for p in [-600.0, -350.0, -20.0, 0.0] {
        // the control's ΔK = K0 + tanβ·(P − P0), in mm, against e(x) with x = P − origin
        let dk_um = (s.k0_mm + s.tan_beta * (p - s.p0_mm)) * 1e3;
        let e = k * (p - origin) + b;
        assert!((dk_um - e).abs() < 1e-9, "P = {p}: {dk_um} vs {e}");
        // the work offset at the same place moves by −e
        let u = to::offset_update(
            &run,
            &log,
            Axis::Z,
            Some(p),
            UpdateOptions {
                origin_mm: origin,
                ..opts()
            },
        )
        .unwrap();
        assert!((u.correction_um + e).abs() < 1e-9);
    }
}

#[test]
fn fade_scales_the_setting_data_and_refuse_is_located() {
    // ambient 31 °C, 1 °C above the training range [21, 30]: w = 1 − 1/2 (fade width 2 °C)
    let train = "time_min,up_c,nut_c,ambient_c\n0,20,20,21\n50,23,26,30\n";
    let (dir, mut om, _) = setup(exp_model(), train);
    let p = dir.path().join("hot.csv");
    std::fs::write(
        &p,
        "time_min,up_c,nut_c,ambient_c\n0,20,20,30\n50,23,26,31\n",
    )
    .unwrap();
    let log = Table::read(&p).unwrap();
    let run = to::run_log(
        &mut om,
        &log,
        RunOptions {
            starts_at_rest: true,
            zeroed_at_min: None,
        },
    )
    .unwrap();
    assert_eq!(run.now.weight, 0.5);
    let set = |outside| SettingOptions {
        update: UpdateOptions { outside, ..opts() },
        travel_mm: Some([-600.0, 0.0]),
        max_slope: 0.01,
    };
    let e = to::temp_comp_setting(&run, &log, Axis::Z, set(OutsidePolicy::Refuse)).unwrap_err();
    assert!(
        e.to_string().starts_with(&format!("{}:3:4:", p.display())),
        "{e}"
    );
    let s = to::temp_comp_setting(&run, &log, Axis::Z, set(OutsidePolicy::Fade)).unwrap();
    let full = run.now.drift;
    assert!((s.k0_mm - 0.5 * full.b_um * 1e-3).abs() < 1e-15);
    assert!((s.tan_beta - 0.5 * full.k_um_per_mm * 1e-3).abs() < 1e-18);
}
