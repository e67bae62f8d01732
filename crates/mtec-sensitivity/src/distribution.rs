//! Input distributions and the map from the unit interval to them (inverse CDF).
//!
//! Every sampler in this crate works in the unit hypercube and maps each coordinate through the
//! input's quantile function, as SALib's `scale_samples` does, so that a design drawn here and one
//! drawn by SALib mean the same thing.

use crate::SensitivityError;
use serde::{Deserialize, Serialize};

/// The distribution of one uncertain input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Distribution {
    /// Uniform on `[low, high]`.
    Uniform { low: f64, high: f64 },
    /// Normal with the given mean and standard deviation.
    Normal { mean: f64, std: f64 },
}

impl Distribution {
    /// Checks the parameters: finite, `low < high`, `std > 0`.
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Distribution::Uniform { low, high } => {
                if !(low.is_finite() && high.is_finite()) {
                    return Err(format!("uniform bounds [{low}, {high}] are not finite"));
                }
                if low >= high {
                    return Err(format!(
                        "uniform bounds [{low}, {high}]: low must be < high"
                    ));
                }
            }
            Distribution::Normal { mean, std } => {
                if !(mean.is_finite() && std.is_finite()) {
                    return Err(format!("normal(mean {mean}, std {std}) is not finite"));
                }
                if std <= 0.0 {
                    return Err(format!("normal std {std} must be > 0"));
                }
            }
        }
        Ok(())
    }

    /// The quantile (inverse CDF) at `u` in (0, 1).
    pub fn quantile(&self, u: f64) -> f64 {
        match *self {
            Distribution::Uniform { low, high } => low + u * (high - low),
            Distribution::Normal { mean, std } => mean + std * standard_normal_quantile(u),
        }
    }

    /// The variance of the distribution.
    pub fn variance(&self) -> f64 {
        match *self {
            Distribution::Uniform { low, high } => (high - low).powi(2) / 12.0,
            Distribution::Normal { std, .. } => std * std,
        }
    }

    /// The mean of the distribution.
    pub fn mean(&self) -> f64 {
        match *self {
            Distribution::Uniform { low, high } => 0.5 * (low + high),
            Distribution::Normal { mean, .. } => mean,
        }
    }
}

/// Standard normal CDF Φ(x) = erfc(−x/√2)/2.
pub fn standard_normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// Standard normal quantile Φ⁻¹(p): Acklam's rational approximation (relative error 1.15e-9)
/// refined by one Halley step on Φ(x) − p with an exact erfc, which brings it to full double
/// precision. Returns ∓∞ at p = 0 and 1 and NaN outside [0, 1].
pub fn standard_normal_quantile(p: f64) -> f64 {
    if !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    if p == 0.0 {
        return f64::NEG_INFINITY;
    }
    if p == 1.0 {
        return f64::INFINITY;
    }
    const A: [f64; 6] = [
        -3.969683028665376e+01,
        2.209460984245205e+02,
        -2.759285104469687e+02,
        1.383577518672690e+02,
        -3.066479806614716e+01,
        2.506628277459239e+00,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e+01,
        1.615858368580409e+02,
        -1.556989798598866e+02,
        6.680131188771972e+01,
        -1.328068155288572e+01,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-03,
        -3.223964580411365e-01,
        -2.400758277161838e+00,
        -2.549732539343734e+00,
        4.374664141464968e+00,
        2.938163982698783e+00,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-03,
        3.224671290700398e-01,
        2.445134137142996e+00,
        3.754408661907416e+00,
    ];
    const P_LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let mut x = if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p <= 1.0 - P_LOW {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    };
    // Halley refinement: e = Φ(x) − p, u = e·√(2π)·exp(x²/2), x ← x − u/(1 + x·u/2).
    // In the upper tail the residual is formed from the complement to keep its precision.
    for _ in 0..2 {
        let e = if x > 0.0 {
            (1.0 - p) - 0.5 * libm::erfc(x / std::f64::consts::SQRT_2)
        } else {
            standard_normal_cdf(x) - p
        };
        let u = e * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
        x -= u / (1.0 + 0.5 * x * u);
    }
    x
}

/// Checks a list of distributions and returns a [`SensitivityError::Problem`] naming the first bad one.
pub(crate) fn validate_all(
    names: &[String],
    dists: &[Distribution],
) -> Result<(), SensitivityError> {
    for (n, d) in names.iter().zip(dists) {
        d.validate()
            .map_err(|m| SensitivityError::Problem(format!("input `{n}`: {m}")))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantile_matches_published_values() {
        // Reference values: scipy.stats.norm.ppf 1.16 (SALib venv of bench/sensitivity.sh).
        let cases = [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.025, -1.959963984540054),
            (0.8413447460685429, 1.0),
            (0.9986501019683699, 3.0),
            (1e-10, -6.361340902404056),
            (1.0 - 1e-12, 7.0344869100478356),
        ];
        for (p, x) in cases {
            let got = standard_normal_quantile(p);
            assert!(
                (got - x).abs() < 1e-9 * (1.0 + x.abs()),
                "ppf({p}) = {got}, want {x}"
            );
        }
        for i in 1..1000 {
            let p = i as f64 / 1000.0;
            let x = standard_normal_quantile(p);
            assert!((standard_normal_cdf(x) - p).abs() < 1e-15);
        }
    }

    #[test]
    fn uniform_quantile_is_affine() {
        let d = Distribution::Uniform {
            low: -2.0,
            high: 6.0,
        };
        assert_eq!(d.quantile(0.25), 0.0);
        assert!((d.variance() - 64.0 / 12.0).abs() < 1e-12);
        assert!(Distribution::Normal {
            mean: 0.0,
            std: 0.0
        }
        .validate()
        .is_err());
    }
}
