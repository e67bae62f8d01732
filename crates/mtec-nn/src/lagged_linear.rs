//! A linear model with lagged temperature features, the non-neural reference of the rotary
//! comparison (issue #21): every target is a linear function of the sensors now and one and two
//! rows earlier, each multiplied by the angle's harmonics, so that a temperature can change
//! each harmonic of the error motion by its own amount.
//!
//! Model (the products are the design matrix's columns):
//!   y(c, t) = Σ_j Σ_h β_{j,h} · φ_j(t) · ψ_h(c)
//!   φ(t) = [1, T(t) − T̄, T(t − 1) − T̄, …, T(t − L) − T̄]   (sensors, centred on the training mean)
//!   ψ(c) = [1, the dataset's angle harmonics cos_k(c), sin_k(c)]
//! Rows before a sequence's start take its first row (the machine sat still before it: the
//! campaigns start after hours switched off).
//!
//! Solved in two least-squares stages (SVD both, no normal equations), which is the full least
//! squares of the product design when every measurement has the same complete revolution of
//! evenly spaced angles (the harmonics are then orthogonal over the angles, and the problem
//! splits by harmonic) and costs a 57 × 28 solve per harmonic instead of one 4104 × 196:
//! 1. per experiment and time, the targets over the angles → their coefficients on ψ;
//! 2. per coefficient, its course over the times → β on φ.
//!
//! Every sequence of an experiment is one angle over the same times (the rotary data of
//! [`crate::rotary::rotary_data`]). Fitted on rows of mtec-thermal's `ThermalData`
//! ([`LaggedLinear::fit_rows`]), it predicts every row of such data
//! ([`LaggedLinear::predict_targets`]).

use crate::dataset::ThermalDataset;
use crate::error::{NnError, Result};
use crate::thermal_fit::{model_inputs, training_data};
use mtec_thermal::ThermalData;
use nalgebra::{DMatrix, DVector};

/// A fitted lagged linear model.
#[derive(Debug, Clone)]
pub struct LaggedLinear {
    /// The sensor columns, then the angle's harmonic columns (the model's inputs).
    pub sensors: Vec<String>,
    pub inputs: Vec<String>,
    /// Leading features that are temperatures (the rest are angle harmonics).
    pub n_sensors: usize,
    /// How many earlier rows enter (1: T(t) and T(t − 1), …).
    pub lags: usize,
    /// Training mean of each sensor.
    pub mean: Vec<f64>,
    /// `coef[target]`: the β of every design column.
    pub coef: Vec<DVector<f64>>,
}

/// The design row of row `t` of a sequence `x` (its features per row).
pub(crate) fn design_row(
    x: &[Vec<f64>],
    t: usize,
    n_sensors: usize,
    lags: usize,
    mean: &[f64],
) -> Vec<f64> {
    let mut phi = vec![1.0];
    for l in 0..=lags {
        let r = &x[t.saturating_sub(l)];
        phi.extend((0..n_sensors).map(|k| r[k] - mean[k]));
    }
    let mut psi = vec![1.0];
    psi.extend_from_slice(&x[t][n_sensors..]);
    phi.iter()
        .flat_map(|a| psi.iter().map(move |b| a * b))
        .collect()
}

/// Least squares by SVD: the coefficients of `a` that best give each column of `y`.
pub(crate) fn lstsq(a: DMatrix<f64>, y: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    a.svd(true, true)
        .solve(y, 1e-10)
        .map_err(|e| NnError::Model(format!("least squares: {e}")))
}

/// A data error of mtec-thermal as this crate's.
pub(crate) fn thermal(e: mtec_thermal::ThermalError) -> NnError {
    NnError::Data(e.to_string())
}

