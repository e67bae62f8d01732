//! On-line evaluation (`ThermalModel::stream`) against the batch `predict` it must reproduce: the
//! real fl-thermal record through a heat-input and a lagged MLR model, and an exp-ambient model
//! on data made from known parameters; the first-order lag against its analytic response; bad
//! readings refused without touching the state.

use mtec_io::Table;
use mtec_thermal::exp_ambient::ExpAmbientModel;
use mtec_thermal::heat_input::with_input;
use mtec_thermal::{Fit, HeatInput, Mlr, Predict, ThermalData, ThermalModel};
use std::path::Path;

fn fl_record(channel: &str) -> ThermalData {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/fl-thermal/train_1min.csv"
    );
    let table = Table::read(Path::new(path)).unwrap();
    let rpm = table.f64_column("spindle_rpm").unwrap();
    let d = ThermalData::from_table(&table, Some(channel), true).unwrap();
    with_input(&d, "spindle_rpm", &rpm).unwrap()
}

/// Runs `model` on line over every row of `data` (one experiment) and returns its predictions.
fn run_stream(model: &ThermalModel, data: &ThermalData) -> Vec<f64> {
    let mut s = model.stream().unwrap();
    let cols: Vec<Box<dyn Fn(usize) -> f64>> = s
        .inputs()
        .iter()
        .map(|name| -> Box<dyn Fn(usize) -> f64> {
            if name == "ambient_c" {
                let a = data.ambient_c.clone().unwrap();
                Box::new(move |i| a[i])
            } else {
                let j = data.sensor_names.iter().position(|s| s == name).unwrap();
                let v = data.sensor(j);
                Box::new(move |i| v[i])
            }
        })
        .collect();
    let mut readings = vec![0.0; cols.len()];
    (0..data.len())
        .map(|i| {
            for (r, c) in readings.iter_mut().zip(&cols) {
                *r = c(i);
            }
            let dt = if i == 0 {
                0.0
            } else {
                data.time_min[i] - data.time_min[i - 1]
            };
            s.step(&readings, dt).unwrap();
            let x = data.position_mm.as_ref().map_or(0.0, |p| p[i]);
            s.predict_um(x)
        })
        .collect()
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn heat_input_on_line_equals_batch_on_the_real_record() {
    let d = fl_record("ch5_um");
    let fitter = HeatInput {
        alphas: vec![1.5],
        banks: vec![vec![30.0, 90.0, 270.0]],
        ks: vec![1e-3],
        ambient_counts: vec![2],
        ambient_lags: vec![Some(60.0)],
        rest_factors: vec![3.0],
        ..Default::default()
    };
    let m = fitter.fit(&d).unwrap();
    assert!(m.rest_tau_factor == 3.0 && m.ambient_lag_min == Some(60.0));
    let batch = m.predict(&d).unwrap();
    let model = ThermalModel::HeatInput(m);
    let online = run_stream(&model, &d);
    let diff = max_abs_diff(&batch, &online);
    assert!(diff < 1e-9, "on line differs from batch by {diff} µm");
    // the drift is not trivially constant (the comparison means something)
    let span = batch.iter().cloned().fold(f64::MIN, f64::max)
        - batch.iter().cloned().fold(f64::MAX, f64::min);
    assert!(span > 5.0, "{span}");
}

#[test]
fn lagged_mlr_on_line_equals_batch_on_the_real_record() {
    let d = fl_record("ch1_um");
    let m = Mlr {
        sensors: vec!["t1_c".into(), "t5_c".into(), "t9_c".into()],
        lag: true,
    }
    .fit(&d)
    .unwrap();
    let batch = m.predict(&d).unwrap();
    let model = ThermalModel::Linear(m);
    let s = model.stream().unwrap();
    // spindle_rpm is not an input of this model
    assert_eq!(s.inputs(), ["t1_c", "t5_c", "t9_c"]);
    let diff = max_abs_diff(&batch, &run_stream(&model, &d));
    assert!(diff < 1e-9, "{diff}");
}

#[test]
fn exp_ambient_on_line_equals_batch() {
    // one experiment per ambient level, the rises of a known model; each time step at 3 positions
    let mut csv = String::from("experiment,time_min,up_c,nut_c,ambient_c,position_mm,ez_um\n");
    for (e, amb) in [15.0, 20.0, 30.0].iter().enumerate() {
        for step in 0..=24 {
            let t = step as f64 * 10.0;
            let up = 8.0 * (1.0 - (-t / 40.0).exp());
            let nut = 12.0 * (1.0 - (-t / 60.0).exp());
            for p in 0..=2 {
                let x = 200.0 * p as f64;
                let d = (0.05 - 0.001 * amb) * (1.0 - (-nut / 6.0).exp()) * x
                    + (8.0 + 0.2 * amb) * (1.0 - (-up / 4.0).exp());
                csv.push_str(&format!(
                    "{},{t},{},{},{amb},{x},{d}\n",
                    e + 1,
                    amb + up,
                    amb + nut
                ));
            }
        }
    }
    let t = Table::parse(Path::new("t.csv"), &csv).unwrap();
    let d = ThermalData::from_table(&t, Some("ez_um"), true).unwrap();
    let m = ExpAmbientModel::fit(&d, "up", "nut").unwrap();
    let batch = m.predict(&d).unwrap();
    let model = ThermalModel::ExpAmbient(Box::new(m));
    assert!(model.stream().unwrap().needs_position());
    // the stream starts again for each experiment (a cold start), as the batch rises do
    for exp in ["1", "2", "3"] {
        let rows: Vec<usize> = (0..d.len()).filter(|&i| d.experiment[i] == exp).collect();
        let sub = d.rows(&rows);
        let want: Vec<f64> = rows.iter().map(|&i| batch[i]).collect();
        let diff = max_abs_diff(&want, &run_stream(&model, &sub));
        assert!(diff < 1e-9, "experiment {exp}: {diff}");
    }
}

#[test]
fn a_lag_on_line_follows_the_analytic_step_response() {
    // L(t) = 10·(1 − e^(−t/20)) for a 10 K step through τ = 20 min, uneven steps
    let model = ThermalModel::Linear(mtec_thermal::LinearModel {
        method: mtec_thermal::model::LinearMethod::Mlr,
        features: vec![mtec_thermal::Feature::Lag {
            sensor: "a_c".into(),
            tau_min: 20.0,
        }],
        intercept_um: 0.0,
        coefficients: vec![1.0],
        std_errors: None,
        ridge: None,
        warnings: Vec::new(),
    });
    let mut s = model.stream().unwrap();
    assert_eq!(s.predict_um(0.0), 0.0, "nothing before the first reading");
    s.step(&[0.0], 0.0).unwrap();
    let mut t = 0.0;
    for dt in [0.25, 1.0, 3.0, 0.5, 7.0, 12.0, 30.0] {
        s.step(&[10.0], dt).unwrap();
        t += dt;
        let exact = 10.0 * (1.0 - (-t / 20.0f64).exp());
        assert!((s.predict_um(0.0) - exact).abs() < 1e-12, "t={t}");
    }
    // refusals leave the state alone
    let before = s.predict_um(0.0);
    assert!(s.step(&[10.0, 1.0], 1.0).is_err());
    assert!(s.step(&[f64::NAN], 1.0).is_err());
    assert!(s.step(&[10.0], -1.0).is_err());
    assert!(s.step(&[10.0], f64::INFINITY).is_err());
    assert_eq!(s.predict_um(0.0), before);
    // a rate feature cannot run on line
    let rate = ThermalModel::Linear(mtec_thermal::LinearModel {
        method: mtec_thermal::model::LinearMethod::Mlr,
        features: vec![mtec_thermal::Feature::Rate {
            sensor: "a_c".into(),
            window_min: 5.0,
        }],
        intercept_um: 0.0,
        coefficients: vec![1.0],
        std_errors: None,
        ridge: None,
        warnings: Vec::new(),
    });
    let err = rate.stream().unwrap_err().to_string();
    assert!(err.contains("on line"), "{err}");
}

/// The `heat` feature of the stepwise families (a switched lag of the powered spindle speed)
/// on line equals its batch values on the real record.
#[test]
fn heat_lag_feature_on_line_equals_batch_on_the_real_record() {
    let d = fl_record("ch2_um");
    let model = ThermalModel::Linear(mtec_thermal::LinearModel {
        method: mtec_thermal::model::LinearMethod::Dynamic,
        features: vec![
            mtec_thermal::Feature::HeatLag {
                input: "spindle_rpm".into(),
                alpha: 1.5,
                tau_min: 45.0,
                rest_tau_min: 135.0,
            },
            mtec_thermal::Feature::Lag {
                sensor: "t3_c".into(),
                tau_min: 80.0,
            },
            mtec_thermal::Feature::Temp {
                sensor: "t7_c".into(),
            },
        ],
        intercept_um: 1.0,
        coefficients: vec![4.0, 0.7, -0.3],
        std_errors: None,
        ridge: None,
        warnings: Vec::new(),
    });
    let batch = model.predict(&d).unwrap();
    let diff = max_abs_diff(&batch, &run_stream(&model, &d));
    assert!(diff < 1e-9, "{diff}");
}
