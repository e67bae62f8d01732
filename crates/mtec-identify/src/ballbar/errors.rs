//! The identified motions as error functions of the C axis: what a kinematic model (and so
//! compensation) takes.
//!
//! Per motion m ∈ {EXC, EYC, EZC, EAC, EBC}, the values identified at the angles of one
//! experiment and time are fitted by a Fourier series of the harmonics the method recovers,
//! m(C) = Σ_{k=2..N} (a_k·cos kC + b_k·sin kC), by least squares (SVD). The mean and the first
//! harmonic are not in the series: the method removes them with the set-up error (they are the
//! axis' location errors `EX0C EY0C EA0C EB0C`, which come from the geometric model, and the
//! centring of the artefact), so they are zero here, not guessed. `ECC` is not observable and
//! is absent. The motions are in the reference frame (module docs of [`super`]): a machine
//! that uses them has `error_frame = "reference"`.

use super::{BallbarError, IdentifiedRow};
use mtec_model::{Axis, ErrorElement, ErrorFunction, ErrorSet};
use nalgebra::{DMatrix, DVector};

/// The motions of `experiment` at `time_min` as Fourier series with harmonics 2..=`max_harmonic`
/// (module docs). Needs more angles than coefficients.
pub fn motions_to_errors(
    rows: &[IdentifiedRow],
    experiment: i64,
    time_min: f64,
    max_harmonic: usize,
) -> Result<ErrorSet, BallbarError> {
    let sel: Vec<&IdentifiedRow> = rows
        .iter()
        .filter(|r| r.experiment == experiment && r.time_min == time_min)
        .collect();
    if max_harmonic < 2 {
        return Err(BallbarError::Signal(
            "the identified motions hold harmonics 2 and up: max_harmonic must be at least 2"
                .into(),
        ));
    }
    let n_coef = 2 * (max_harmonic - 1);
    if sel.len() <= n_coef {
        return Err(BallbarError::Signal(format!(
            "{} angles at experiment {experiment}, time {time_min} min: a Fourier series up to harmonic {max_harmonic} needs more than {n_coef}",
            sel.len()
        )));
    }
    // design matrix: cos kC, sin kC for k = 2..=N
    let a = DMatrix::from_fn(sel.len(), n_coef, |i, j| {
        let k = (j / 2 + 2) as f64;
        let c = sel[i].angle_deg.to_radians();
        if j % 2 == 0 {
            (k * c).cos()
        } else {
            (k * c).sin()
        }
    });
    let svd = a.svd(true, true);
    let mut set = ErrorSet::new(format!(
        "ballbar identification, experiment {experiment}, time {time_min} min: harmonics 2..{max_harmonic} (mean and first harmonic are the location errors and the set-up, not identified)"
    ));
    let elements = [
        (Axis::X, 0),
        (Axis::Y, 1),
        (Axis::Z, 2),
        (Axis::A, 3),
        (Axis::B, 4),
    ];
    for (direction, k) in elements {
        let y = DVector::from_iterator(sel.len(), sel.iter().map(|r| r.motions.observable()[k]));
        let x = svd
            .solve(&y, 1e-12)
            .map_err(|e| BallbarError::Signal(e.to_string()))?;
        // Fourier shape: cos[k−1], sin[k−1] multiply cos kC, sin kC (harmonic 1 is zero)
        let mut cos = vec![0.0; max_harmonic];
        let mut sin = vec![0.0; max_harmonic];
        for h in 2..=max_harmonic {
            cos[h - 1] = x[2 * (h - 2)];
            sin[h - 1] = x[2 * (h - 2) + 1];
        }
        set.insert(
            ErrorElement::motion(direction, Axis::C),
            ErrorFunction::fourier(0.0, cos, sin),
        );
    }
    Ok(set)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ballbar::ErrorMotions;

    #[test]
    fn a_series_of_harmonics_two_and_up_is_recovered_exactly() {
        let rows: Vec<IdentifiedRow> = (0..72)
            .map(|i| {
                let c = i as f64 * 5.0;
                let r = c.to_radians();
                IdentifiedRow {
                    experiment: 1,
                    time_min: 0.0,
                    angle_deg: c,
                    motions: ErrorMotions::from_observable([
                        2.0 * (2.0 * r).cos() - 0.5 * (5.0 * r).sin(),
                        1.0 * (3.0 * r).sin(),
                        0.3 * (4.0 * r).cos(),
                        12.0 * (2.0 * r).sin(),
                        -7.0 * (6.0 * r).cos(),
                    ]),
                }
            })
            .collect();
        let set = motions_to_errors(&rows, 1, 0.0, 8).unwrap();
        for c in [0.0, 17.0, 123.4, -250.0] {
            let r = f64::to_radians(c);
            let exc = set.value(&ErrorElement::motion(Axis::X, Axis::C), c);
            assert!((exc - (2.0 * (2.0 * r).cos() - 0.5 * (5.0 * r).sin())).abs() < 1e-9);
            let ebc = set.value(&ErrorElement::motion(Axis::B, Axis::C), c);
            assert!((ebc + 7.0 * (6.0 * r).cos()).abs() < 1e-9);
        }
        assert!(motions_to_errors(&rows, 1, 0.0, 1).is_err());
        assert!(motions_to_errors(&rows[..10], 1, 0.0, 8).is_err());
    }
}
