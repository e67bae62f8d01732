//! MLR, VIF and ridge against statsmodels and scikit-learn on the same data
//! (`tests/fixtures/collinear.csv`, outputs in `reference.json`, made by `gen_reference.py`
//! whose library versions are recorded in the JSON). Tolerance 1e-8, relative to the value's size.

use mtec_io::Table;
use mtec_thermal::linear::{ols, vif, vif_by_regressions, RidgeProblem};
use mtec_thermal::{Fit, Metrics, Mlr, Predict, ThermalData};
use serde_json::Value;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn load() -> (ThermalData, Value) {
    let t = Table::read(&fixture("collinear.csv")).unwrap();
    let d = ThermalData::from_table(&t, Some("drift_um"), true).unwrap();
    let r: Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("reference.json")).unwrap()).unwrap();
    (d, r)
}

fn close(a: f64, b: f64, what: &str) {
    let tol = 1e-8 * b.abs().max(1.0);
    assert!(
        (a - b).abs() <= tol,
        "{what}: mtec {a} vs reference {b} (diff {:e})",
        (a - b).abs()
    );
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn mlr_equals_statsmodels_ols() {
    let (d, r) = load();
    let y = d.target_um().unwrap();
    let fit = ols(&d.temps_c, y, &d.sensor_names).unwrap();
    let params = nums(&r["ols"]["params"]);
    let bse = nums(&r["ols"]["bse"]);
    close(fit.intercept, params[0], "intercept");
    for j in 0..5 {
        close(fit.coefficients[j], params[j + 1], "coefficient");
        close(fit.std_errors[j + 1], bse[j + 1], "standard error");
    }
    close(fit.std_errors[0], bse[0], "intercept standard error");
    let model = Mlr::default().fit(&d).unwrap();
    let m: Metrics = model.evaluate(&d).unwrap();
    close(m.r2.unwrap(), r["ols"]["rsquared"].as_f64().unwrap(), "R2");
    close(
        m.adj_r2.unwrap(),
        r["ols"]["rsquared_adj"].as_f64().unwrap(),
        "adjusted R2",
    );
    close(
        m.f_statistic.unwrap(),
        r["ols"]["fvalue"].as_f64().unwrap(),
        "F",
    );
    close(m.sse_um2, r["ols"]["ssr"].as_f64().unwrap(), "SSE");
    close(
        m.mse_um2.unwrap(),
        r["ols"]["mse_resid"].as_f64().unwrap(),
        "MSE",
    );
    let p = r["ols"]["f_pvalue"].as_f64().unwrap();
    assert!(
        (m.f_pvalue.unwrap() - p).abs() <= 1e-8 * p.max(1e-300) + 1e-300,
        "{} vs {p}",
        m.f_pvalue.unwrap()
    );
}

#[test]
fn vif_equals_statsmodels() {
    let (d, r) = load();
    let v = vif(&d.temps_c, &d.sensor_names).unwrap();
    let by_definition = vif_by_regressions(&d.temps_c, &d.sensor_names).unwrap();
    for ((a, c), b) in v.iter().zip(&by_definition).zip(nums(&r["vif"])) {
        close(*a, b, "VIF");
        close(*c, b, "VIF by auxiliary regressions");
    }
    assert!(v.iter().any(|x| *x > 10.0), "fixture must be collinear");
}

#[test]
fn ridge_equals_scikit_learn() {
    let (d, r) = load();
    let y = d.target_um().unwrap();
    let prob = RidgeProblem::new(&d.temps_c, y, &d.sensor_names).unwrap();
    for case in r["ridge"].as_array().unwrap() {
        let k = case["k"].as_f64().unwrap();
        let beta = prob.standardised(k).unwrap();
        for (a, b) in beta.iter().zip(nums(&case["standardised"])) {
            close(*a, b, &format!("standardised coefficient at k={k}"));
        }
        let (b0, b) = prob.destandardise(&beta);
        close(
            b0,
            case["intercept"].as_f64().unwrap(),
            &format!("intercept at k={k}"),
        );
        for (a, c) in b.iter().zip(nums(&case["coefficients"])) {
            close(*a, c, &format!("coefficient at k={k}"));
        }
    }
}
