//! Forward (rolling-origin) validation, auto and the guard rails of issue 17: folds never see the
//! future (a planted change of the future must not move a fold's score, while leave-one-block-out
//! moves), blocks follow the duty cycle, auto never picks a candidate worse than no
//! compensation, the envelope flags made-up extrapolation, and every warning fires.

use mtec_thermal::auto::{one_standard_error, Auto, CandidateScore};
use mtec_thermal::guard::{envelope, outside_envelope};
use mtec_thermal::heat_input::{switched_lag, with_input};
use mtec_thermal::model::{cancellation_warning, Ridge, ThermalModel};
use mtec_thermal::stepwise::{Family, Stepwise};
use mtec_thermal::validate::{
    block_cv, duty_cycle_blocks, forward_cv, forward_folds, forward_folds_of, BlockSpec, ForwardCv,
};
use mtec_thermal::{Fit, Mlr, Predict, ThermalData};
use nalgebra::DMatrix;

/// A simulated duty cycle, 1-min samples: the spindle runs `speeds[b]` rpm in step b (each
/// `step_min` long; 0 = rest). Sensor `a_c` follows the spindle power through a 40-min lag, `b_c`
/// through a 200-min lag, `room_c` drifts slowly; the drift is 4·ΔL₁₂₀[a] + 2·Δb (a structure
/// with its own 120-min lag), plus a small deterministic ripple as noise.
fn machine(speeds: &[f64], step_min: f64) -> ThermalData {
    let n = (speeds.len() as f64 * step_min) as usize;
    let time: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let rpm: Vec<f64> = time
        .iter()
        .map(|t| speeds[((t / step_min) as usize).min(speeds.len() - 1)])
        .collect();
    let p: Vec<f64> = rpm.iter().map(|n| (n / 1000.0).powf(1.5)).collect();
    let d0 = ThermalData {
        experiment: vec!["1".into(); n],
        time_min: time.clone(),
        sensor_names: vec![],
        temps_c: DMatrix::zeros(n, 0),
        ambient_c: None,
        position_mm: None,
        target: None,
        more_targets: Vec::new(),
        sequence: None,
        source: None,
        lines: (2..n + 2).collect(),
    };
    let la = switched_lag(&d0, &p, &rpm, 40.0, 40.0);
    let lb = switched_lag(&d0, &p, &rpm, 200.0, 200.0);
    let a: Vec<f64> = la.iter().map(|v| 22.0 + 3.0 * v).collect();
    let b: Vec<f64> = lb.iter().map(|v| 21.0 + 2.0 * v).collect();
    let room: Vec<f64> = time
        .iter()
        .map(|t| 20.0 + 0.5 * (t / 900.0).sin())
        .collect();
    let la120 = switched_lag(&d0, &a, &rpm, 120.0, 120.0);
    let y: Vec<f64> = (0..n)
        .map(|i| 4.0 * (la120[i] - a[0]) + 2.0 * (b[i] - b[0]) + 0.05 * ((i as f64) * 0.7).sin())
        .collect();
    let d = ThermalData {
        sensor_names: vec!["a_c".into(), "b_c".into(), "room_c".into()],
        temps_c: DMatrix::from_fn(n, 3, |i, j| [a[i], b[i], room[i]][j]),
        target: Some(("drift_um".into(), y)),
        more_targets: Vec::new(),
        sequence: None,
        ..d0
    };
    with_input(&d, "spindle_rpm", &rpm).unwrap()
}

fn cycle() -> ThermalData {
    machine(
        &[0.0, 1000.0, 0.0, 2000.0, 0.0, 3000.0, 0.0, 1500.0, 0.0],
        120.0,
    )
}

fn spec() -> BlockSpec {
    BlockSpec {
        block_min: None,
        input: Some("spindle_rpm".into()),
    }
}

