//! Methods against worked references: the lag filter against the analytic first-order response,
//! the exp-ambient fit against the parameters that generated its data, the refusals, and the
//! reading of a log without an `experiment` column.

use mtec_io::Table;
use mtec_thermal::exp_ambient::ExpAmbientModel;
use mtec_thermal::features::{lag_filter, rate};
use mtec_thermal::{Fit, LagSelect, ThermalData, ThermalError};
use std::path::Path;

fn parse(csv: &str, target: &str) -> ThermalData {
    let t = Table::parse(Path::new("t.csv"), csv).unwrap();
    ThermalData::from_table(&t, Some(target), true).unwrap()
}

/// A step of 10 K at t = 0 through τ = 20 min: L(t) = 10·(1 − e^(−t/20)) exactly at the samples
/// (the filter is the exact discretisation for inputs held over each interval).
#[test]
fn lag_filter_is_the_first_order_step_response() {
    let mut csv = String::from("time_min,a_c,y_um\n0,0,0\n");
    for i in 1..=100 {
        csv.push_str(&format!("{},{},0\n", i as f64 * 0.5, 10.0));
    }
    let d = parse(&csv, "y_um");
    let l = lag_filter(&d, &d.sensor(0), 20.0);
    for (i, v) in l.iter().enumerate().skip(1) {
        let t = d.time_min[i];
        let exact = 10.0 * (1.0 - (-t / 20.0).exp());
        assert!((v - exact).abs() < 1e-9, "t={t}: {v} vs {exact}");
    }
    // a ramp of 0.3 K/min has rate 0.3 once the window is full
    let mut csv = String::from("time_min,a_c,y_um\n");
    for i in 0..30 {
        csv.push_str(&format!("{i},{},0\n", 20.0 + 0.3 * i as f64));
    }
    let d = parse(&csv, "y_um");
    let r = rate(&d, &d.sensor(0), 5.0);
    for v in &r[5..] {
        assert!((v - 0.3).abs() < 1e-9, "{v}");
    }
}

/// Data made from known exp-ambient parameters (b_a, k_a linear in ambient and b_b, k_b
/// log-linear, so the quadratics in b_a, ln b_b, k_a, ln k_b that three levels allow contain them
/// exactly; the rises reach 2 b_b, so both parameters of each exponential are determined): the fit
/// recovers them within 3σ, reports no identifiability warning, and predicts a fourth ambient level.
#[test]
fn exp_ambient_recovers_generating_parameters() {
    let (ln_bb, ln_kb) = ([4f64.ln(), 0.25, 0.0], [6f64.ln(), 0.1, 0.0]);
    let truth = |amb: f64| {
        let u = (amb - 20.0) / 10.0;
        (
            12.0 + 3.0 * u,
            (ln_bb[0] + ln_bb[1] * u).exp(),
            0.05 - 0.01 * u,
            (ln_kb[0] + ln_kb[1] * u).exp(),
        )
    };
    let mut csv = String::from("experiment,time_min,up_c,nut_c,ambient_c,position_mm,ez_um\n");
    let mut noise = 0.0f64;
    for (e, amb) in [15.0, 20.0, 30.0, 25.0].iter().enumerate() {
        let (ba, bb, ka, kb) = truth(*amb);
        for step in 0..=24 {
            let t = step as f64 * 10.0;
            let up = 8.0 * (1.0 - (-t / 40.0).exp());
            let nut = 12.0 * (1.0 - (-t / 60.0).exp());
            for p in 0..=5 {
                let x = 100.0 * p as f64;
                // deterministic pseudo-noise of ±0.1 µm
                noise = (noise * 7.3 + 0.37).fract();
                let d = ka * (1.0 - (-nut / kb).exp()) * x
                    + ba * (1.0 - (-up / bb).exp())
                    + 0.2 * (noise - 0.5);
                csv.push_str(&format!(
                    "{},{t},{},{},{amb},{x},{d}\n",
                    e + 1,
                    amb + up,
                    amb + nut
                ));
            }
        }
    }
    let d = parse(&csv, "ez_um");
    let train: Vec<usize> = (0..d.len()).filter(|&i| d.experiment[i] != "4").collect();
    let test: Vec<usize> = (0..d.len()).filter(|&i| d.experiment[i] == "4").collect();
    let m = ExpAmbientModel::fit(&d.rows(&train), "up", "nut").unwrap();
    assert_eq!(m.degree, 2);
    let want = [[12.0, 3.0, 0.0], ln_bb, [0.05, -0.01, 0.0], ln_kb];
    for (got, (sd, w)) in [&m.b_a, &m.ln_b_b, &m.k_a, &m.ln_k_b].iter().zip(
        [&m.b_a_sd, &m.ln_b_b_sd, &m.k_a_sd, &m.ln_k_b_sd]
            .iter()
            .zip(want),
    ) {
        for c in 0..3 {
            assert!(
                (got[c] - w[c]).abs() <= 3.0 * sd[c] + 1e-9,
                "{got:?} ± {sd:?} vs {w:?}"
            );
        }
    }
    assert!(
        m.warnings.is_empty() && m.held_at_cap.is_empty(),
        "{:?}",
        m.warnings
    );
    // b_b(20 °C) = 4 °C, k_b(20 °C) = 6 °C
    let (bb, kb) = m.time_constants_c(20.0);
    assert!(
        (bb - 4.0).abs() < 0.1 && (kb - 6.0).abs() < 0.1,
        "{bb} {kb}"
    );
    let p = m.predict(&d).unwrap();
    let y = d.target_um().unwrap();
    let rmse =
        (test.iter().map(|&i| (p[i] - y[i]).powi(2)).sum::<f64>() / test.len() as f64).sqrt();
    assert!(rmse < 0.15, "{rmse}");
}

