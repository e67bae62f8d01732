//! One metrics type for every thermal model, on training or test rows.
//!
//! Definitions (residual e_i = y_i − ŷ_i, n rows, p predictors, ȳ the mean target):
//! SSE = Σe², SST = Σ(y−ȳ)², R² = 1 − SSE/SST, adjusted R² = 1 − (1−R²)(n−1)/(n−p−1),
//! RMSE = √(SSE/n), MAE = Σ|e|/n, MSE = SSE/(n−p−1) (the ANOVA residual mean square that the
//! source's comparison table and statsmodels' `mse_resid` use), F = (R²/p)/((1−R²)/(n−p−1)) with
//! its upper-tail p-value from F(p, n−p−1), residual ratio = max|e| / max|y| (the source's
//! "max residual over max error"), compensation rate = 1 − RMS(e)/RMS(y) (error left after
//! subtracting the prediction, relative to the uncompensated error).
//! F, its p-value and MSE are `None` when n ≤ p + 1; R² is `None` when the target is constant.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// Goodness of fit of a prediction against the measured drift (µm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    pub n: usize,
    pub predictors: usize,
    pub r2: Option<f64>,
    pub adj_r2: Option<f64>,
    pub rmse_um: f64,
    pub mae_um: f64,
    pub max_abs_residual_um: f64,
    pub sse_um2: f64,
    pub mse_um2: Option<f64>,
    pub f_statistic: Option<f64>,
    pub f_pvalue: Option<f64>,
    pub residual_ratio: Option<f64>,
    pub compensation_rate: Option<f64>,
}

impl Metrics {
    /// Metrics of predictions `pred_um` of the measured `y_um` by a model with `predictors` regressors.
    pub fn new(y_um: &[f64], pred_um: &[f64], predictors: usize) -> Metrics {
        let n = y_um.len();
        let nf = n as f64;
        let mean = y_um.iter().sum::<f64>() / nf;
        let res: Vec<f64> = y_um.iter().zip(pred_um).map(|(y, f)| y - f).collect();
        let sse: f64 = res.iter().map(|e| e * e).sum();
        let sst: f64 = y_um.iter().map(|y| (y - mean).powi(2)).sum();
        let max_abs_res = res.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
        let max_abs_y = y_um.iter().fold(0.0_f64, |m, y| m.max(y.abs()));
        let rms_y = (y_um.iter().map(|y| y * y).sum::<f64>() / nf).sqrt();
        let rmse = (sse / nf).sqrt();
        let r2 = (sst > 0.0).then(|| 1.0 - sse / sst);
        let dof = n as i64 - predictors as i64 - 1;
        let (adj_r2, mse, f, fp) = if dof > 0 {
            let d = dof as f64;
            let adj = r2.map(|r| 1.0 - (1.0 - r) * (nf - 1.0) / d);
            let f = match r2 {
                // F = (R²/p) / ((1−R²)/(n−p−1))  (ANOVA of the regression)
                Some(r) if predictors > 0 && r < 1.0 => {
                    Some((r / predictors as f64) / ((1.0 - r) / d))
                }
                _ => None,
            };
            let fp = f.and_then(|f| {
                FisherSnedecor::new(predictors as f64, d)
                    .ok()
                    .map(|dist| dist.sf(f.max(0.0)))
            });
            (adj, Some(sse / d), f, fp)
        } else {
            (None, None, None, None)
        };
        Metrics {
            n,
            predictors,
            r2,
            adj_r2,
            rmse_um: rmse,
            mae_um: res.iter().map(|e| e.abs()).sum::<f64>() / nf,
            max_abs_residual_um: max_abs_res,
            sse_um2: sse,
            mse_um2: mse,
            f_statistic: f,
            f_pvalue: fp,
            residual_ratio: (max_abs_y > 0.0).then(|| max_abs_res / max_abs_y),
            compensation_rate: (rms_y > 0.0).then(|| 1.0 - rmse / rms_y),
        }
    }
}

/// The metrics of one target of a model of several (a network of the five rotary error
/// motions): the same [`Metrics`], named.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TargetMetrics {
    pub target: String,
    #[serde(flatten)]
    pub metrics: Metrics,
}

impl TargetMetrics {
    /// Metrics of every target on the rows `rows`: `targets` the measured columns by name,
    /// `pred` one row of predictions (in `targets` order) per row of the data.
    pub fn on_rows(
        targets: &[(&str, &[f64])],
        pred: &[Vec<f64>],
        rows: &[usize],
        predictors: usize,
    ) -> Vec<TargetMetrics> {
        targets
            .iter()
            .enumerate()
            .map(|(c, (name, y))| {
                let yt: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
                let pt: Vec<f64> = rows.iter().map(|&i| pred[i][c]).collect();
                TargetMetrics {
                    target: name.to_string(),
                    metrics: Metrics::new(&yt, &pt, predictors),
                }
            })
            .collect()
    }
}

/// Root mean square of a slice.
pub fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worked by hand: y = [1,2,3,4,6], ŷ = [1.2,1.8,3.1,4.3,5.6], p = 1.
    /// e = [−0.2, 0.2, −0.1, −0.3, 0.4]; SSE = 0.04+0.04+0.01+0.09+0.16 = 0.34;
    /// ȳ = 3.2, SST = 4.84+1.44+0.04+0.64+7.84 = 14.8; R² = 1 − 0.34/14.8;
    /// MSE = 0.34/3; F = (R²/1)/((1−R²)/3); max|e| = 0.4; residual ratio = 0.4/6.
    #[test]
    fn metrics_match_hand_worked_example() {
        let m = Metrics::new(&[1., 2., 3., 4., 6.], &[1.2, 1.8, 3.1, 4.3, 5.6], 1);
        let r2 = 1.0 - 0.34 / 14.8;
        assert!((m.sse_um2 - 0.34).abs() < 1e-12);
        assert!((m.r2.unwrap() - r2).abs() < 1e-12);
        assert!((m.adj_r2.unwrap() - (1.0 - (1.0 - r2) * 4.0 / 3.0)).abs() < 1e-12);
        assert!((m.mse_um2.unwrap() - 0.34 / 3.0).abs() < 1e-12);
        let f = r2 / ((1.0 - r2) / 3.0);
        assert!((m.f_statistic.unwrap() - f).abs() < 1e-9);
        assert!((m.max_abs_residual_um - 0.4).abs() < 1e-12);
        assert!((m.residual_ratio.unwrap() - 0.4 / 6.0).abs() < 1e-12);
        assert!((m.rmse_um - (0.34f64 / 5.0).sqrt()).abs() < 1e-12);
        assert!((m.mae_um - 1.2 / 5.0).abs() < 1e-12);
        let rms_y = (66.0f64 / 5.0).sqrt();
        assert!((m.compensation_rate.unwrap() - (1.0 - m.rmse_um / rms_y)).abs() < 1e-12);
        // F(1,3) upper tail at F: the F(1,d) tail equals the two-sided t(d) tail at √F.
        let p = m.f_pvalue.unwrap();
        assert!(p > 0.0 && p < 0.01, "{p}");
    }
}