#[test]
fn blocks_follow_the_duty_cycle_steps_and_short_steps_join_the_next() {
    let d = cycle();
    let all: Vec<usize> = (0..d.len()).collect();
    let blocks = duty_cycle_blocks(&d, &all, &spec());
    assert_eq!(blocks.len(), 9, "one block per 120-min step");
    for (b, rows) in blocks.iter().enumerate() {
        assert_eq!(d.time_min[rows[0]], 120.0 * b as f64);
    }
    // a 10-min step is too short to score: it joins the following step
    let mut speeds = vec![0.0; 12];
    speeds.push(1000.0);
    speeds.extend([2000.0; 12]);
    speeds.extend([0.0; 12]);
    let short = machine(&speeds, 10.0);
    let all: Vec<usize> = (0..short.len()).collect();
    let starts: Vec<f64> = duty_cycle_blocks(&short, &all, &spec())
        .iter()
        .map(|b| short.time_min[b[0]])
        .collect();
    assert_eq!(starts, vec![0.0, 120.0, 250.0]);
    // forward folds: training strictly before the scored block, at least half of the rows
    let folds = forward_folds(&duty_cycle_blocks(
        &cycle(),
        &(0..960).collect::<Vec<_>>(),
        &spec(),
    ));
    assert_eq!(folds.len(), 4, "blocks 5-8 of 8 (the first 960 min)");
    for f in &folds {
        assert!(f.train.iter().max().unwrap() < f.test.iter().min().unwrap());
        assert!(f.train.len() >= 480);
    }
}

/// The same data with every row from `from` on replaced by a planted "future" that would help a
/// model that could see it: the target there is copied from the rows the fold scores.
fn plant_future(d: &ThermalData, from: usize, scored: &[usize]) -> ThermalData {
    let mut p = d.clone();
    let (_, y) = p.target.as_mut().unwrap();
    for (k, i) in (from..d.len()).enumerate() {
        y[i] = y[scored[k % scored.len()]] * 3.0 + 7.0;
        for j in 0..p.temps_c.ncols() - 1 {
            p.temps_c[(i, j)] = d.temps_c[(scored[k % scored.len()], j)] + 1.0;
        }
    }
    p
}

#[test]
fn a_planted_future_leak_does_not_move_a_forward_fold_but_moves_leave_one_block_out() {
    let d = cycle();
    let all: Vec<usize> = (0..d.len()).collect();
    let folds = forward_folds_of(&d, &all, &spec());
    let first = &folds[0];
    let end = *first.test.last().unwrap() + 1;
    let leaked = plant_future(&d, end, &first.test);
    let fitter = Stepwise {
        family: Family::Dynamic,
        sensors: vec![],
        input: Some("spindle_rpm".into()),
        max_sensors: 2,
        block_min: None,
    };
    let one = std::slice::from_ref(first);
    let clean = forward_cv(&fitter, &d, one).unwrap();
    let dirty = forward_cv(&fitter, &leaked, one).unwrap();
    assert_eq!(
        clean.folds[0].metrics.rmse_um, dirty.folds[0].metrics.rmse_um,
        "the fold's score must not depend on anything after its block"
    );
    // control: leave-one-block-out trains on the planted future and its score moves
    let all_blocks = duty_cycle_blocks(&d, &all, &spec());
    let b = all_blocks
        .iter()
        .position(|b| b[0] == first.test[0])
        .unwrap();
    let mlr = Mlr::default();
    let loo_clean = block_cv(&mlr, &d, &all_blocks).unwrap().per_block[b].rmse_um;
    let loo_dirty = block_cv(&mlr, &leaked, &all_blocks).unwrap().per_block[b].rmse_um;
    assert!(
        (loo_clean - loo_dirty).abs() > 1e-6,
        "{loo_clean} {loo_dirty}"
    );
}

