//! Prediction metrics per output channel, the same for every model (CNN-LSTM, BPNN baseline).
//!
//! - RMSE = √(Σ r²/n), MAE = Σ|r|/n with r = predicted − measured.
//! - residual ratio = max|r| / (max y − min y) over the evaluated rows: the largest residual
//!   against the measured error *change* over the test (the source reports 7.4 µm residual
//!   against 19.3 µm change). The range is used rather than max|y| so that a constant offset of
//!   the error does not flatter the ratio.

use serde::Serialize;

/// Metrics of one channel.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ChannelMetrics {
    pub channel: String,
    pub n: usize,
    pub rmse: f64,
    pub mae: f64,
    pub max_abs_residual: f64,
    /// max y − min y of the measured values.
    pub range: f64,
    pub residual_ratio: f64,
}

/// Metrics per channel; `pred` and `meas` are rows × channels.
pub fn channel_metrics(
    names: &[String],
    pred: &[Vec<f64>],
    meas: &[Vec<f64>],
) -> Vec<ChannelMetrics> {
    names
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let r: Vec<f64> = pred.iter().zip(meas).map(|(p, m)| p[c] - m[c]).collect();
            let n = r.len().max(1) as f64;
            let lo = meas.iter().map(|m| m[c]).fold(f64::INFINITY, f64::min);
            let hi = meas.iter().map(|m| m[c]).fold(f64::NEG_INFINITY, f64::max);
            let max_abs = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let range = hi - lo;
            ChannelMetrics {
                channel: name.clone(),
                n: r.len(),
                rmse: (r.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
                mae: r.iter().map(|v| v.abs()).sum::<f64>() / n,
                max_abs_residual: max_abs,
                range,
                residual_ratio: if range > 0.0 {
                    max_abs / range
                } else {
                    f64::INFINITY
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_by_hand() {
        // measured 0, 2, 4; predicted 1, 2, 2 → r = 1, 0, −2
        let names = vec!["a".to_string()];
        let m = channel_metrics(
            &names,
            &[vec![1.0], vec![2.0], vec![2.0]],
            &[vec![0.0], vec![2.0], vec![4.0]],
        );
        assert!((m[0].rmse - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((m[0].mae - 1.0).abs() < 1e-15);
        assert_eq!(m[0].max_abs_residual, 2.0);
        assert_eq!(m[0].range, 4.0);
        assert_eq!(m[0].residual_ratio, 0.5);
    }
}
