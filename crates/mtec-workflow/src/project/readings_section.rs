//! The report section of a rotary thermal model's predicted ballbar readings (`[ballbar] model`,
//! issue #21): the source's metrics per experiment and its figure of predicted against measured
//! readings.

use crate::ops::thermal::neural::RotaryReadings;
use mtec_report::rotary::{readings_figure, ReadingSample};
use mtec_report::Section;

/// Fills `sec` from the readings of `model` (its file name, for the text).
pub fn section(sec: &mut Section, model: &str, r: &RotaryReadings) {
    sec.source(
        "the readings comparison of the CNN-LSTM rotary-axis study (predicted error motions \
         through the bar-length model of the five installation modes; the source: max residual \
         7.4 µm against 19.3 µm of measured change, −61.6 %); mtec docs/methods.md §10.3",
    );
    sec.text(format!(
        "The error motions that the thermal model {model} predicts from the temperatures are \
         turned into the bar-length reading of every installation mode (first-order ballbar \
         model), and the mean and first harmonic of each mode's revolution are removed from \
         predicted and measured readings alike (the set-up error of every installation). \
         \"change\" is each reading minus the same mode and angle at the experiment's first \
         measurement: the thermal part, which is what a compensation has to remove. Ratio = \
         max |residual| / max |measured|."
    ));
    let mut rows = Vec::new();
    for m in &r.metrics {
        for (what, v) in m.rows() {
            rows.push(vec![
                m.experiment.to_string(),
                what.to_string(),
                m.n.to_string(),
                format!("{:.3}", v[0]),
                format!("{:.3}", v[1]),
                format!("{:.3}", v[2]),
                format!("{:.3}", v[3]),
                format!("{:.1} %", 100.0 * v[4]),
            ]);
        }
    }
    sec.table(
        &[
            "experiment",
            "readings",
            "n",
            "RMSE (µm)",
            "MAE (µm)",
            "max |residual| (µm)",
            "max |measured| (µm)",
            "ratio",
        ],
        rows,
    );
    for m in &r.metrics {
        let samples: Vec<ReadingSample> = r
            .rows
            .iter()
            .filter(|x| x.experiment == m.experiment)
            .map(|x| ReadingSample {
                experiment: i64::from(x.experiment),
                time_min: x.time_min,
                mode: x.mode,
                angle_deg: x.angle_deg,
                predicted_change_um: x.predicted_change_um,
                measured_change_um: x.measured_change_um,
            })
            .collect();
        let f = readings_figure(&samples);
        sec.figure(
            f.svg,
            format!(
                "Experiment {}: the bar-length change of the reading that changed most, measured \
                 and predicted, and the largest |residual| over all modes and angles, against \
                 time. Look at whether the predicted line follows the measured one through the \
                 speed steps and cooling phases, and at how far the residual line stays below \
                 the measured change (here {:.2} µm at worst against {:.2} µm, {:.0} %).",
                m.experiment,
                m.change_max_abs_residual_um,
                m.change_max_abs_measured_um,
                100.0 * m.change_residual_ratio
            ),
        );
    }
}