#[test]
fn auto_recovers_the_dynamics_and_predicts_an_unseen_duty_cycle() {
    let d = cycle();
    let fit = Auto {
        max_sensors: 3,
        ..Default::default()
    }
    .fit_auto(&d, &(0..d.len()).collect::<Vec<_>>())
    .unwrap();
    assert!(fit.candidates.iter().filter(|c| c.chosen).count() == 1);
    assert!(fit.candidates.iter().any(|c| c.family == "dynamic"));
    // a kind of the registry that offers itself (pls.rs) is scored like auto's own families
    let pls = fit
        .candidates
        .iter()
        .find(|c| c.family == "pls")
        .expect("pls is a candidate");
    assert!(pls.forward.is_some() || pls.error.is_some());
    let chosen = fit.candidates.iter().find(|c| c.chosen).unwrap();
    assert!(chosen.eligible());
    // unseen: shorter steps at speeds never trained on
    let test = machine(&[0.0, 500.0, 2500.0, 0.0, 1200.0, 0.0, 2800.0, 0.0], 60.0);
    let pred = fit.model.predict(&test).unwrap();
    let y = test.target_um().unwrap();
    let e: Vec<f64> = y.iter().zip(&pred).map(|(a, b)| a - b).collect();
    let rmse = mtec_thermal::metrics::rms(&e);
    let raw = mtec_thermal::metrics::rms(y);
    assert!(rmse < 0.1 * raw, "{} {rmse} vs raw {raw}", fit.family);
}

fn score(family: &str, complexity: usize, folds: &[(f64, f64)]) -> CandidateScore {
    let fs: Vec<mtec_thermal::validate::FoldScore> = folds
        .iter()
        .map(|&(m, none)| mtec_thermal::validate::FoldScore {
            train_from_min: 0.0,
            train_to_min: 1.0,
            test_from_min: 1.0,
            test_to_min: 2.0,
            metrics: mtec_thermal::Metrics::new(&[m, -m], &[0.0, 0.0], 1),
            uncompensated_rmse_um: none,
        })
        .collect();
    let k = fs.len() as f64;
    let mean = fs.iter().map(|f| f.metrics.rmse_um).sum::<f64>() / k;
    let sd = (fs
        .iter()
        .map(|f| (f.metrics.rmse_um - mean).powi(2))
        .sum::<f64>()
        / (k - 1.0))
        .sqrt();
    let cv = ForwardCv {
        pooled_rmse_um: mean,
        pooled_max_abs_um: 0.0,
        rmse_std_error_um: sd / k.sqrt(),
        folds: fs,
    };
    CandidateScore {
        family: family.into(),
        complexity,
        worse_than_uncompensated: cv.folds_worse_than_uncompensated(),
        forward: Some(cv),
        error: None,
        chosen: false,
    }
}

#[test]
fn one_standard_error_prefers_the_simpler_and_never_a_model_worse_than_none() {
    // best mean 1.0 ± 0.5 (dynamic); ridge at 1.3 is within one SE and simpler
    let s = vec![
        score("mlr", 0, &[(3.0, 10.0), (3.0, 10.0)]),
        score("ridge", 1, &[(1.3, 10.0), (1.3, 10.0)]),
        score("dynamic", 4, &[(0.5, 10.0), (1.5, 10.0)]),
    ];
    assert_eq!(s[2].forward.as_ref().unwrap().rmse_std_error_um, 0.5);
    assert_eq!(one_standard_error(&s), Some(1));
    // the best mean, but worse than no compensation on one fold: never chosen
    let s = vec![
        score("ridge", 1, &[(2.0, 10.0), (2.0, 10.0)]),
        score("dynamic", 4, &[(0.2, 10.0), (1.2, 1.0)]),
    ];
    assert_eq!(s[1].worse_than_uncompensated, vec![2]);
    assert_eq!(one_standard_error(&s), Some(0));
    // nothing safe: nothing chosen
    let s = vec![score("mlr", 0, &[(5.0, 4.0), (1.0, 2.0)])];
    assert_eq!(one_standard_error(&s), None);
}

#[test]
fn auto_refuses_when_every_candidate_is_worse_than_no_compensation() {
    // the drift is unrelated to every input (and small): no candidate can beat leaving it alone
    let mut d = cycle();
    let n = d.len();
    let y: Vec<f64> = (0..n)
        .map(|i| 0.3 * ((i as f64) * 0.37).sin() * ((i as f64) * 0.011).cos())
        .collect();
    d.target = Some(("drift_um".into(), y));
    let e = Auto {
        max_sensors: 2,
        ..Default::default()
    }
    .fit_auto(&d, &(0..n).collect::<Vec<_>>())
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("no candidate is better than no compensation"),
        "{e}"
    );
}

