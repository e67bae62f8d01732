//! Networks with the error motions' structure in their output (issue #21, the study of
//! docs/methods.md §10.4): instead of one motion value per (time, angle) row, the network
//! predicts the **angle-harmonic coefficients** of every motion at a time; the motion at angle c
//! is then Σ_h c_h·ψ_h(c), as in the lagged linear model ([`crate::lagged_linear`]), whose stage
//! 2 (a linear map φ → coefficients) the network replaces: a BPNN on the lagged sensors of the
//! time, a CNN-LSTM over the sensors of each experiment, or, as the control, least squares.
//!
//! - Inputs: φ(t) without its constant: T(t) − T̄, …, T(t − L) − T̄ (the trainer scales them).
//! - Outputs: the principal-component scores of the coefficient vectors over the training
//!   times (centred; the first `components` directions, within the numerical rank), so that
//!   the network learns the few directions in which the thermal state moves the motions and
//!   not the noise of every high harmonic (the trainer z-scores each output).
//! - The Fourier stage is the lagged linear model's (shared code), so the two differ only in
//!   the map from φ to the coefficients.

use crate::bpnn_train::{train_bpnn, BpnnTrainConfig};
use crate::cnn_lstm::{train_cnn_lstm, CnnLstm, CnnLstmConfig};
use crate::dataset::{Experiment, Sequence, ThermalDataset};
use crate::error::{NnError, Result};
use crate::lagged_linear::{design_row, fourier_stage, lstsq, thermal, FourierStage};
use crate::thermal_fit::{model_inputs, training_data};
use mtec_comp::bpnn::Bpnn;
use mtec_thermal::ThermalData;
use nalgebra::DMatrix;

/// The map from the lagged sensors to the principal-component scores.
#[derive(Debug, Clone)]
pub enum ScoreMap {
    /// The network on the lagged sensors of one time.
    Bpnn(Bpnn),
    /// The sequence network on the sensors over its window (the history is its own input).
    CnnLstm(CnnLstm),
    /// The control: least squares (SVD) on [1, φ], i.e. the lagged linear model restricted to
    /// the same principal directions.
    Linear(DMatrix<f64>),
    /// The least-squares map plus a network fitted to what it leaves (its residual scores).
    Residual {
        linear: DMatrix<f64>,
        net: Box<ScoreMap>,
    },
}

/// How stage 2 is fitted.
#[derive(Debug, Clone)]
pub enum Stage2 {
    Bpnn(BpnnTrainConfig),
    /// One sequence per training experiment: the sensors T(t) − T̄ of every time, the scores
    /// as targets (the window gives the history, so `lags` only shapes the Fourier stage's φ).
    CnnLstm(CnnLstmConfig),
    Linear,
    /// Least squares first, then the network (`Bpnn` or `CnnLstm`) on the residual scores: a
    /// hybrid whose network only adds what the linear map misses, so that a strong weight
    /// decay returns the linear model (the linear-plus-network hybrids of time-series
    /// forecasting, Zhang 2003, *Neurocomputing* 50).
    Residual(Box<Stage2>),
}

/// A fitted harmonic-output model.
#[derive(Debug, Clone)]
pub struct HarmonicNet {
    pub sensors: Vec<String>,
    pub inputs: Vec<String>,
    pub n_sensors: usize,
    pub lags: usize,
    /// Training mean of each sensor.
    pub mean: Vec<f64>,
    /// Mean coefficient vector (target k's harmonic h at k·nh + h).
    pub coef_mean: Vec<f64>,
    /// The kept principal directions, one row each (length nh·nt).
    pub directions: Vec<Vec<f64>>,
    pub net: ScoreMap,
    nh: usize,
    nt: usize,
}