/// Drift that grows faster than the sensor's rise (the moving structure lags the sensor:
/// δ = s·ΔT^1.5 at the upper bearing, worked so that no positive b_b can bend the curve that way):
/// the fit keeps b_b > 0, holds it at its linear-limit cap, says that b_a and b_b are not
/// separately determined, and reports the slope b_a/b_b, which the data do fix.
#[test]
fn exp_ambient_warns_when_the_exponential_stays_linear() {
    let mut csv = String::from("experiment,time_min,up_c,nut_c,ambient_c,position_mm,ez_um\n");
    for (e, amb) in [15.0, 20.0, 30.0].iter().enumerate() {
        for step in 0..=24 {
            let t = step as f64 * 10.0;
            let up = 4.0 * (1.0 - (-t / 60.0).exp());
            let nut = 6.0 * (1.0 - (-t / 30.0).exp());
            for p in 0..=5 {
                let x = 100.0 * p as f64;
                // nut term saturating (k_b = 3 °C), up term convex
                let d = 0.02 * (1.0 - (-nut / 3.0).exp()) * x + 0.5 * up.powf(1.5);
                csv.push_str(&format!(
                    "{},{t},{},{},{amb},{x},{d}\n",
                    e + 1,
                    amb + up,
                    amb + nut
                ));
            }
        }
    }
    let m = ExpAmbientModel::fit(&parse(&csv, "ez_um"), "up", "nut").unwrap();
    for l in &m.identifiability {
        assert!(l.b_b_c > 0.0 && l.k_b_c > 0.0, "{l:?}");
        // held at 100 × the largest rise (4 °C at every level, to the sample's 1 − e^−4)
        assert!(
            (l.b_b_c / (100.0 * l.max_dt_up_c) - 1.0).abs() < 0.05,
            "{l:?}"
        );
        // the nut term stays determined (k_b finite, inside the data's range; not exactly 3 °C,
        // because the misfit of the convex zero-point term leaks into the slope: x is not centred)
        assert!(l.rho_nut > 0.2 && l.k_b_c < 10.0, "{l:?}");
    }
    assert_eq!(m.held_at_cap, vec!["b_b".to_string()]);
    assert_eq!(m.warnings.len(), 1, "{:?}", m.warnings);
    assert!(m.warnings[0].contains("b_a and b_b are not separately determined"));
}