#[test]
fn the_envelope_flags_made_up_extrapolation() {
    let d = cycle();
    let all: Vec<usize> = (0..d.len()).collect();
    let m = ThermalModel::Linear(Mlr::default().fit(&d).unwrap());
    let env = envelope(&m, &d, &all);
    assert!(env.iter().any(|r| r.column == "a_c"));
    assert!(outside_envelope(&env, &d).iter().all(|o| o.is_empty()));
    // the same machine run far beyond its training speed heats sensor a above its range
    let hot = machine(&[0.0, 6000.0, 0.0], 240.0);
    let out = outside_envelope(&env, &hot);
    assert!(out.iter().any(|o| o.contains(&"a_c".to_string())));
    assert!(out[0].is_empty(), "the first rows are still inside");
    // a dynamic model reads the spindle column too, and flags a speed never trained on
    let dynm = ThermalModel::Linear(
        Stepwise {
            family: Family::Dynamic,
            sensors: vec![],
            input: Some("spindle_rpm".into()),
            max_sensors: 1,
            block_min: None,
        }
        .fit(&d)
        .unwrap(),
    );
    let env = envelope(&dynm, &d, &all);
    if env.iter().any(|r| r.column == "spindle_rpm") {
        let out = outside_envelope(&env, &hot);
        assert!(
            out[240].contains(&"spindle_rpm".to_string()),
            "{:?}",
            out[240]
        );
    }
}

#[test]
fn cancelling_large_coefficients_warn() {
    let names = vec!["t1".to_string(), "t2".to_string(), "t3".to_string()];
    let w = cancellation_warning(&names, &[6.0, -5.5, 0.3]).unwrap();
    assert!(w.contains("t1 +6.0") && w.contains("t2 -5.5"), "{w}");
    assert!(
        cancellation_warning(&names, &[6.0, 0.5, 0.3]).is_none(),
        "one large term alone does not cancel"
    );
    // OLS on two nearly identical sensors gives them opposite huge coefficients
    let mut d = cycle();
    let n = d.len();
    let a: Vec<f64> = d.sensor(0);
    // the twin differs from a by a ripple that matches the drift's noise: OLS uses the tiny
    // difference, with huge opposite coefficients on a and its twin
    let twin: Vec<f64> = (0..n)
        .map(|i| a[i] + 0.001 * ((i as f64) * 0.7).sin())
        .collect();
    d = with_input(&d, "a2_c", &twin).unwrap();
    let m = Mlr {
        sensors: vec!["a_c".into(), "a2_c".into(), "b_c".into()],
        lag: false,
        ..Default::default()
    }
    .fit(&d)
    .unwrap();
    assert!(
        m.warnings.iter().any(|w| w.contains("cancel")),
        "{:?}",
        m.warnings
    );
}

#[test]
fn ridge_warns_when_the_forward_k_is_the_end_of_the_grid() {
    // the drift is noise unrelated to the sensors: the most shrinkage predicts best
    let mut d = cycle();
    let n = d.len();
    let y: Vec<f64> = (0..n)
        .map(|i| ((i as f64) * 0.9).sin() + 3.0 * ((i / 200) % 2) as f64)
        .collect();
    d.target = Some(("drift_um".into(), y));
    let m = Ridge {
        sensors: vec![],
        k: None,
        lag: false,
        blocks: spec(),
    }
    .fit(&d)
    .unwrap();
    assert_eq!(m.ridge.as_ref().unwrap().k, 1.0);
    assert!(
        m.warnings.iter().any(|w| w.contains("largest k")),
        "{:?}",
        m.warnings
    );
}