/// Fits stage 2: the map from φ (`phis`, with its constant; `x` without it) to the scores `y`.
fn fit_score_map(
    stage2: &Stage2,
    train: &ThermalDataset,
    n_sensors: usize,
    (phis, x): (&[Vec<f64>], &[Vec<f64>]),
    y: &[Vec<f64>],
) -> Result<ScoreMap> {
    let (n, kept) = (y.len(), y.first().map_or(0, |r| r.len()));
    let least_squares = || {
        let a = DMatrix::from_fn(n, phis[0].len(), |i, j| phis[i][j]);
        let b = DMatrix::from_fn(n, kept, |i, j| y[i][j]);
        lstsq(a, &b)
    };
    Ok(match stage2 {
        Stage2::Bpnn(config) => ScoreMap::Bpnn(train_bpnn(x, y, config)?.0),
        Stage2::CnnLstm(config) => {
            // φ without its constant starts with T(t) − T̄: the first n_sensors entries
            let mut experiments = Vec::new();
            let mut i = 0;
            for e in &train.experiments {
                let len = e.sequences[0].len();
                experiments.push(Experiment {
                    id: e.id,
                    sequences: vec![Sequence {
                        features: (i..i + len).map(|r| x[r][..n_sensors].to_vec()).collect(),
                        targets: y[i..i + len].to_vec(),
                        warmup: 0,
                    }],
                });
                i += len;
            }
            if i != n {
                return Err(NnError::Data(format!(
                    "the experiments hold {i} rows, the scores {n}"
                )));
            }
            let scores = ThermalDataset {
                feature_names: train.feature_names[..n_sensors].to_vec(),
                target_names: (0..kept).map(|r| format!("score_{r}")).collect(),
                experiments,
            };
            ScoreMap::CnnLstm(train_cnn_lstm(&scores, config)?.0)
        }
        Stage2::Linear => ScoreMap::Linear(least_squares()?),
        Stage2::Residual(inner) => {
            if matches!(**inner, Stage2::Linear | Stage2::Residual(_)) {
                return Err(NnError::Model(
                    "a residual stage needs a network (BPNN or CNN-LSTM) after the linear map"
                        .into(),
                ));
            }
            let linear = least_squares()?;
            let residual: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    (0..kept)
                        .map(|r| y[i][r] - linear_score(&linear, r, &phis[i][1..]))
                        .collect()
                })
                .collect();
            let net = fit_score_map(inner, train, n_sensors, (phis, x), &residual)?;
            ScoreMap::Residual {
                linear,
                net: Box::new(net),
            }
        }
    })
}

/// Score `r` of the least-squares map β at φ without its constant: β₀ᵣ + Σⱼ φⱼ·βⱼ₊₁,ᵣ.
fn linear_score(beta: &DMatrix<f64>, r: usize, phi: &[f64]) -> f64 {
    beta[(0, r)]
        + phi
            .iter()
            .enumerate()
            .map(|(j, p)| p * beta[(j + 1, r)])
            .sum::<f64>()
}

impl HarmonicNet {
    /// Fits on `rows` of `data`: sensors `sensors` with `lags` earlier rows, angle harmonics
    /// `harmonics`, at most `components` principal directions, the map to them by `stage2`.
    pub fn fit_rows(
        data: &ThermalData,
        rows: &[usize],
        (sensors, harmonics): (&[String], &[String]),
        lags: usize,
        components: usize,
        stage2: &Stage2,
    ) -> Result<HarmonicNet> {
        let train =
            training_data(data, (sensors, harmonics), (false, false), rows, 0).map_err(thermal)?;
        HarmonicNet::fit(&train, sensors.len(), lags, components, stage2)
    }

