//! `pls`: partial least squares regression of the drift on the temperature sensors (PLS1 by
//! NIPALS: Wold, Sjöström & Eriksson 2001, "PLS-regression: a basic tool of chemometrics",
//! Chemometrics and Intelligent Laboratory Systems 58, 109–130), the number of latent components
//! chosen by forward validation on the training rows with the one-standard-error rule.
//!
//! Sensors on a machine are collinear: neighbouring sensors follow the same heat. Least squares
//! then gives large coefficients of opposite sign that cancel on the training duty cycle and
//! break on another; PLS regresses on a few components that each combine the sensors in the
//! direction of their covariance with the drift, so collinear sensors share a component instead
//! of cancelling. The model is stored as a linear model in the sensors (`mtec.thermal-model/1`),
//! predicted and streamed like any other.
//!
//! This file is the whole kind (fitter, `Fit`, [`Kind`], `auto` candidate): with its line
//! in `registry!` it is a `--model` of `thermal fit` and `cv`, a model of Python's
//! `thermal_fit`, and a candidate of `--model auto`.

use crate::auto::Auto;
use crate::data::{target_rows, ThermalData};
use crate::error::ThermalError;
use crate::features::{design, temp_features};
use crate::fit::Fit;
use crate::kind::Kind;
use crate::linear::cancellation_warning;
use crate::linear_model::{LinearMethod, LinearModel};
use crate::model::ThermalModel;
use crate::options::{BlockSpec, FitOptions};
use crate::validate::{forward_cv, forward_folds_of};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The largest number of latent components tried.
pub const MAX_COMPONENTS: usize = 6;

/// PLS regression on the named sensors (all `_c` sensors when empty).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Pls {
    pub sensors: Vec<String>,
    /// Latent components; `None`: chosen by forward validation (1 … [`MAX_COMPONENTS`]).
    pub components: Option<usize>,
    /// Validation blocks of that choice.
    pub blocks: BlockSpec,
    /// As `auto`'s candidate: its sensor budget (`--max-sensors`). PLS weighs every sensor it
    /// is given, so with more sensors than that it refuses to fit, as a network does.
    #[serde(skip)]
    pub max_sensors: Option<usize>,
}

/// PLS1 coefficients β of the standardised design `z` (centred, unit-variance columns) for the
/// centred target `y` with `a` components: the NIPALS deflation
/// w = Eᵀf/‖Eᵀf‖, t = Ew, p = Eᵀt/tᵀt, q = fᵀt/tᵀt, E ← E − tpᵀ, f ← f − qt,
/// then β = W(PᵀW)⁻¹q (Wold et al. 2001, eqs. 4–11). `Undetermined` when a component finds no
/// covariance left (fewer informative directions than `a`).
pub fn pls1(z: &DMatrix<f64>, y: &DVector<f64>, a: usize) -> Result<DVector<f64>, ThermalError> {
    let p = z.ncols();
    let (mut e, mut f) = (z.clone(), y.clone());
    let (mut w, mut loadings, mut q) = (
        DMatrix::zeros(p, a),
        DMatrix::zeros(p, a),
        DVector::zeros(a),
    );
    let first = (z.transpose() * y).norm();
    for k in 0..a {
        let c = e.transpose() * &f;
        let norm = c.norm();
        if !(norm > 1e-10 * first) {
            return Err(ThermalError::Undetermined(format!(
                "pls: component {} finds no covariance left between the sensors and the drift (at most {k} components carry information)",
                k + 1
            )));
        }
        let wk = c / norm;
        let t = &e * &wk;
        let tt = t.dot(&t);
        let pk = e.transpose() * &t / tt;
        let qk = f.dot(&t) / tt;
        e -= &t * pk.transpose();
        f -= &t * qk;
        w.set_column(k, &wk);
        loadings.set_column(k, &pk);
        q[k] = qk;
    }
    // (PᵀW)⁻¹q by SVD: PᵀW is triangular and well conditioned when every component carries
    // covariance, but an SVD solve costs nothing at this size
    let r = (loadings.transpose() * &w)
        .svd(true, true)
        .solve(&q, 1e-12)
        .map_err(|e| ThermalError::Undetermined(format!("pls: {e}")))?;
    Ok(&w * r)
}