/// Pooled forward RMSE of OLS of y on [1, x columns] over the folds, solved by nalgebra's SVD
/// (independent of mtec's least squares).
fn svd_forward_rmse(
    cols: &[Vec<f64>],
    y: &[f64],
    folds: &[mtec_thermal::validate::ForwardFold],
) -> f64 {
    let (mut sse, mut n) = (0.0, 0usize);
    for f in folds {
        let x = DMatrix::from_fn(f.train.len(), cols.len() + 1, |r, j| {
            if j == 0 {
                1.0
            } else {
                cols[j - 1][f.train[r]]
            }
        });
        let yt = nalgebra::DVector::from_iterator(f.train.len(), f.train.iter().map(|&i| y[i]));
        let b = x.svd(true, true).solve(&yt, 1e-12).unwrap();
        for &i in &f.test {
            let p = b[0] + (0..cols.len()).map(|j| b[j + 1] * cols[j][i]).sum::<f64>();
            sse += (y[i] - p).powi(2);
            n += 1;
        }
    }
    (sse / n as f64).sqrt()
}

/// Training SSE of the same OLS on `rows`.
fn svd_training_sse(cols: &[Vec<f64>], y: &[f64], rows: &[usize]) -> f64 {
    let x = DMatrix::from_fn(rows.len(), cols.len() + 1, |r, j| {
        if j == 0 {
            1.0
        } else {
            cols[j - 1][rows[r]]
        }
    });
    let yt = nalgebra::DVector::from_iterator(rows.len(), rows.iter().map(|&i| y[i]));
    let b = x.svd(true, true).solve(&yt, 1e-12).unwrap();
    rows.iter()
        .map(|&i| {
            let p = b[0] + (0..cols.len()).map(|j| b[j + 1] * cols[j][i]).sum::<f64>();
            (y[i] - p).powi(2)
        })
        .sum()
}

#[test]
fn mlr_lag_time_constant_is_the_forward_choice_not_the_training_fit() {
    let d = cycle();
    let rows: Vec<usize> = (0..d.len()).collect();
    // b_c and room_c: the τ that fits the training rows best is not the one that predicts the
    // next blocks best (10.1 vs 7.7 min, 1000 vs 7.7 min)
    for sensor in ["b_c", "room_c"] {
        let fit = Mlr {
            sensors: vec![sensor.into()],
            lag: true,
            blocks: spec(),
        }
        .fit_rows(&d, &rows)
        .unwrap();
        let tau = match &fit.features[1] {
            mtec_thermal::Feature::Lag { tau_min, .. } => *tau_min,
            f => panic!("{f:?}"),
        };
        // the same folds (thinned to one row a minute: the record is already 1-min)
        let folds = forward_folds_of(&d, &rows, &spec());
        let y = d.target_um().unwrap();
        let rpm = mtec_thermal::validate::input_column(&d, "spindle_rpm").unwrap();
        let t = d.sensor(d.sensor_index(sensor).unwrap());
        // first-order lag with equal running and rest τ: heat_input's switched lag, not lag_filter
        let cols = |tau: f64| vec![t.clone(), switched_lag(&d, &t, &rpm, tau, tau)];
        let grid = mtec_thermal::features::tau_grid();
        let argmin = |score: &dyn Fn(f64) -> f64| {
            grid.iter()
                .copied()
                .min_by(|a, b| score(*a).total_cmp(&score(*b)))
                .unwrap()
        };
        let by_forward = argmin(&|tau| svd_forward_rmse(&cols(tau), y, &folds));
        let by_training = argmin(&|tau| svd_training_sse(&cols(tau), y, &rows));
        assert!(
            (by_forward - by_training).abs() > 1.0,
            "{sensor}: the data must tell the two choices apart"
        );
        assert!(
            (tau - by_forward).abs() < 1e-9,
            "{sensor}: fitted τ {tau}, forward choice {by_forward}, training fit {by_training}"
        );
        // ridge --lag takes its τ the same way (before its k)
        let ridge = Ridge {
            sensors: vec![sensor.into()],
            k: None,
            lag: true,
            blocks: spec(),
        }
        .fit_rows(&d, &rows)
        .unwrap();
        assert_eq!(ridge.features, fit.features, "{sensor}");
    }
}