#[test]
fn exp_ambient_refuses_undetermined_data() {
    let mut one_level =
        String::from("experiment,time_min,up_c,nut_c,ambient_c,position_mm,ez_um\n");
    let mut no_spread = one_level.clone();
    for e in 1..=2 {
        for t in 0..20 {
            let tf = t as f64;
            one_level.push_str(&format!(
                "{e},{t},{},{},20,{},{}\n",
                20.0 + tf * 0.2,
                20.0 + tf * 0.3,
                100 * (t % 3),
                tf
            ));
            no_spread.push_str(&format!(
                "{e},{t},{},{},{},250,{}\n",
                20.0 + tf * 0.2,
                20.0 + tf * 0.3,
                15 + 10 * e,
                tf
            ));
        }
    }
    let e = ExpAmbientModel::fit(&parse(&one_level, "ez_um"), "up", "nut").unwrap_err();
    assert!(
        matches!(&e, ThermalError::Undetermined(m) if m.contains("one level")),
        "{e}"
    );
    let e = ExpAmbientModel::fit(&parse(&no_spread, "ez_um"), "up", "nut").unwrap_err();
    assert!(
        matches!(&e, ThermalError::Undetermined(m) if m.contains("position spread")),
        "{e}"
    );
}

/// Drift made from a lagged sensor: lag-select finds that sensor and a time constant near the
/// true one, choosing by held-out blocks.
#[test]
fn lag_select_finds_the_lagged_sensor() {
    let mut csv = String::from("time_min,a_c,b_c,c_c,y_um\n");
    let (mut la, mut s) = (20.0f64, 0.0f64);
    for i in 0..960 {
        let t = i as f64;
        let on = (t / 120.0).floor() as i64 % 2 == 0;
        let a = 20.0
            + if on {
                6.0 * (1.0 - (-(t % 120.0) / 15.0).exp())
            } else {
                6.0 * (-(t % 120.0) / 15.0).exp()
            };
        // τ = 60 min lag of a drives the drift (exact discretisation, 1-min steps)
        la += (1.0 - (-1.0f64 / 60.0).exp()) * (a - la);
        s = (s * 9.7 + 0.13).fract();
        let b = 20.0 + 0.5 * (t / 200.0).sin() + 0.05 * s;
        let c = 20.0 + 0.01 * t;
        csv.push_str(&format!("{t},{a},{b},{c},{}\n", 3.0 * (la - 20.0)));
    }
    let d = parse(&csv, "y_um");
    let m = LagSelect {
        block_min: Some(240.0),
        ..Default::default()
    }
    .fit(&d)
    .unwrap();
    let lag = m.features.iter().find_map(|f| match f {
        mtec_thermal::Feature::Lag { sensor, tau_min } if sensor == "a_c" => Some(*tau_min),
        _ => None,
    });
    let tau = lag.expect("a lag of sensor a");
    assert!((40.0..=90.0).contains(&tau), "{tau}");
}

#[test]
fn a_log_without_experiment_column_is_one_experiment() {
    let d = parse(
        "time_min,spindle_rpm,a_c,ch1_um,ch2_um\n0,0,20,1,2\n1,100,21,2,3\n",
        "ch2",
    );
    assert_eq!(d.experiments(), vec!["1"]);
    assert_eq!(d.sensor_names, vec!["a_c"]);
    assert_eq!(d.target_um().unwrap(), &[2.0, 3.0]);
}

/// An exactly dependent sensor (c = a + b) has infinite VIF, and so do the sensors it depends on;
/// an independent one stays finite.
#[test]
fn vif_of_exactly_dependent_sensors_is_infinite() {
    let mut csv = String::from("time_min,a_c,b_c,c_c,d_c,y_um\n");
    for i in 0..30 {
        let t = i as f64;
        let (a, b, d) = (
            20.0 + (t / 7.0).sin(),
            21.0 + 0.1 * t,
            19.0 + (t / 3.0).cos(),
        );
        csv.push_str(&format!("{t},{a},{b},{},{d},{t}\n", a + b));
    }
    let data = parse(&csv, "y_um");
    let v = mtec_thermal::linear::vif(&data.temps_c, &data.sensor_names).unwrap();
    assert!(
        v[0].is_infinite() && v[1].is_infinite() && v[2].is_infinite(),
        "{v:?}"
    );
    assert!(v[3].is_finite() && v[3] < 10.0, "{v:?}");
}