/// Stage 1 of the fit (module docs), shared with [`crate::harmonic_net`]: per experiment and
/// time of `data` (features: `n_sensors` temperatures, then the angle harmonics), the lagged
/// sensors φ (centred on `mean`, with the leading 1) and the Fourier coefficients of every
/// target over the angles on ψ = [1, harmonics] (target k's coefficient h at k·nh + h).
pub(crate) fn fourier_stage(
    data: &ThermalDataset,
    n_sensors: usize,
    lags: usize,
    mean: &[f64],
) -> Result<FourierStage> {
    let nf = data.feature_names.len();
    let nt = data.target_names.len();
    let nh = 1 + nf - n_sensors;
    let (mut phis, mut coefs): (Vec<Vec<f64>>, Vec<Vec<f64>>) = (Vec::new(), Vec::new());
    for e in &data.experiments {
        let len = e.sequences.first().map_or(0, |s| s.len());
        if e.sequences.iter().any(|s| s.len() != len || s.warmup != 0) {
            return Err(NnError::Data(format!(
                "experiment {}: the lagged linear model needs every angle at the same times",
                e.id
            )));
        }
        let psi = DMatrix::from_fn(e.sequences.len(), nh, |i, h| {
            if h == 0 {
                1.0
            } else {
                e.sequences[i].features[0][n_sensors + h - 1]
            }
        });
        let svd = psi.svd(true, true);
        for t in 0..len {
            let y = DMatrix::from_fn(e.sequences.len(), nt, |i, k| e.sequences[i].targets[t][k]);
            let c = svd
                .solve(&y, 1e-10)
                .map_err(|x| NnError::Model(format!("least squares: {x}")))?;
            let x = &e.sequences[0].features;
            let phi = design_row(x, t, n_sensors, lags, mean);
            // design_row's ψ part is the first sequence's: keep every nh-th entry (ψ_0 = 1)
            phis.push(phi.iter().step_by(nh).copied().collect());
            coefs.push(c.iter().copied().collect()); // column-major: h fastest, then k
        }
    }
    Ok(FourierStage { phis, coefs })
}

/// What [`fourier_stage`] gives per experiment and time: `phis` the lagged sensors φ (with the
/// leading 1), `coefs` the Fourier coefficients of every target.
pub(crate) struct FourierStage {
    pub phis: Vec<Vec<f64>>,
    pub coefs: Vec<Vec<f64>>,
}

impl LaggedLinear {
    /// Fits on `rows` of `data` (every target of it), the inputs the `sensors` columns (the
    /// temperatures) and the angle's harmonic columns `harmonics`.
    pub fn fit_rows(
        data: &ThermalData,
        rows: &[usize],
        sensors: &[String],
        harmonics: &[String],
        lags: usize,
    ) -> Result<LaggedLinear> {
        let train =
            training_data(data, (sensors, harmonics), (false, false), rows, 0).map_err(thermal)?;
        let mut m = LaggedLinear::fit(&train, sensors.len(), lags)?;
        (m.sensors, m.inputs) = (sensors.to_vec(), harmonics.to_vec());
        Ok(m)
    }

    /// Predicted targets (rows × targets) of every row of `data`, each segment (experiment and
    /// angle) a time series from its first row.
    pub fn predict_targets(&self, data: &ThermalData) -> Result<Vec<Vec<f64>>> {
        let (_, x) = model_inputs(data, &self.sensors, &self.inputs, false).map_err(thermal)?;
        let mut out = Vec::with_capacity(x.len());
        for (a, b) in data.segments() {
            for t in 0..b - a {
                let d = DVector::from_vec(design_row(
                    &x[a..b],
                    t,
                    self.n_sensors,
                    self.lags,
                    &self.mean,
                ));
                out.push(self.coef.iter().map(|c| c.dot(&d)).collect());
            }
        }
        Ok(out)
    }

    /// Fits on every scored row of `data` (features: `n_sensors` temperatures, then the angle
    /// harmonics; module docs for the two stages).
    pub(crate) fn fit(
        data: &ThermalDataset,
        n_sensors: usize,
        lags: usize,
    ) -> Result<LaggedLinear> {
        let nf = data.feature_names.len();
        if n_sensors == 0 || n_sensors > nf {
            return Err(NnError::Config(format!(
                "{n_sensors} sensors of {nf} features"
            )));
        }
        let (xs, _) = data.rows();
        if xs.is_empty() {
            return Err(NnError::Data("no rows to fit".into()));
        }
        let mean: Vec<f64> = (0..n_sensors)
            .map(|k| xs.iter().map(|r| r[k]).sum::<f64>() / xs.len() as f64)
            .collect();
        let nt = data.target_names.len();
        let nh = 1 + nf - n_sensors;
        let np = 1 + n_sensors * (lags + 1);
        let FourierStage { phis, coefs } = fourier_stage(data, n_sensors, lags, &mean)?;
        let n = phis.len();
        if n <= np {
            return Err(NnError::Data(format!(
                "{n} measurements for {np} coefficients per harmonic: too few to fit"
            )));
        }
        // stage 2: every (harmonic, target) coefficient on φ
        let a = DMatrix::from_fn(n, np, |i, j| phis[i][j]);
        let y = DMatrix::from_fn(n, nh * nt, |i, j| coefs[i][j]);
        let beta = lstsq(a, &y)?; // np × (nh·nt)
                                  // back to the product design's order: column j·nh + h of target k
        let coef = (0..nt)
            .map(|k| DVector::from_fn(np * nh, |c, _| beta[(c / nh, k * nh + c % nh)]))
            .collect();
        Ok(LaggedLinear {
            sensors: data.feature_names[..n_sensors].to_vec(),
            inputs: data.feature_names[n_sensors..].to_vec(),
            n_sensors,
            lags,
            mean,
            coef,
        })
    }