impl Pls {
    /// The model with `a` components fitted to `rows`.
    pub fn fit_components(
        &self,
        data: &ThermalData,
        rows: &[usize],
        a: usize,
    ) -> Result<LinearModel, ThermalError> {
        let y = target_rows(data, rows)?;
        let features = temp_features(data, &self.sensors)?;
        let x = design(data, &features)?.select_rows(rows.iter());
        let names: Vec<String> = features.iter().map(|f| f.name()).collect();
        let (n, p) = x.shape();
        if p == 0 || n < 3 {
            return Err(ThermalError::Invalid(format!(
                "pls needs temperature sensors and at least 3 rows (got {p} sensors, {n} rows)"
            )));
        }
        if a == 0 || a > p.min(n - 1) {
            return Err(ThermalError::Invalid(format!(
                "pls: {a} components with {p} sensors and {n} rows (at most {})",
                p.min(n - 1)
            )));
        }
        // standardise: z_ij = (x_ij − x̄_j)/s_j, y_i − ȳ (sample standard deviations)
        let y_mean = y.iter().sum::<f64>() / n as f64;
        let y_std = (y.iter().map(|v| (v - y_mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        let mut z = x.clone();
        let (mut mean, mut std) = (vec![0.0; p], vec![0.0; p]);
        for j in 0..p {
            let col = x.column(j);
            mean[j] = col.mean();
            std[j] =
                (col.iter().map(|v| (v - mean[j]).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
            if !(std[j] > 0.0) {
                return Err(ThermalError::Invalid(format!(
                    "pls: sensor `{}` is constant on the training rows",
                    names[j]
                )));
            }
            for i in 0..n {
                z[(i, j)] = (x[(i, j)] - mean[j]) / std[j];
            }
        }
        let yc = DVector::from_iterator(n, y.iter().map(|v| v - y_mean));
        let beta = pls1(&z, &yc, a)?;
        // back to the sensors' units: b_j = β_j/s_j, b₀ = ȳ − Σ b_j x̄_j
        let coefficients: Vec<f64> = (0..p).map(|j| beta[j] / std[j]).collect();
        let intercept_um = y_mean - (0..p).map(|j| coefficients[j] * mean[j]).sum::<f64>();
        let standardised: Vec<f64> = beta.iter().map(|b| b / y_std).collect();
        let mut warnings: Vec<String> = cancellation_warning(&names, &standardised)
            .into_iter()
            .collect();
        if self.components.is_none() && a == p {
            warnings.push(format!(
                "pls: forward validation chose all {p} components, which is least squares on these sensors"
            ));
        }
        Ok(LinearModel {
            method: LinearMethod::Pls,
            features,
            intercept_um,
            coefficients,
            std_errors: None,
            ridge: None,
            warnings,
        })
    }

    /// The number of components the forward folds of `rows` choose: the fewest whose mean fold
    /// RMSE is within one standard error of the best (Hastie, Tibshirani & Friedman, §7.10.1).
    pub fn choose_components(
        &self,
        data: &ThermalData,
        rows: &[usize],
    ) -> Result<usize, ThermalError> {
        let folds = forward_folds_of(data, rows, &self.blocks);
        if folds.is_empty() {
            return Err(ThermalError::Undetermined(
                "pls: choosing the number of components needs at least two blocks in the training rows (a longer record, experiments, or --block-min)".into(),
            ));
        }
        let p = temp_features(data, &self.sensors)?.len();
        let mut scores = Vec::new();
        for a in 1..=p.min(MAX_COMPONENTS) {
            let fixed = Pls {
                components: Some(a),
                ..self.clone()
            };
            match forward_cv(&fixed, data, &folds) {
                Ok(cv) => scores.push((a, cv.mean_rmse_um(), cv.rmse_std_error_um)),
                // a component with no covariance left ends the search
                Err(ThermalError::Undetermined(_)) if !scores.is_empty() => break,
                Err(e) => return Err(e),
            }
        }
        let &(_, best, se) = scores
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or_else(|| {
                ThermalError::Undetermined("pls: no component count could be scored".into())
            })?;
        Ok(scores
            .iter()
            .find(|s| s.1 <= best + se)
            .map(|s| s.0)
            .unwrap_or(1))
    }
}

impl Fit for Pls {
    type Model = LinearModel;
    fn fit_rows(&self, data: &ThermalData, rows: &[usize]) -> Result<LinearModel, ThermalError> {
        let n = temp_features(data, &self.sensors)?.len();
        if let Some(max) = self.max_sensors.filter(|&m| n > m) {
            return Err(ThermalError::Invalid(format!(
                "pls weighs all its {n} sensors, more than --max-sensors {max}: name at most that many with --sensors, or raise --max-sensors"
            )));
        }
        let a = match self.components {
            Some(a) => a,
            None => self.choose_components(data, rows)?,
        };
        self.fit_components(data, rows, a)
    }
}

impl Kind for Pls {
    const NAME: &'static str = "pls";
    const HELP: &'static str = "partial least squares on the sensors: collinear sensors share latent components (their number by forward validation)";
    fn from_options(o: &FitOptions, _: &ThermalData) -> Result<Self, ThermalError> {
        Ok(Pls {
            sensors: o.sensors.clone(),
            components: None,
            blocks: o.blocks(),
            max_sensors: None,
        })
    }
    fn fit_model(&self, d: &ThermalData, r: &[usize]) -> Result<ThermalModel, ThermalError> {
        Ok(ThermalModel::Linear(self.fit_rows(d, r)?))
    }
    /// Ranked with ridge (1): a static linear model in the sensors, shrunk in another way.
    fn auto_candidate(auto: &Auto, _: &ThermalData) -> Option<(usize, Self)> {
        Some((
            1,
            Pls {
                sensors: auto.sensors.clone(),
                components: None,
                blocks: BlockSpec {
                    block_min: auto.block_min,
                    input: Some(auto.input.clone()),
                },
                max_sensors: Some(auto.max_sensors),
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linear_model::Mlr;

    /// Three collinear sensors and a drift that depends on two of them, with a little noise.
    fn data() -> ThermalData {
        let n = 240;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 2.0).collect();
        let s1: Vec<f64> = t
            .iter()
            .map(|t| 20.0 + 5.0 * (1.0 - (-t / 60.0).exp()))
            .collect();
        let s2: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, t)| 20.0 + 4.0 * (1.0 - (-t / 90.0).exp()) + 0.02 * ((i * 7919) % 13) as f64)
            .collect();
        let s3: Vec<f64> = t
            .iter()
            .map(|t| 20.0 + 0.01 * t + 0.5 * (t / 40.0).sin())
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|i| {
                3.0 * (s1[i] - 20.0) - 1.5 * (s2[i] - 20.0) + 0.01 * ((i * 104_729) % 7) as f64
            })
            .collect();
        let mut csv = String::from("time_min,s1_c,s2_c,s3_c,dz_um\n");
        for i in 0..n {
            csv.push_str(&format!(
                "{},{},{},{},{}\n",
                t[i], s1[i], s2[i], s3[i], y[i]
            ));
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("log.csv");
        std::fs::write(&path, csv).unwrap();
        let table = mtec_io::Table::read(&path).unwrap();
        ThermalData::from_table(&table, Some("dz_um"), true).unwrap()
    }

    /// With as many components as sensors PLS spans the whole column space: it is least
    /// squares (Wold et al. 2001, §3.9), so it must equal the MLR fit.
    #[test]
    fn all_components_is_least_squares() {
        let d = data();
        let rows: Vec<usize> = (0..d.len()).collect();
        let pls = Pls::default().fit_components(&d, &rows, 3).unwrap();
        let mlr = Mlr::default().fit_rows(&d, &rows).unwrap();
        assert_eq!(pls.coefficients.len(), mlr.coefficients.len());
        for (a, b) in pls.coefficients.iter().zip(&mlr.coefficients) {
            assert!((a - b).abs() < 1e-8 * b.abs().max(1.0), "{a} vs {b}");
        }
        assert!((pls.intercept_um - mlr.intercept_um).abs() < 1e-6);
    }

    /// One component: the weight vector is the covariance of each standardised sensor with
    /// the drift, w ∝ Zᵀy (Wold et al. 2001, eq. 4), so the standardised coefficients are
    /// proportional to the sensors' correlations with the drift.
    #[test]
    fn one_component_follows_the_covariances() {
        let d = data();
        let rows: Vec<usize> = (0..d.len()).collect();
        let m = Pls::default().fit_components(&d, &rows, 1).unwrap();
        let y = d.target_um().unwrap();
        let n = y.len() as f64;
        let ym = y.iter().sum::<f64>() / n;
        let mut ratio = None;
        for (j, f) in m.features.iter().enumerate() {
            let x = f.values(&d).unwrap();
            let xm = x.iter().sum::<f64>() / n;
            let sx = (x.iter().map(|v| (v - xm).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            // Σ z_ij y_i with z the standardised column
            let cov: f64 = x.iter().zip(y).map(|(a, b)| (a - xm) / sx * (b - ym)).sum();
            let beta_std = m.coefficients[j] * sx;
            let r = beta_std / cov;
            match ratio {
                None => ratio = Some(r),
                Some(r0) => assert!((r - r0).abs() < 1e-9 * r0.abs(), "{r} vs {r0}"),
            }
        }
    }

    /// Too many components, a constant sensor and lags are refused with the reason.
    #[test]
    fn refusals() {
        let d = data();
        let rows: Vec<usize> = (0..d.len()).collect();
        assert!(Pls::default().fit_components(&d, &rows, 4).is_err());
        let pls = crate::registry::kind("pls").unwrap();
        assert!(FitOptions {
            lag: true,
            ..FitOptions::default()
        }
        .check(pls)
        .is_err());
    }

    #[test]
    fn as_autos_candidate_it_keeps_the_sensor_budget() {
        // PLS weighs every sensor it is given: with more than auto's --max-sensors it refuses,
        // as a network does (issue 17: at most `max_sensors` sensors on the machine)
        let d = data();
        let rows: Vec<usize> = (0..d.len()).collect();
        let offer = |max_sensors| {
            let auto = Auto {
                max_sensors,
                block_min: Some(60.0),
                ..Auto::default()
            };
            Pls::auto_candidate(&auto, &d).unwrap().1
        };
        let e = offer(2).fit_rows(&d, &rows).unwrap_err().to_string();
        assert!(
            e.contains("all its 3 sensors, more than --max-sensors 2"),
            "{e}"
        );
        let within = offer(3).fit_rows(&d, &rows).unwrap();
        assert_eq!(within.features.len(), 3);
        // named alone (thermal fit --model pls) it takes what it is given
        assert!(Pls::default().fit_components(&d, &rows, 2).is_ok());
    }
}
