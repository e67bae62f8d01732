//! Direction-dependent compensation values of one axis, from the mean unidirectional positional
//! deviations of an ISO 230-2 run (`mtec compensate table --from-iso230-2`).
//!
//! ISO 230-2:2014 3.3.1 gives, per target P_i, the mean deviation x̄_i↑ of the approaches in the
//! positive direction and x̄_i↓ of those in the negative direction (deviation = position reached
//! − target, µm). The correction that puts the axis on the target is the negative of that error
//! (SPEC §1, method C), per direction: c_i↑ = −x̄_i↑, c_i↓ = −x̄_i↓. The writers of each format
//! (`write_bidirectional` and friends) carry both columns in the controller's own form.

use super::{check_correction, Axis, AxisProfile, TableError};

/// Compensation values of one axis at its measured targets, one column per approach direction.
#[derive(Debug, Clone, PartialEq)]
pub struct BidirectionalProfile {
    /// The axis measured and compensated.
    pub axis: Axis,
    /// Target positions P_i (mm), strictly increasing.
    pub positions_mm: Vec<f64>,
    /// c_i↑ = −x̄_i↑ (µm): the correction when the target is approached moving positive.
    pub forward_um: Vec<f64>,
    /// c_i↓ = −x̄_i↓ (µm): the correction when approached moving negative.
    pub reverse_um: Vec<f64>,
    /// Largest |value| (µm) a writer accepts (see [`check_correction`]).
    pub max_correction_um: f64,
}

impl BidirectionalProfile {
    /// The profile of the mean deviations x̄↑, x̄↓ (µm) at `positions_mm`: c = −x̄ per direction.
    pub fn from_mean_deviations(
        axis: Axis,
        positions_mm: Vec<f64>,
        mean_up_um: &[f64],
        mean_down_um: &[f64],
        max_correction_um: f64,
    ) -> Result<Self, TableError> {
        let n = positions_mm.len();
        if mean_up_um.len() != n || mean_down_um.len() != n {
            return Err(TableError::Sampling(format!(
                "{n} targets but {} forward and {} reverse means",
                mean_up_um.len(),
                mean_down_um.len()
            )));
        }
        if n < 2 {
            return Err(TableError::Sampling(
                "a compensation table needs at least 2 targets".into(),
            ));
        }
        if let Some(k) = (1..n).find(|&k| positions_mm[k] <= positions_mm[k - 1]) {
            return Err(TableError::Sampling(format!(
                "target {} mm does not increase (previous {} mm)",
                positions_mm[k],
                positions_mm[k - 1]
            )));
        }
        Ok(BidirectionalProfile {
            axis,
            positions_mm,
            forward_um: mean_up_um.iter().map(|x| -x).collect(),
            reverse_um: mean_down_um.iter().map(|x| -x).collect(),
            max_correction_um,
        })
    }

    /// The same profile with another size bound (µm).
    pub fn with_max_correction_um(mut self, max_um: f64) -> Self {
        self.max_correction_um = max_um;
        self
    }

    /// Number of targets.
    pub fn len(&self) -> usize {
        self.positions_mm.len()
    }

    /// Never true for a profile built by [`Self::from_mean_deviations`].
    pub fn is_empty(&self) -> bool {
        self.positions_mm.is_empty()
    }

    /// The values (forward, reverse), once every one has passed [`check_correction`]; every
    /// bidirectional writer starts here.
    pub fn checked_values(&self) -> Result<(&[f64], &[f64]), TableError> {
        for (n, &p) in self.positions_mm.iter().enumerate() {
            let mut at = [0.0; 3];
            at[self.axis.index()] = p;
            for c in [self.forward_um[n], self.reverse_um[n]] {
                check_correction(
                    self.axis,
                    Some((self.axis, p)),
                    at,
                    c,
                    c.abs(),
                    self.max_correction_um,
                )?;
            }
        }
        Ok((&self.forward_um, &self.reverse_um))
    }

    /// Start and step of equally spaced targets (to 1 nm); the formats whose tables are
    /// defined by a start and a step (Siemens, FANUC) cannot hold any other spacing.
    pub fn uniform_step(&self, format: &'static str) -> Result<(f64, f64), TableError> {
        let p = &self.positions_mm;
        let start = p[0];
        let step = (p[p.len() - 1] - start) / (p.len() - 1) as f64;
        for (k, &x) in p.iter().enumerate() {
            let expect = start + step * k as f64;
            if (x - expect).abs() > 1e-6 {
                return Err(TableError::rule(
                    format,
                    None,
                    format!(
                        "target {x} mm is not on an equally spaced grid ({start} mm + {k} x {step} mm = {expect} mm): this format holds only equally spaced points; measure on equal steps or use linuxcnc, heidenhain or beckhoff"
                    ),
                ));
            }
        }
        Ok((start, step))
    }

    /// One direction's values `comp_um` on the equally spaced grid `start_mm + k step_mm` (from
    /// [`BidirectionalProfile::uniform_step`]) as the one-direction profile the start-and-step
    /// writers take, with this profile's axis and bound.
    pub fn uniform_axis_profile(
        &self,
        start_mm: f64,
        step_mm: f64,
        comp_um: &[f64],
    ) -> AxisProfile {
        AxisProfile {
            input_axis: self.axis,
            output_axis: self.axis,
            start_mm,
            step_mm,
            comp_um: comp_um.to_vec(),
            rotary: false,
            max_correction_um: self.max_correction_um,
            at_mm: [0.0; 3],
        }
    }

    /// ISO 230-2 3.3.2 reversal B_i = x̄_i↑ − x̄_i↓ = c_i↓ − c_i↑ (µm).
    pub fn reversal_um(&self) -> Vec<f64> {
        self.forward_um
            .iter()
            .zip(&self.reverse_um)
            .map(|(f, r)| r - f)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corrections_are_the_negated_means_and_checked() {
        let p = BidirectionalProfile::from_mean_deviations(
            Axis::X,
            vec![0.0, 10.0],
            &[1.0, -2.0],
            &[3.0, 4.0],
            500.0,
        )
        .unwrap();
        assert_eq!(p.forward_um, vec![-1.0, 2.0]);
        assert_eq!(p.reverse_um, vec![-3.0, -4.0]);
        // B_i = x̄↑ − x̄↓ = 1 − 3, −2 − 4
        assert_eq!(p.reversal_um(), vec![-2.0, -6.0]);
        assert_eq!(p.uniform_step("t").unwrap(), (0.0, 10.0));
        let small = p.clone().with_max_correction_um(3.5);
        let e = small.checked_values().unwrap_err().to_string();
        assert!(
            e.contains("table position X = 10 mm") && e.contains("-4.000 um"),
            "{e}"
        );
        assert!(BidirectionalProfile::from_mean_deviations(
            Axis::X,
            vec![0.0, 0.0],
            &[1.0, 1.0],
            &[1.0, 1.0],
            500.0
        )
        .is_err());
        let uneven = BidirectionalProfile::from_mean_deviations(
            Axis::X,
            vec![0.0, 10.0, 25.0],
            &[0.0; 3],
            &[0.0; 3],
            500.0,
        )
        .unwrap();
        assert!(uneven
            .uniform_step("t")
            .unwrap_err()
            .to_string()
            .contains("target 10 mm is not on an equally spaced grid"));
    }
}