    /// Predictions for every scored row of `data`, in [`ThermalDataset::rows`] order.
    #[cfg(test)]
    pub(crate) fn predict(&self, data: &ThermalDataset) -> Vec<Vec<f64>> {
        let mut out = Vec::new();
        for e in &data.experiments {
            for s in &e.sequences {
                for t in s.scored_rows() {
                    let d = DVector::from_vec(design_row(
                        &s.features,
                        t,
                        self.n_sensors,
                        self.lags,
                        &self.mean,
                    ));
                    out.push(self.coef.iter().map(|c| c.dot(&d)).collect());
                }
            }
        }
        out
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::dataset::{Experiment, Sequence};

    /// Three experiments of 12 angles × 10 times whose one target follows a lagged harmonic law
    /// of two sensors (a lag of one row, one harmonic): the data of the tests here and in
    /// [`crate::harmonic_net`].
    pub(crate) fn law_dataset() -> ThermalDataset {
        let law = |t: &[f64], tp: &[f64], c: f64| {
            let (cs, sn) = (c.to_radians().cos(), c.to_radians().sin());
            vec![
                0.5 + 2.0 * cs + (t[0] - 20.0) * 0.8 * sn + (tp[0] - 20.0) * (1.0 - 0.3 * cs)
                    - 0.2 * (t[1] - 20.0),
            ]
        };
        let experiments = (1..=3)
            .map(|e| Experiment {
                id: e,
                sequences: (0..12)
                    .map(|a| {
                        let c = a as f64 * 30.0;
                        let temps: Vec<[f64; 2]> = (0..10)
                            .map(|t| {
                                let t = t as f64;
                                [
                                    20.0 + (t * 0.7 * e as f64).sin() * 3.0,
                                    20.0 + 0.1 * t * e as f64,
                                ]
                            })
                            .collect();
                        Sequence {
                            features: temps
                                .iter()
                                .map(|x| {
                                    vec![x[0], x[1], c.to_radians().cos(), c.to_radians().sin()]
                                })
                                .collect(),
                            targets: (0..10)
                                .map(|t| law(&temps[t], &temps[t.saturating_sub(1)], c))
                                .collect(),
                            warmup: 0,
                        }
                    })
                    .collect(),
            })
            .collect();
        ThermalDataset {
            feature_names: ["T1_c", "T2_c", "cos_1(angle_deg)", "sin_1(angle_deg)"]
                .map(String::from)
                .to_vec(),
            target_names: vec!["EXC_um".into()],
            experiments,
        }
    }

    /// Data made by the model itself are fitted exactly, and a model without the lag cannot
    /// fit them.
    #[test]
    fn recovers_a_lagged_harmonic_law() {
        let data = law_dataset();
        let m = LaggedLinear::fit(&data, 2, 1).unwrap();
        let (_, y) = data.rows();
        let worst = m
            .predict(&data)
            .iter()
            .zip(&y)
            .map(|(p, y)| (p[0] - y[0]).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{worst}");
        let m0 = LaggedLinear::fit(&data, 2, 0).unwrap();
        let worst0 = m0
            .predict(&data)
            .iter()
            .zip(&y)
            .map(|(p, y)| (p[0] - y[0]).abs())
            .fold(0.0, f64::max);
        assert!(worst0 > 0.1, "{worst0}");
        assert!(LaggedLinear::fit(&data, 5, 1).is_err());
    }
}
