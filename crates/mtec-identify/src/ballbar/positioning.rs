//! `ECC`, the one error motion of a C axis no ballbar bar in an axial plane sees, from a rotary
//! positioning test (ISO 230-2:2014, which applies to rotary axes too) against a reference
//! instrument (an angle calibrator on the table, e.g. a self-centring rotary calibrator read
//! with an angular interferometer, or a polygon and autocollimator).
//!
//! The test gives, at m evenly spaced target angles of one revolution, the mean bidirectional
//! positional deviation `x̄_i = (x̄_i↑ + x̄_i↓)/2` (ISO 230-2 3.3.4) of n runs each way, the
//! deviation being the actual minus the commanded angle. For the reference-frame convention of
//! [`super`] (table pose `E(C)·Rz(C)`) a pure `ECC` turns the table to `C + ECC`, so
//! `x̄_i = ECC(C_i)` plus the instrument's own error. The instrument is zeroed at the first
//! target, so the mean of `ECC` is not measured; it is the angular set-up of the table's frame
//! (where the workpiece is turned on the table), which probing the workpiece measures.
//!
//! The function returned is the least-squares (SVD) Fourier series of the deviations,
//! harmonics 1..=N, mean left out.

use super::harmonics::check_full_revolution;
use super::BallbarError;
use mtec_model::ErrorFunction;
use nalgebra::{DMatrix, DVector};

/// The mean bidirectional positional deviation at each target (ISO 230-2 3.3.4), µrad, from
/// `up[j][i]` and `down[j][i]` (run j, target i).
pub fn mean_bidirectional_urad(
    up: &[Vec<f64>],
    down: &[Vec<f64>],
) -> Result<Vec<f64>, BallbarError> {
    let m = up.first().map(|r| r.len()).unwrap_or(0);
    if up.is_empty() || down.is_empty() || up.iter().chain(down).any(|r| r.len() != m) {
        return Err(BallbarError::Signal(
            "rotary positioning: every run needs one deviation per target, in both directions"
                .into(),
        ));
    }
    let mean =
        |runs: &[Vec<f64>], i: usize| runs.iter().map(|r| r[i]).sum::<f64>() / runs.len() as f64;
    Ok((0..m)
        .map(|i| 0.5 * (mean(up, i) + mean(down, i)))
        .collect())
}

/// `ECC` (µrad) as a Fourier series of harmonics 1..=`max_harmonic` fitted to the mean
/// bidirectional deviations at evenly spaced targets over one revolution (module docs).
pub fn ecc_from_positioning(
    targets_deg: &[f64],
    deviations_urad: &[f64],
    max_harmonic: usize,
) -> Result<ErrorFunction, BallbarError> {
    if targets_deg.len() != deviations_urad.len() {
        return Err(BallbarError::Signal(format!(
            "rotary positioning: {} targets but {} deviations",
            targets_deg.len(),
            deviations_urad.len()
        )));
    }
    check_full_revolution(targets_deg)?;
    let n = targets_deg.len();
    if max_harmonic == 0 || 2 * max_harmonic + 1 >= n {
        return Err(BallbarError::Signal(format!(
            "rotary positioning: {n} targets resolve harmonics up to {}, not {max_harmonic}",
            (n - 2) / 2
        )));
    }
    if deviations_urad.iter().any(|v| !v.is_finite()) {
        return Err(BallbarError::Signal(
            "rotary positioning: a deviation is not a finite number".into(),
        ));
    }
    // columns: 1, cos C, sin C, …, cos NC, sin NC
    let a = DMatrix::from_fn(n, 2 * max_harmonic + 1, |i, j| {
        let c = targets_deg[i].to_radians();
        let k = j.div_ceil(2) as f64;
        match j {
            0 => 1.0,
            _ if j % 2 == 1 => (k * c).cos(),
            _ => (k * c).sin(),
        }
    });
    let x = a
        .svd(true, true)
        .solve(&DVector::from_column_slice(deviations_urad), 0.0)
        .map_err(|e| BallbarError::Signal(e.to_string()))?;
    let cos = (0..max_harmonic).map(|k| x[2 * k + 1]).collect();
    let sin = (0..max_harmonic).map(|k| x[2 * k + 2]).collect();
    Ok(ErrorFunction::fourier(0.0, cos, sin))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked: deviations 5·cos C − 2·sin 3C + 7 (the 7 is the instrument's zero) at 24
    /// targets give ECC = 5·cos C − 2·sin 3C exactly, mean dropped.
    #[test]
    fn recovers_harmonics_and_drops_the_mean() {
        let t: Vec<f64> = (0..24).map(|i| i as f64 * 15.0).collect();
        let d: Vec<f64> = t
            .iter()
            .map(|c| {
                let r = c.to_radians();
                5.0 * r.cos() - 2.0 * (3.0 * r).sin() + 7.0
            })
            .collect();
        let f = ecc_from_positioning(&t, &d, 4).unwrap();
        for c in [0.0, 33.0, 190.0] {
            let r = f64::to_radians(c);
            let want = 5.0 * r.cos() - 2.0 * (3.0 * r).sin();
            assert!((f.value(c) - want).abs() < 1e-9, "{c}");
        }
        assert!(ecc_from_positioning(&t, &d, 12).is_err());
        assert!(ecc_from_positioning(&t[..12], &d[..12], 2).is_err());
    }

    #[test]
    fn bidirectional_mean_follows_iso_230_2() {
        let up = vec![vec![1.0, 2.0], vec![3.0, 4.0]];
        let down = vec![vec![0.0, 0.0], vec![1.0, 2.0]];
        assert_eq!(
            mean_bidirectional_urad(&up, &down).unwrap(),
            vec![1.25, 2.0]
        );
        assert!(mean_bidirectional_urad(&up, &[vec![1.0]]).is_err());
    }
}
