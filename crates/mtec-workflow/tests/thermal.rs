//! `ops::thermal` in-process on the simulated feed axis: the fit's numbers against the model
//! evaluated by hand from its own coefficients, the files it writes, and located bad input.

use mtec_thermal::features::Feature;
use mtec_thermal::model_file::SplitBy;
use mtec_thermal::{ModelFile, ThermalModel};
use mtec_workflow::ops::thermal as op;
use mtec_workflow::{Collect, Error};
use std::path::{Path, PathBuf};

fn feed_axis(dir: &Path) -> PathBuf {
    let out = mtec_sim::run_scenario("feed-axis-ambient", 1).unwrap();
    let p = dir.join("thermal.csv");
    std::fs::write(&p, &out.files[0].contents).unwrap();
    p
}

fn mlr_options(data: &Path, output: PathBuf) -> op::FitOptions {
    op::FitOptions {
        data: data.to_path_buf(),
        target: "ez_um".into(),
        model: "mlr".into(),
        fit: mtec_thermal::FitOptions {
            sensors: vec!["up".into(), "nut".into()],
            ..Default::default()
        },
        split: SplitBy::Experiments {
            train: vec!["1".into(), "2".into(), "4".into()],
            test: vec!["3".into()],
        },
        output,
    }
}

/// The columns of the log, by name, read without mtec's thermal code.
fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let j = header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(j).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn fit_and_predict_agree_with_the_model_evaluated_by_hand() {
    let dir = tempfile::tempdir().unwrap();
    let data = feed_axis(dir.path());
    let model = dir.path().join("z.json");
    let mut obs = Collect::default();
    let fit = op::fit(&mlr_options(&data, model.clone()), &mut obs).unwrap();

    // the file written is the outcome's model file, as `thermal fit` writes it
    let text = std::fs::read_to_string(&model).unwrap();
    assert_eq!(text, serde_json::to_string_pretty(&fit.file).unwrap());
    let back: ModelFile = serde_json::from_str(&text).unwrap();
    assert_eq!(back.split, fit.file.split);
    assert_eq!(obs.warnings, fit.warnings);
    assert!(fit
        .to_string()
        .ends_with(&format!("wrote {}\n", model.display())));

    // δ = b0 + b_up·T_up + b_nut·T_nut on experiment 3, by hand
    let ThermalModel::Linear(m) = &fit.file.model else {
        panic!("mlr fits a linear model")
    };
    let csv = std::fs::read_to_string(&data).unwrap();
    let exp = column(&csv, "experiment");
    let y = column(&csv, "ez_um");
    let temps: Vec<Vec<f64>> = m
        .features
        .iter()
        .map(|f| match f {
            Feature::Temp { sensor } => column(&csv, sensor),
            other => panic!("{other:?}"),
        })
        .collect();
    let pred: Vec<f64> = (0..y.len())
        .map(|i| {
            m.intercept_um
                + m.coefficients
                    .iter()
                    .zip(&temps)
                    .map(|(c, t)| c * t[i])
                    .sum::<f64>()
        })
        .collect();
    let test: Vec<usize> = (0..y.len()).filter(|&i| exp[i] == 3.0).collect();
    assert_eq!(fit.file.split.test_rows, test.len());
    assert_eq!(fit.file.split.train_rows, y.len() - test.len());
    let rmse =
        (test.iter().map(|&i| (y[i] - pred[i]).powi(2)).sum::<f64>() / test.len() as f64).sqrt();
    let got = fit.file.test_metrics.as_ref().unwrap().rmse_um;
    assert!((got - rmse).abs() < 1e-9 * rmse.max(1.0), "{got} vs {rmse}");

    // predict: the same drift per row, in the CSV `thermal predict` writes
    let out = dir.path().join("pred.csv");
    let p = op::predict(
        &op::PredictOptions {
            model: model.clone(),
            data: data.clone(),
            history: None,
            output: Some(out.clone()),
            readings: None,
        },
        &mut Collect::default(),
    )
    .unwrap();
    // without the `neural` feature the enum has this one variant
    #[allow(irrefutable_let_patterns)]
    let op::PredictOutcome::Regression(p) = p
    else {
        panic!("a regression model file")
    };
    assert_eq!(p.predictions.len(), pred.len());
    for (a, b) in p.predictions.iter().zip(&pred) {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    let written = std::fs::read_to_string(&out).unwrap();
    assert_eq!(written, p.csv);
    assert_eq!(
        written.lines().next().unwrap(),
        "experiment,time_min,predicted_um,measured_um,residual_um,uncertainty_um,outside_training_range"
    );
    assert_eq!(written.lines().count(), y.len() + 1);
    let v = serde_json::to_value(&p).unwrap();
    assert_eq!(v["format"], "mtec.thermal-prediction/1");
    assert_eq!(v["n"], y.len());
    assert!(v.get("csv").is_none() && v.get("metrics").is_some());
}

#[test]
fn forward_cv_outcome_is_the_cli_json() {
    let dir = tempfile::tempdir().unwrap();
    let data = feed_axis(dir.path());
    let o = op::cv(
        &op::CvOptions {
            data,
            target: "ez_um".into(),
            model: "ridge".into(),
            fit: Default::default(),
            loo: false,
        },
        &mut Collect::default(),
    )
    .unwrap();
    let v = serde_json::to_value(&o).unwrap();
    assert_eq!(v["format"], "mtec.thermal-cv/2");
    assert_eq!(v["protocol"], "forward");
    // the pooled RMSE is the fold RMSEs recombined by their row counts
    let folds = v["folds"].as_array().unwrap();
    assert!(!folds.is_empty());
    let (mut sse, mut n) = (0.0, 0.0);
    for f in folds {
        let (r, k) = (
            f["metrics"]["rmse_um"].as_f64().unwrap(),
            f["metrics"]["n"].as_f64().unwrap(),
        );
        sse += r * r * k;
        n += k;
    }
    let pooled = v["pooled_rmse_um"].as_f64().unwrap();
    assert!(((sse / n).sqrt() - pooled).abs() < 1e-9, "{pooled}");
    assert!(v["folds_worse_than_uncompensated"].is_array());
    assert!(o.to_string().starts_with("forward validation:"));
}

#[test]
fn bad_input_is_located_and_usage_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(
        &bad,
        "experiment,time_min,up_c,nut_c,ez_um\n1,0,20,20,0\n1,1,2x,20,0.1\n",
    )
    .unwrap();
    let e = op::fit(
        &mlr_options(&bad, dir.path().join("m.json")),
        &mut Collect::default(),
    )
    .unwrap_err();
    match &e {
        Error::Input(i) => assert!(i.to_string().contains("bad.csv:3:3"), "{i}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(e.exit_code(), 2);

    // an option the kind does not take, before any reading
    let mut o = mlr_options(&bad, dir.path().join("m.json"));
    o.fit.k = Some(0.1);
    match op::fit(&o, &mut Collect::default()).unwrap_err() {
        Error::Usage(m) => assert_eq!(
            m,
            "--k must be a number from 0 to 100 and goes with --model ridge"
        ),
        other => panic!("{other:?}"),
    }
    // the model file may not overwrite the data
    let o = mlr_options(&bad, bad.clone());
    assert!(matches!(
        op::fit(&o, &mut Collect::default()),
        Err(Error::Usage(_))
    ));
}
