//! The acceptance checks on the virtual machine's scenarios (seed 1; `SEED=n` in the
//! environment reruns the first two on another seed — seeds 1–8 were looked at, see the report).

use mtec_io::Table;
use mtec_thermal::select::{select_sensors, SelectOptions};
use mtec_thermal::validate::rows_of_experiments;
use mtec_thermal::{ExpAmbient, Fit, Mlr, Predict, RidgeSelect, ThermalData};
use std::path::Path;

fn scenario_data(name: &str, seed: u64, target: &str) -> ThermalData {
    let out = mtec_sim::run_scenario(name, seed).expect("scenario runs");
    let csv = &out
        .files
        .iter()
        .find(|f| f.name == "thermal.csv")
        .unwrap()
        .contents;
    let t = Table::parse(Path::new(name), csv).unwrap();
    ThermalData::from_table(&t, Some(target), true).unwrap()
}

fn rmse_on(model: &impl Predict, data: &ThermalData, rows: &[usize]) -> f64 {
    let p = model.predict(data).unwrap();
    let y = data.target_um().unwrap();
    (rows.iter().map(|&i| (p[i] - y[i]).powi(2)).sum::<f64>() / rows.len() as f64).sqrt()
}

/// Ridge-trace selection on spindle-sensors keeps ≤ 4 sensors, predicts the unseen duty cycle
/// within 10 % of the full model, and the comparison table reproduces the source: ridge-selected
/// ≈ full (R²), better F; the simple-correlation model worse.
#[test]
fn spindle_sensors_ridge_selection() {
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let data = scenario_data("spindle-sensors", seed, "radial_um");
    let train = rows_of_experiments(&data, &["1".into()]).unwrap();
    let test = rows_of_experiments(&data, &["2".into()]).unwrap();
    let tr = data.rows(&train);
    let x = tr.temps_c.clone();
    let sel = select_sensors(
        &x,
        tr.target_um().unwrap(),
        &tr.sensor_names,
        SelectOptions::default(),
    )
    .unwrap();
    for s in &sel.steps {
        eprintln!("{} removed {:?} at k={:.4}", s.rule, s.removed, s.k);
    }
    for r in &sel.comparison {
        let m = &r.metrics;
        eprintln!(
            "{:32} {:?} R2={:.4} max={:.2} SSE={:.1} MSE={:.3} F={:.1}",
            r.model,
            r.sensors,
            m.r2.unwrap(),
            m.max_abs_residual_um,
            m.sse_um2,
            m.mse_um2.unwrap(),
            m.f_statistic.unwrap()
        );
    }
    let max_vif = sel
        .vif
        .iter()
        .map(|v| v.vif.unwrap_or(f64::INFINITY))
        .fold(0.0, f64::max);
    eprintln!("max VIF {max_vif:.1}, k = {}", sel.k);
    assert!(max_vif > 100.0, "sensors must be strongly collinear");
    assert!(sel.selected.len() <= 4, "{:?}", sel.selected);
    let full = Mlr::default().fit_rows(&data, &train).unwrap();
    let ridge = RidgeSelect::default().fit_rows(&data, &train).unwrap();
    let (rf, rr) = (rmse_on(&full, &data, &test), rmse_on(&ridge, &data, &test));
    eprintln!("test RMSE full {rf:.3} um, ridge-selected {rr:.3} um");
    assert!(rr <= 1.10 * rf, "ridge-selected {rr} vs full {rf}");
    let [f, r, c] = [
        &sel.comparison[0].metrics,
        &sel.comparison[1].metrics,
        &sel.comparison[2].metrics,
    ];
    assert!((f.r2.unwrap() - r.r2.unwrap()).abs() < 0.02);
    assert!(r.f_statistic.unwrap() > f.f_statistic.unwrap());
    assert!(c.sse_um2 > r.sse_um2 && c.r2.unwrap() < r.r2.unwrap());
}

/// Trained on three ambient levels, the exp-ambient model predicts the fourth within 2 µm RMS.
#[test]
fn feed_axis_ambient_predicts_unseen_ambient() {
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let data = scenario_data("feed-axis-ambient", seed, "ez_um");
    for held in ["3", "4", "2"] {
        let train_exps: Vec<String> = ["1", "2", "3", "4"]
            .iter()
            .filter(|e| **e != held)
            .map(|e| e.to_string())
            .collect();
        let train = rows_of_experiments(&data, &train_exps).unwrap();
        let test = rows_of_experiments(&data, &[held.to_string()]).unwrap();
        let fitter = ExpAmbient {
            up_sensor: "up".into(),
            nut_sensor: "nut".into(),
        };
        let m = fitter.fit_rows(&data, &train).unwrap();
        let y = data.target_um().unwrap();
        let max_err = test.iter().map(|&i| y[i].abs()).fold(0.0, f64::max);
        let rt = rmse_on(&m, &data, &test);
        eprintln!("held out exp {held}: train RMSE {:.3}, test RMSE {rt:.3} um (max |error| {max_err:.1} um); degree {}; {:?}", rmse_on(&m, &data, &train), m.degree, m.training_levels);
        if held == "3" {
            assert!(rt < 2.0, "{rt}");
        }
    }
}

/// Thermal dynamics: with the front-bearing sensor alone, a static MLR cannot follow the unseen
/// duty cycle (experiment 2, with a stop) because the housing and bed lag the bearing; the same
/// regression with a fitted first-order lag of the sensor can, to about the probe noise (0.3 µm).
#[test]
fn lag_feature_follows_an_unseen_duty_cycle() {
    let data = scenario_data("spindle-sensors", 1, "radial_um");
    let train = rows_of_experiments(&data, &["1".into()]).unwrap();
    let test = rows_of_experiments(&data, &["2".into()]).unwrap();
    let sensors = vec!["s1".to_string()];
    let fit = |lag| {
        Mlr {
            sensors: sensors.clone(),
            lag,
        }
        .fit_rows(&data, &train)
        .unwrap()
    };
    let (stat, dynamic) = (
        rmse_on(&fit(false), &data, &test),
        rmse_on(&fit(true), &data, &test),
    );
    eprintln!("one sensor, unseen duty cycle: static {stat:.3} um, with lag {dynamic:.3} um");
    assert!(
        dynamic < 0.5 && dynamic < 0.5 * stat,
        "static {stat}, lag {dynamic}"
    );
}
