//! Installation-error removal: subtract each mode signal's mean and first harmonic.
//!
//! `ΔR'(C) = ΔR − cosC·(1/π)∫ΔR cosC dC − sinC·(1/π)∫ΔR sinC dC − (1/2π)∫ΔR dC` over one
//! revolution. Why it works: an eccentric ball (set-up error), an offset tool cup, the location
//! errors of the axis (`EX0C`, `EY0C`, `EA0C`, `EB0C`) and drifts of the linear axes that hold the
//! tool all change a bar length by a constant plus a once-per-revolution term.
//!
//! The limit, which users must know: anything else that is constant or once-per-revolution in a
//! reading is removed too. A true first-harmonic error motion (e.g. a tilt `EBC` ∝ cos C) and a
//! uniform thermal growth (`EZC` constant in C) disappear from the result.
//!
//! A second, less obvious limit of the source layout: the inclined modes 3–5 have their bar turn
//! with the table, so they read `Re(e^{i(C+φ)}·z_H(C))` with
//! `z_H = (EXC + H·EBC) − i·(EYC − H·EAC)` (H = height of their tool cup): a component of `z_H`
//! turning at −2 (or +1) cycles per revolution becomes a first harmonic (or mean) of their
//! readings and is removed with the set-up error. Together with what modes 1–2 see, one family of
//! motions is unobservable whatever the solver: `EBC + i·EAC = s·e^{−2iC}`, `EXC = −h·EBC`,
//! `EYC = h·EAC` gives all-zero cleaned readings (test
//! `radial_tilt_wobble_at_minus_two_cycles_is_invisible`). The per-angle solve reports that
//! family as zero, so the identified motions are the true motions minus it: exactly the motions
//! whose model readings equal the cleaned readings. To compare a truth with this method, push the
//! truth through the same path ([`super::predicted_dl_um`], then this function, then the per-angle
//! solve). On `dbb-rotary` (random-phase 2nd–6th harmonics) the identified `EXC`/`EYC` differ from
//! the true motions with their own mean and first harmonic removed by ≈ 2 µm RMS and `EAC`/`EBC`
//! by ≈ 20 µrad RMS for this reason, while they match the truth taken through the same path to
//! the noise level (0.13 µm, 0.41 µrad). `EZC` is not affected.
//!
//! Discrete form: with N evenly spaced samples over a full revolution the integrals are the
//! rectangle-rule sums `(2/N)Σ ΔR cos C` etc., which are exact for trigonometric polynomials of
//! degree < N − 1.

use super::BallbarError;

/// Checks that angles (deg) are N ≥ 8 evenly spaced samples of one full revolution, in
/// increasing order, and returns the spacing (deg).
pub fn check_full_revolution(angles_deg: &[f64]) -> Result<f64, BallbarError> {
    let n = angles_deg.len();
    if n < 8 {
        return Err(BallbarError::Signal(format!(
            "a mode signal needs at least 8 angles over one revolution to separate its first \
             harmonic; it has {n}"
        )));
    }
    let step = 360.0 / n as f64;
    for (i, a) in angles_deg.iter().enumerate() {
        let expected = angles_deg[0] + step * i as f64;
        if (a - expected).abs() > 1e-6 * step.max(1.0) {
            return Err(BallbarError::Signal(format!(
                "angles must be {n} evenly spaced values covering one revolution (step \
                 {step} deg from {first} deg): sample {} is {a} deg, expected {expected} deg",
                i + 1,
                first = angles_deg[0]
            )));
        }
    }
    Ok(step)
}

/// The mean, cosine and sine coefficients `(a0, a1, b1)` of a sampled signal.
pub fn mean_and_first_harmonic(angles_deg: &[f64], values: &[f64]) -> (f64, f64, f64) {
    let n = values.len() as f64;
    let (mut s0, mut sc, mut ss) = (0.0, 0.0, 0.0);
    for (a, v) in angles_deg.iter().zip(values) {
        let c = a.to_radians();
        s0 += v;
        sc += v * c.cos();
        ss += v * c.sin();
    }
    (s0 / n, 2.0 * sc / n, 2.0 * ss / n)
}

/// The signal with its mean and first harmonic removed (see the module docs for the limit).
pub fn remove_mean_and_first_harmonic(
    angles_deg: &[f64],
    values: &[f64],
) -> Result<Vec<f64>, BallbarError> {
    if angles_deg.len() != values.len() {
        return Err(BallbarError::Signal(format!(
            "{} angles but {} values",
            angles_deg.len(),
            values.len()
        )));
    }
    check_full_revolution(angles_deg)?;
    let (a0, a1, b1) = mean_and_first_harmonic(angles_deg, values);
    Ok(angles_deg
        .iter()
        .zip(values)
        .map(|(a, v)| {
            let c = a.to_radians();
            v - a0 - a1 * c.cos() - b1 * c.sin()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn removes_exactly_mean_and_first_harmonic() {
        let angles: Vec<f64> = (0..72).map(|i| i as f64 * 5.0).collect();
        let keep = |c: f64| 0.7 * (2.0 * c).cos() - 0.3 * (3.0 * c + 0.4).sin();
        let signal: Vec<f64> = angles
            .iter()
            .map(|a| {
                let c = a.to_radians();
                4.0 + 2.5 * c.cos() - 1.5 * c.sin() + keep(c)
            })
            .collect();
        let out = remove_mean_and_first_harmonic(&angles, &signal).unwrap();
        for (a, v) in angles.iter().zip(out) {
            assert!((v - keep(a.to_radians())).abs() < 1e-12);
        }
    }

    #[test]
    fn refuses_partial_or_uneven_revolutions() {
        let half: Vec<f64> = (0..36).map(|i| i as f64 * 5.0).collect();
        let v = vec![0.0; 36];
        assert!(remove_mean_and_first_harmonic(&half, &v).is_err());
        let mut uneven: Vec<f64> = (0..72).map(|i| i as f64 * 5.0).collect();
        uneven[10] += 1.0;
        let e = remove_mean_and_first_harmonic(&uneven, &vec![0.0; 72]).unwrap_err();
        assert!(e.to_string().contains("sample 11"), "{e}");
    }
}