    /// Fits on every row of `data` (features: `n_sensors` temperatures, then the angle
    /// harmonics).
    pub(crate) fn fit(
        train: &ThermalDataset,
        n_sensors: usize,
        lags: usize,
        components: usize,
        stage2: &Stage2,
    ) -> Result<HarmonicNet> {
        let (xs, _) = train.rows();
        if xs.is_empty() {
            return Err(NnError::Data("no rows to fit".into()));
        }
        let mean: Vec<f64> = (0..n_sensors)
            .map(|k| xs.iter().map(|r| r[k]).sum::<f64>() / xs.len() as f64)
            .collect();
        let FourierStage { phis, coefs } = fourier_stage(train, n_sensors, lags, &mean)?;
        let (n, m) = (coefs.len(), coefs[0].len());
        let coef_mean: Vec<f64> = (0..m)
            .map(|j| coefs.iter().map(|c| c[j]).sum::<f64>() / n as f64)
            .collect();
        let centred = DMatrix::from_fn(n, m, |i, j| coefs[i][j] - coef_mean[j]);
        let svd = centred.svd(false, true);
        let v_t = svd
            .v_t
            .ok_or_else(|| NnError::Model("SVD without V".into()))?;
        // the numerical rank, at most `components` (nalgebra sorts the values, largest first)
        let s_max = svd.singular_values.max();
        let kept = (svd.singular_values.iter())
            .take_while(|&&s| s > 1e-9 * s_max)
            .count()
            .min(components);
        let directions: Vec<Vec<f64>> = (0..kept)
            .map(|r| v_t.row(r).iter().copied().collect())
            .collect();
        let x: Vec<Vec<f64>> = phis.iter().map(|p| p[1..].to_vec()).collect();
        let y: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                directions
                    .iter()
                    .map(|d| {
                        d.iter()
                            .zip(&coefs[i])
                            .zip(&coef_mean)
                            .map(|((d, c), m)| d * (c - m))
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let net = fit_score_map(stage2, train, n_sensors, (&phis, &x), &y)?;
        let nh = 1 + train.feature_names.len() - n_sensors;
        Ok(HarmonicNet {
            sensors: train.feature_names[..n_sensors].to_vec(),
            inputs: train.feature_names[n_sensors..].to_vec(),
            n_sensors,
            lags,
            mean,
            coef_mean,
            directions,
            net,
            nh,
            nt: m / nh,
        })
    }

    /// Predicted targets (rows × targets) of every row of `data`.
    pub fn predict_targets(&self, data: &ThermalData) -> Result<Vec<Vec<f64>>> {
        let (_, x) = model_inputs(data, &self.sensors, &self.inputs, false).map_err(thermal)?;
        let mut out = Vec::with_capacity(x.len());
        for (a, b) in data.segments() {
            self.predict_sequence(&x[a..b], &mut out)?;
        }
        Ok(out)
    }

    /// The predictions of every row of one sequence `x` (features per row), appended to `out`.
    fn predict_sequence(&self, x: &[Vec<f64>], out: &mut Vec<Vec<f64>>) -> Result<()> {
        // the sequence network's scores of every time of the sequence, at once
        let sequence_net = match &self.net {
            ScoreMap::CnnLstm(net) => Some(net),
            ScoreMap::Residual { net, .. } => match &**net {
                ScoreMap::CnnLstm(net) => Some(net),
                _ => None,
            },
            _ => None,
        };
        let sequence_scores = match sequence_net {
            Some(net) => {
                let features = (x.iter())
                    .map(|r| (0..self.n_sensors).map(|k| r[k] - self.mean[k]).collect())
                    .collect();
                let one = ThermalDataset {
                    feature_names: net.feature_names.clone(),
                    target_names: net.target_names.clone(),
                    experiments: vec![Experiment {
                        id: 0,
                        sequences: vec![Sequence {
                            features,
                            targets: vec![vec![0.0; net.target_names.len()]; x.len()],
                            warmup: 0,
                        }],
                    }],
                };
                let scores = net.predict(&one)?;
                if scores.len() != x.len() {
                    return Err(NnError::Model(format!(
                        "the sequence network gave {} rows for {}",
                        scores.len(),
                        x.len()
                    )));
                }
                scores
            }
            None => Vec::new(),
        };
        let scores_at = |map: &ScoreMap, t: usize, phi: &[f64]| -> Result<Vec<f64>> {
            Ok(match map {
                ScoreMap::CnnLstm(_) => sequence_scores[t].clone(),
                ScoreMap::Bpnn(net) => net
                    .predict(phi)
                    .map_err(|e| NnError::Model(e.to_string()))?,
                ScoreMap::Linear(beta) => (0..beta.ncols())
                    .map(|r| linear_score(beta, r, phi))
                    .collect(),
                ScoreMap::Residual { .. } => {
                    return Err(NnError::Model("a residual stage inside another".into()))
                }
            })
        };
        for t in 0..x.len() {
            let d = design_row(x, t, self.n_sensors, self.lags, &self.mean);
            let phi: Vec<f64> = d.iter().step_by(self.nh).skip(1).copied().collect();
            let s = match &self.net {
                ScoreMap::Residual { linear, net } => {
                    let correction = scores_at(net, t, &phi)?;
                    if correction.len() != linear.ncols() {
                        return Err(NnError::Model(format!(
                            "the residual network gives {} scores, the linear map {}",
                            correction.len(),
                            linear.ncols()
                        )));
                    }
                    (0..linear.ncols())
                        .map(|r| linear_score(linear, r, &phi) + correction[r])
                        .collect()
                }
                map => scores_at(map, t, &phi)?,
            };
            if s.len() != self.directions.len() {
                return Err(NnError::Model(format!(
                    "stage 2 gives {} scores for {} directions",
                    s.len(),
                    self.directions.len()
                )));
            }
            let mut c = self.coef_mean.clone();
            for (d, s) in self.directions.iter().zip(&s) {
                for (c, d) in c.iter_mut().zip(d) {
                    *c += s * d;
                }
            }
            let psi: Vec<f64> = std::iter::once(1.0)
                .chain(x[t][self.n_sensors..].iter().copied())
                .collect();
            out.push(
                (0..self.nt)
                    .map(|k| (0..self.nh).map(|h| c[k * self.nh + h] * psi[h]).sum())
                    .collect(),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lagged_linear::{tests::law_dataset, LaggedLinear};

    /// The two stages are the lagged linear model's: with the linear map and every direction,
    /// the predictions are the lagged linear model's (to rounding); the network, trained on the
    /// same coefficients, fits the exact law closely, and one direction alone cannot.
    #[test]
    fn linear_stage_is_the_lagged_linear_model_and_the_network_fits_the_law() {
        let data = law_dataset();
        let predict = |m: &HarmonicNet| {
            let mut out = Vec::new();
            for e in &data.experiments {
                for s in &e.sequences {
                    m.predict_sequence(&s.features, &mut out).unwrap();
                }
            }
            out
        };
        let (_, y) = data.rows();
        let worst = |p: &[Vec<f64>], q: &[Vec<f64>]| {
            assert_eq!(p.len(), q.len());
            p.iter()
                .zip(q)
                .map(|(a, b)| (a[0] - b[0]).abs())
                .fold(0.0, f64::max)
        };
        let reference = LaggedLinear::fit(&data, 2, 1).unwrap().predict(&data);
        let linear = HarmonicNet::fit(&data, 2, 1, 100, &Stage2::Linear).unwrap();
        assert!(linear.directions.len() >= 2, "{}", linear.directions.len());
        assert!(worst(&predict(&linear), &reference) < 1e-9);
        let one = HarmonicNet::fit(&data, 2, 1, 1, &Stage2::Linear).unwrap();
        assert!(worst(&predict(&one), &y) > 0.1);
        let config = BpnnTrainConfig {
            hidden: 4,
            max_epochs: 200,
            validation_fraction: 0.0,
            weight_decay: 1e-4,
            seed: 3,
            ..BpnnTrainConfig::default()
        };
        let net = HarmonicNet::fit(&data, 2, 1, 100, &Stage2::Bpnn(config)).unwrap();
        // the law spans about ±6 µm
        let w = worst(&predict(&net), &y);
        assert!(w < 0.1, "{w}");
        // the sequence stage: one sequence per experiment, its window the history (the law's
        // lag of one row); against a model that always predicts the mean coefficients
        let mut c = CnnLstmConfig::default();
        // two sensors: a convolution of width 1 (the architecture needs kernel + 1 features)
        let a = &mut c.architecture;
        (a.window, a.kernel, a.conv_channels, a.lstm_hidden) = (3, 1, 8, 8);
        (c.max_epochs, c.validation_fraction, c.learning_rate) = (800, 0.0, 1e-2);
        let seq = HarmonicNet::fit(&data, 2, 1, 100, &Stage2::CnnLstm(c)).unwrap();
        let p = predict(&seq);
        let mean_only = HarmonicNet::fit(&data, 2, 1, 0, &Stage2::Linear).unwrap();
        let rms = |p: &[Vec<f64>]| {
            (p.iter()
                .zip(&y)
                .map(|(a, b)| (a[0] - b[0]).powi(2))
                .sum::<f64>()
                / y.len() as f64)
                .sqrt()
        };
        let (r, r0) = (rms(&p), rms(&predict(&mean_only)));
        eprintln!("cnn-lstm stage RMS {r} against {r0} for the mean coefficients");
        assert!(r < 0.2 * r0, "{r} vs {r0}");
    }

    /// The residual stage: on a law with a term the lagged sensors do not carry linearly
    /// ((T1 − 20)²·cos c), the network on what least squares leaves fits it far better than
    /// least squares alone; with a decay that leaves the network nothing, it is the linear
    /// model; and a residual stage without a network is refused.
    #[test]
    fn residual_stage_adds_what_the_linear_map_misses_and_decays_to_it() {
        let mut data = law_dataset();
        for e in &mut data.experiments {
            for s in &mut e.sequences {
                for (f, y) in s.features.iter().zip(s.targets.iter_mut()) {
                    y[0] += (f[0] - 20.0).powi(2) * f[2];
                }
            }
        }
        let (_, y) = data.rows();
        let rms = |m: &HarmonicNet| {
            let mut p = Vec::new();
            for e in &data.experiments {
                for s in &e.sequences {
                    m.predict_sequence(&s.features, &mut p).unwrap();
                }
            }
            assert_eq!(p.len(), y.len());
            let ss: f64 = p.iter().zip(&y).map(|(a, b)| (a[0] - b[0]).powi(2)).sum();
            ((ss / y.len() as f64).sqrt(), p)
        };
        let linear = HarmonicNet::fit(&data, 2, 1, 100, &Stage2::Linear).unwrap();
        let (r_lin, p_lin) = rms(&linear);
        let bpnn = |decay: f64| {
            Stage2::Residual(Box::new(Stage2::Bpnn(BpnnTrainConfig {
                hidden: 4,
                max_epochs: 200,
                validation_fraction: 0.0,
                weight_decay: decay,
                seed: 3,
                ..BpnnTrainConfig::default()
            })))
        };
        let hybrid = HarmonicNet::fit(&data, 2, 1, 100, &bpnn(1e-4)).unwrap();
        let (r_hyb, _) = rms(&hybrid);
        eprintln!("linear RMS {r_lin}, linear + BPNN on the residual {r_hyb}");
        assert!(
            r_lin > 1.0,
            "the term must be one least squares misses: {r_lin}"
        );
        assert!(r_hyb < 0.1 * r_lin, "{r_hyb} vs {r_lin}");
        // a decay of 1e6 on z-scored outputs leaves the network its bias: the mean residual
        // (zero for least squares with an intercept), so the hybrid is the linear model
        let damped = HarmonicNet::fit(&data, 2, 1, 100, &bpnn(1e6)).unwrap();
        let (r_damped, p_damped) = rms(&damped);
        let gap = (p_damped.iter().zip(&p_lin))
            .map(|(a, b)| (a[0] - b[0]).abs())
            .fold(0.0, f64::max);
        assert!(
            gap < 0.02 * r_lin,
            "{gap} vs {r_lin} (damped RMS {r_damped})"
        );
        let refused = HarmonicNet::fit(
            &data,
            2,
            1,
            100,
            &Stage2::Residual(Box::new(Stage2::Linear)),
        );
        assert!(refused.is_err());
    }
}
