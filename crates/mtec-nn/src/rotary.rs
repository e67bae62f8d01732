//! The rotary-axis pipeline of the source's CNN-LSTM study, from ballbar measurements to a
//! sequence dataset and from predicted error motions back to predicted ballbar readings.
//!
//! 1. [`TemperatureLog`]: the temperatures at each measurement (`experiment,time_min,<s>_c...`,
//!    e.g. `dbb-rotary`'s `temps.csv`).
//! 2. [`rotary_data`]: joins the per-experiment, per-time, per-angle error motions that
//!    `mtec_identify::ballbar::identify` recovered with those temperatures into mtec-thermal's
//!    `ThermalData`: one sequence per (experiment, angle) (sequence column `angle_deg`), its rows
//!    the measurement times; columns the temperatures and the angle; targets `EXC_um EYC_um
//!    EZC_um EAC_urad EBC_urad`. [`motion_rows`] labels predictions on its rows.
//! 3. [`observable_motions`]: any motions (a model's predictions, a simulation's truth) pushed
//!    through the ballbar method's own path — first-order bar-length model
//!    (`predicted_dl_um`), mean and first harmonic removed per mode, per-angle solve — i.e. the
//!    part of them the five modes can see. The identified motions are exactly this part of the
//!    true motions (see `mtec_identify::ballbar::harmonics`), so a truth must be compared after
//!    this map.
//! 4. [`compare_readings`]: predicted motions → predicted bar-length changes of every mode
//!    (`predicted_dl_um`, mean and first harmonic removed like the measured signal) against the
//!    measured readings after the same removal; the source's figure is the largest residual
//!    against the largest measured reading (7.4 µm against 19.3 µm, −61.6 %).
//!
//! Decisions where the source is silent:
//! - The angle enters as one feature `angle_deg` (as in the source: "temperatures and angle"),
//!   z-scored like every feature, or as its first n harmonics `cos_k(angle_deg)`,
//!   `sin_k(angle_deg)` ([`AngleEncoding::Harmonics`], continuous across 0°/360°; the static
//!   error motions are sums of such harmonics, so a network need not build them from the raw
//!   angle). The angle is a fixed label of each sequence, not a time series.
//! - The readings are compared *after* the mean and first harmonic are removed from both the
//!   measured and the predicted signal of each mode: the raw readings carry a new set-up error
//!   (ball and cup eccentricity, ~10 µm) at every installation, which no model of the axis can or
//!   should predict; the source's readings were likewise "after eccentricity removal".
//! - The largest measured change is `max |cleaned reading|` over the experiment's modes, times
//!   and angles (the error one would be left with without a model), the residual is
//!   `max |predicted − measured|`; the ratio of the two is the source's "residual ratio". The
//!   same ratio for the *thermal change alone* (every reading minus the reading at the same mode
//!   and angle at the experiment's first time, predicted likewise) is reported next to it,
//!   because the static part of the motions repeats in every experiment and dominates the first
//!   ratio.
//!
//! Where it lives: here in `mtec-nn` (which then depends on `mtec-identify` for the ballbar model
//! and on `mtec-io` for the temperature file, both without any NN code), so that the CLI and the
//! tests share one implementation; `mtec-sim` is a dev-dependency only (the `dbb-rotary`
//! acceptance test).

use crate::dataset::{Experiment, Sequence, ThermalDataset};
use crate::error::{NnError, Result};
use mtec_identify::ballbar::identify::solve_angle;
use mtec_identify::ballbar::{
    predicted_dl_um, remove_mean_and_first_harmonic, ErrorMotions, IdentifiedRow, Measurements,
    Setup,
};
use mtec_thermal::ThermalData;
use serde::Serialize;
use std::collections::BTreeMap;

/// The temperature file of a campaign (moved to the ballbar module, where `mtec identify
/// ballbar --temps` reads it too).
pub use mtec_identify::ballbar::TemperatureLog;

/// Target names of the rotary dataset, in `ErrorMotions::observable` order.
pub const TARGET_NAMES: [&str; 5] = ["EXC_um", "EYC_um", "EZC_um", "EAC_urad", "EBC_urad"];
/// The angle feature's name.
pub const ANGLE_FEATURE: &str = "angle_deg";

/// How the table angle enters the features.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AngleEncoding {
    /// One feature `angle_deg` (0..360).
    #[default]
    Degrees,
    /// `2n` features `cos_k(angle_deg)`, `sin_k(angle_deg)` for k = 1..=n: the Fourier basis in
    /// which the error motions of a rotary axis are written (ISO 230-7 harmonics), continuous
    /// across 0°/360°. `Harmonics(1)` is the plain cos/sin encoding.
    Harmonics(u8),
}

impl AngleEncoding {
    /// The features this encoding adds after the temperatures.
    pub fn feature_names(self) -> Vec<String> {
        match self {
            AngleEncoding::Degrees => vec![ANGLE_FEATURE.into()],
            AngleEncoding::Harmonics(n) => harmonic_feature_names(ANGLE_FEATURE, n),
        }
    }
    /// The feature values at `angle_deg`, in `feature_names` order (computed from the names, so
    /// the two cannot disagree).
    pub fn features(self, angle_deg: f64) -> Vec<f64> {
        self.feature_names()
            .iter()
            .map(|n| HarmonicFeature::parse(n).map_or(angle_deg, |h| h.value(angle_deg)))
            .collect()
    }
}

/// `cos_1(col), sin_1(col), …, cos_n(col), sin_n(col)`.
pub fn harmonic_feature_names(column: &str, n: u8) -> Vec<String> {
    (1..=n)
        .flat_map(|order| {
            [Trig::Cos, Trig::Sin].map(|trig| {
                HarmonicFeature {
                    trig,
                    order,
                    column: column.to_string(),
                }
                .name()
            })
        })
        .collect()
}

/// cos or sin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trig {
    Cos,
    Sin,
}

/// A feature derived from an angle column in degrees: `cos_k(col)` = cos(k·col), `sin_k(col)`
/// = sin(k·col). Model files store these names, so a model trained on them recomputes them
/// from the angle column of any data file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HarmonicFeature {
    pub trig: Trig,
    /// Harmonic order k ≥ 1.
    pub order: u8,
    /// The angle column (degrees).
    pub column: String,
}

impl HarmonicFeature {
    /// Parses `cos_k(col)` / `sin_k(col)`; any other name is not a harmonic feature.
    pub fn parse(name: &str) -> Option<HarmonicFeature> {
        let (trig, rest) = if let Some(r) = name.strip_prefix("cos_") {
            (Trig::Cos, r)
        } else {
            (Trig::Sin, name.strip_prefix("sin_")?)
        };
        let (order, rest) = rest.split_once('(')?;
        let column = rest.strip_suffix(')')?;
        let order: u8 = order.parse().ok().filter(|k| *k >= 1)?;
        (!column.is_empty()).then(|| HarmonicFeature {
            trig,
            order,
            column: column.to_string(),
        })
    }
    /// `cos_k(col)` or `sin_k(col)`.
    pub fn name(&self) -> String {
        let trig = match self.trig {
            Trig::Cos => "cos",
            Trig::Sin => "sin",
        };
        format!("{trig}_{}({})", self.order, self.column)
    }
    /// The feature at an angle in degrees.
    pub fn value(&self, angle_deg: f64) -> f64 {
        let a = f64::from(self.order) * angle_deg.to_radians();
        match self.trig {
            Trig::Cos => a.cos(),
            Trig::Sin => a.sin(),
        }
    }
}

/// Keys of times and angles: µmin and µdeg, so that 20.0 and 20.000000001 meet.
fn key(v: f64) -> i64 {
    (v * 1e6).round() as i64
}

/// A rotary dataset in the training representation and, for every sequence, the angle and
/// measurement times it stands for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RotaryDataset {
    pub(crate) data: ThermalDataset,
    /// experiment id → per sequence (angle in deg, times in min).
    pub(crate) labels: BTreeMap<u32, Vec<(f64, Vec<f64>)>>,
}

/// One predicted or measured row: where it is and the five motions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MotionRow {
    pub experiment: u32,
    pub time_min: f64,
    pub angle_deg: f64,
    /// `[EXC, EYC, EZC (µm), EAC, EBC (µrad)]`.
    pub motions: [f64; 5],
}

impl RotaryDataset {
    /// Joins identified motions with the temperatures (see the module docs). Every
    /// (experiment, time) of `rows` needs a temperature row; every experiment the same angles is
    /// not required, but each (experiment, angle) sequence is ordered by time.
    pub(crate) fn build(
        temps: &TemperatureLog,
        rows: &[IdentifiedRow],
        angle_encoding: AngleEncoding,
    ) -> Result<RotaryDataset> {
        // experiment → angle key → [(time, motions)]
        type Series = Vec<(f64, [f64; 5])>;
        let mut groups: BTreeMap<u32, BTreeMap<i64, (f64, Series)>> = BTreeMap::new();
        for r in rows {
            let e = u32::try_from(r.experiment).map_err(|_| {
                NnError::Data(format!(
                    "experiment numbers must be 0 or more, got {}",
                    r.experiment
                ))
            })?;
            groups
                .entry(e)
                .or_default()
                .entry(key(r.angle_deg))
                .or_insert_with(|| (r.angle_deg, Vec::new()))
                .1
                .push((r.time_min, r.motions.observable()));
        }
        if groups.is_empty() {
            return Err(NnError::Data("no identified motions".into()));
        }
        let mut experiments = Vec::new();
        let mut labels = BTreeMap::new();
        for (e, by_angle) in groups {
            let mut sequences = Vec::new();
            let mut lab = Vec::new();
            for (_, (angle, mut series)) in by_angle {
                series.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut features = Vec::with_capacity(series.len());
                for (t, _) in &series {
                    let temp = temps.rows.get(&(e as i64, key(*t))).ok_or_else(|| {
                        NnError::Data(format!(
                            "no temperatures for experiment {e} at {t} min (the temperature file \
                             must have a row for every measurement)"
                        ))
                    })?;
                    let mut f = temp.clone();
                    f.extend(angle_encoding.features(angle));
                    features.push(f);
                }
                lab.push((angle, series.iter().map(|s| s.0).collect()));
                sequences.push(Sequence {
                    features,
                    targets: series.iter().map(|s| s.1.to_vec()).collect(),
                    warmup: 0,
                });
            }
            labels.insert(e, lab);
            experiments.push(Experiment { id: e, sequences });
        }
        let mut feature_names = temps.sensor_names.clone();
        feature_names.extend(angle_encoding.feature_names());
        let data = ThermalDataset {
            feature_names,
            target_names: TARGET_NAMES.iter().map(|s| s.to_string()).collect(),
            experiments,
        };
        data.validate()?;
        Ok(RotaryDataset { data, labels })
    }
}

/// Joins identified motions with the temperatures into thermal data (see the module docs): one
/// sequence per (experiment, angle) ordered by time (sequence column [`ANGLE_FEATURE`]), in
/// experiment and angle order; the columns the temperatures then the angle's features of
/// `angle_encoding`; targets [`TARGET_NAMES`] (`EXC_um` first). Every (experiment, time) of
/// `rows` needs a temperature row; every experiment the same angles is not required.
pub fn rotary_data(
    temps: &TemperatureLog,
    rows: &[IdentifiedRow],
    angle_encoding: AngleEncoding,
) -> Result<ThermalData> {
    let d = RotaryDataset::build(temps, rows, angle_encoding)?;
    Ok(d.data.to_thermal_data(ANGLE_FEATURE, &|e, k, t| {
        let (angle, times) = &d.labels[&e][k];
        (times[t], *angle)
    }))
}

/// Attaches (experiment, time, angle) to the predicted motions `pred` of every row of `data`
/// (thermal data of [`rotary_data`], or some of its rows: `ThermalData::rows`).
pub fn motion_rows(data: &ThermalData, pred: &[Vec<f64>]) -> Result<Vec<MotionRow>> {
    if pred.len() != data.len() {
        return Err(NnError::Data(format!(
            "{} predictions for {} rows",
            pred.len(),
            data.len()
        )));
    }
    let Some((_, angles)) = &data.sequence else {
        return Err(NnError::Data(
            "rotary data need the angle as their sequence column".into(),
        ));
    };
    (0..data.len())
        .map(|i| {
            let p = &pred[i];
            if p.len() != 5 {
                return Err(NnError::Data(format!(
                    "a prediction has {} channels, expected the five motions",
                    p.len()
                )));
            }
            let experiment = data.experiment[i].parse().map_err(|_| {
                NnError::Data(format!("experiment {} is not a number", data.experiment[i]))
            })?;
            Ok(MotionRow {
                experiment,
                time_min: data.time_min[i],
                angle_deg: angles[i],
                motions: [p[0], p[1], p[2], p[3], p[4]],
            })
        })
        .collect()
}

fn ballbar(e: mtec_identify::ballbar::BallbarError) -> NnError {
    NnError::Data(format!("ballbar model: {e}"))
}

/// (experiment, time key) → (time in min, [(angle in deg, value)] sorted by angle).
type ByMeasurement<T> = BTreeMap<(u32, i64), (f64, Vec<(f64, T)>)>;

/// Cleaned readings `[mode][angle]`: predicted and measured, of one measurement.
type ReadingPair = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Rows grouped by (experiment, time) and sorted by angle.
fn by_measurement(rows: &[MotionRow]) -> ByMeasurement<[f64; 5]> {
    let mut g: ByMeasurement<[f64; 5]> = BTreeMap::new();
    for r in rows {
        g.entry((r.experiment, key(r.time_min)))
            .or_insert_with(|| (r.time_min, Vec::new()))
            .1
            .push((r.angle_deg, r.motions));
    }
    for (_, v) in g.values_mut() {
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    g
}

/// Cleaned model readings `[mode][angle]` of motions over one revolution.
fn cleaned_readings(setup: &Setup, series: &[(f64, ErrorMotions)]) -> Result<Vec<Vec<f64>>> {
    let angles: Vec<f64> = series.iter().map(|s| s.0).collect();
    (0..setup.modes.len())
        .map(|m| {
            let raw: Vec<f64> = series
                .iter()
                .map(|(c, e)| predicted_dl_um(setup, *c, e)[m])
                .collect();
            remove_mean_and_first_harmonic(&angles, &raw).map_err(ballbar)
        })
        .collect()
}

/// The part of `rows`' motions the ballbar method sees (module docs, item 3), same order and
/// labels. Each (experiment, time) must cover one full revolution at evenly spaced angles.
pub fn observable_motions(setup: &Setup, rows: &[ErrorMotionsAt]) -> Result<Vec<MotionRow>> {
    let mut g: ByMeasurement<ErrorMotions> = BTreeMap::new();
    for r in rows {
        g.entry((r.experiment, key(r.time_min)))
            .or_insert_with(|| (r.time_min, Vec::new()))
            .1
            .push((r.angle_deg, r.motions));
    }
    let mut out = Vec::with_capacity(rows.len());
    for ((e, _), (time, mut series)) in g {
        series.sort_by(|a, b| a.0.total_cmp(&b.0));
        let cleaned = cleaned_readings(setup, &series)?;
        for (j, (c, _)) in series.iter().enumerate() {
            let y: [f64; 5] = std::array::from_fn(|i| cleaned[i][j]);
            out.push(MotionRow {
                experiment: e,
                time_min: time,
                angle_deg: *c,
                motions: solve_angle(setup, *c, y).map_err(ballbar)?,
            });
        }
    }
    Ok(out)
}

/// All six motions (ECC included) at one experiment, time and angle: a simulation's truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorMotionsAt {
    pub experiment: u32,
    pub time_min: f64,
    pub angle_deg: f64,
    pub motions: ErrorMotions,
}

/// The true motions of one experiment from a `dbb-rotary` truth document (`mtec.truth/1`:
/// `motions` holds columns `experiment, time_min, angle_deg, EXC_um … ECC_urad`). Compare them
/// with predictions after [`observable_motions`].
pub fn truth_motions(truth: &serde_json::Value, experiment: u32) -> Result<Vec<ErrorMotionsAt>> {
    let col = |n: &str| -> Result<Vec<f64>> {
        truth["motions"][n]
            .as_array()
            .and_then(|a| a.iter().map(|v| v.as_f64()).collect::<Option<Vec<f64>>>())
            .ok_or_else(|| NnError::Data(format!("the truth has no numeric motions column {n}")))
    };
    let (exp, time, angle) = (col("experiment")?, col("time_min")?, col("angle_deg")?);
    let e = [
        "EXC_um", "EYC_um", "EZC_um", "EAC_urad", "EBC_urad", "ECC_urad",
    ]
    .iter()
    .map(|n| col(n))
    .collect::<Result<Vec<_>>>()?;
    if e.iter()
        .chain([&time, &angle])
        .any(|c| c.len() != exp.len())
    {
        return Err(NnError::Data(
            "the truth's motions columns differ in length".into(),
        ));
    }
    Ok((0..exp.len())
        .filter(|&i| exp[i] == f64::from(experiment))
        .map(|i| ErrorMotionsAt {
            experiment,
            time_min: time[i],
            angle_deg: angle[i],
            motions: ErrorMotions {
                exc_um: e[0][i],
                eyc_um: e[1][i],
                ezc_um: e[2][i],
                eac_urad: e[3][i],
                ebc_urad: e[4][i],
                ecc_urad: e[5][i],
            },
        })
        .collect())
}

/// Predicted against measured ballbar readings of one experiment (µm), see the module docs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReadingComparison {
    pub experiment: u32,
    /// Readings compared (modes × angles × times).
    pub n: usize,
    pub rmse_um: f64,
    pub mae_um: f64,
    /// max |predicted − measured| over modes, angles and times.
    pub max_abs_residual_um: f64,
    /// max |measured| (cleaned readings).
    pub max_abs_measured_um: f64,
    /// `max_abs_residual_um / max_abs_measured_um` (the source: 7.4 / 19.3 = 0.384).
    pub residual_ratio: f64,
    /// The same for the thermal change alone (readings minus those at the first time).
    pub change_rmse_um: f64,
    pub change_mae_um: f64,
    pub change_max_abs_residual_um: f64,
    pub change_max_abs_measured_um: f64,
    pub change_residual_ratio: f64,
}

impl ReadingComparison {
    /// The two rows of a table, readings and their change: RMSE, MAE, max |residual|,
    /// max |measured| (µm) and their ratio.
    pub fn rows(&self) -> [(&'static str, [f64; 5]); 2] {
        [
            (
                "reading",
                [
                    self.rmse_um,
                    self.mae_um,
                    self.max_abs_residual_um,
                    self.max_abs_measured_um,
                    self.residual_ratio,
                ],
            ),
            (
                "change",
                [
                    self.change_rmse_um,
                    self.change_mae_um,
                    self.change_max_abs_residual_um,
                    self.change_max_abs_measured_um,
                    self.change_residual_ratio,
                ],
            ),
        ]
    }
}

/// One cleaned ballbar reading (µm), predicted and measured, and its bar-length change since
/// the experiment's first measurement (same mode and angle).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ReadingRow {
    pub experiment: u32,
    pub time_min: f64,
    /// Mode id of the setup.
    pub mode: i64,
    pub angle_deg: f64,
    pub predicted_um: f64,
    pub measured_um: f64,
    pub predicted_change_um: f64,
    pub measured_change_um: f64,
}

/// Maps predicted motions of one experiment to predicted readings of every mode, beside the
/// measured readings (both cleaned of mean and first harmonic) and both changes since the
/// first measurement; ordered by time, mode, angle. `predicted` must hold every angle of every
/// measurement of `experiment` in `measured`.
pub fn reading_rows(
    setup: &Setup,
    measured: &Measurements,
    experiment: u32,
    predicted: &[MotionRow],
) -> Result<Vec<ReadingRow>> {
    let pred = by_measurement(predicted);
    let mut out = Vec::new();
    let mut first: Option<ReadingPair> = None;
    for m in measured
        .items
        .iter()
        .filter(|m| m.experiment == experiment as i64)
    {
        let Some((_, series)) = pred.get(&(experiment, key(m.time_min))) else {
            return Err(NnError::Data(format!(
                "no predictions for experiment {experiment} at {} min",
                m.time_min
            )));
        };
        let angles: Vec<i64> = series.iter().map(|s| key(s.0)).collect();
        if angles != m.angles_deg.iter().map(|a| key(*a)).collect::<Vec<_>>() {
            return Err(NnError::Data(format!(
                "the predictions for experiment {experiment} at {} min are not at the measured angles",
                m.time_min
            )));
        }
        let motions: Vec<(f64, ErrorMotions)> = series
            .iter()
            .map(|(c, p)| (*c, ErrorMotions::from_observable(*p)))
            .collect();
        let p = cleaned_readings(setup, &motions)?;
        let y = m
            .dl_um
            .iter()
            .map(|s| remove_mean_and_first_harmonic(&m.angles_deg, s).map_err(ballbar))
            .collect::<Result<Vec<_>>>()?;
        let (p0, y0) = first.get_or_insert_with(|| (p.clone(), y.clone())).clone();
        for (mi, mode) in setup.modes.iter().enumerate() {
            for (j, c) in m.angles_deg.iter().enumerate() {
                out.push(ReadingRow {
                    experiment,
                    time_min: m.time_min,
                    mode: mode.id,
                    angle_deg: *c,
                    predicted_um: p[mi][j],
                    measured_um: y[mi][j],
                    predicted_change_um: p[mi][j] - p0[mi][j],
                    measured_change_um: y[mi][j] - y0[mi][j],
                });
            }
        }
    }
    if out.is_empty() {
        return Err(NnError::Data(format!(
            "the measurements hold no experiment {experiment}"
        )));
    }
    Ok(out)
}

/// The source's metrics of reading rows of one experiment (module docs).
pub fn reading_metrics(experiment: u32, rows: &[ReadingRow]) -> ReadingComparison {
    // RMSE, MAE, max |residual|, max |measured| of (predicted, measured) pairs
    let stats = |pairs: &mut dyn Iterator<Item = (f64, f64)>| {
        let (mut sq, mut ab, mut n, mut max_r, mut max_y) = (0.0, 0.0, 0usize, 0.0f64, 0.0f64);
        for (p, y) in pairs {
            sq += (p - y) * (p - y);
            ab += (p - y).abs();
            n += 1;
            max_r = max_r.max((p - y).abs());
            max_y = max_y.max(y.abs());
        }
        let d = n.max(1) as f64;
        ((sq / d).sqrt(), ab / d, max_r, max_y, n)
    };
    let (rmse, mae, max_r, max_y, n) =
        stats(&mut rows.iter().map(|r| (r.predicted_um, r.measured_um)));
    let (c_rmse, c_mae, c_max_r, c_max_y, _) = stats(
        &mut rows
            .iter()
            .map(|r| (r.predicted_change_um, r.measured_change_um)),
    );
    let ratio = |r: f64, y: f64| if y > 0.0 { r / y } else { f64::INFINITY };
    ReadingComparison {
        experiment,
        n,
        rmse_um: rmse,
        mae_um: mae,
        max_abs_residual_um: max_r,
        max_abs_measured_um: max_y,
        residual_ratio: ratio(max_r, max_y),
        change_rmse_um: c_rmse,
        change_mae_um: c_mae,
        change_max_abs_residual_um: c_max_r,
        change_max_abs_measured_um: c_max_y,
        change_residual_ratio: ratio(c_max_r, c_max_y),
    }
}

/// Maps predicted motions of one experiment to predicted readings of every mode and compares
/// them with the measured readings ([`reading_rows`], [`reading_metrics`]).
pub fn compare_readings(
    setup: &Setup,
    measured: &Measurements,
    experiment: u32,
    predicted: &[MotionRow],
) -> Result<ReadingComparison> {
    let rows = reading_rows(setup, measured, experiment, predicted)?;
    Ok(reading_metrics(experiment, &rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mtec_identify::ballbar::identify::Measurement;

    fn setup() -> Setup {
        Setup::preset(Setup::default_dims()).unwrap()
    }

    const N: usize = 24;

    fn angles() -> Vec<f64> {
        (0..N).map(|i| i as f64 * 360.0 / N as f64).collect()
    }

    /// Harmonics 2–3 only (no content the removal touches, see `harmonics.rs`) plus, optionally,
    /// a uniform axial growth and a constant tilt, which the method cannot see.
    fn motions(c_deg: f64, growth: f64) -> ErrorMotions {
        let r = c_deg.to_radians();
        ErrorMotions {
            exc_um: 2.0 * (3.0 * r).cos(),
            eyc_um: 2.5 * (3.0 * r).sin(),
            ezc_um: 1.2 * (2.0 * r).sin() + growth,
            eac_urad: 20.0 * (2.0 * r).cos(),
            ebc_urad: -20.0 * (2.0 * r).sin() + 3.0 * growth,
            ecc_urad: 0.0,
        }
    }

    #[test]
    fn observable_part_keeps_visible_motions_and_drops_growth_and_tilt() {
        let rows: Vec<ErrorMotionsAt> = angles()
            .into_iter()
            .map(|c| ErrorMotionsAt {
                experiment: 1,
                time_min: 0.0,
                angle_deg: c,
                motions: motions(c, 5.0),
            })
            .collect();
        let seen = observable_motions(&setup(), &rows).unwrap();
        assert_eq!(seen.len(), N);
        for r in &seen {
            let want = motions(r.angle_deg, 0.0).observable();
            for (got, w) in r.motions.iter().zip(want) {
                assert!((got - w).abs() < 1e-9, "{:?} vs {want:?}", r.motions);
            }
        }
    }

    /// Readings worked by hand: measured readings are the model readings of known motions at
    /// two times; predicting those motions exactly leaves no residual, predicting the t = 0
    /// motions at both times leaves exactly the thermal change as residual.
    #[test]
    fn readings_comparison_by_construction() {
        let s = setup();
        let change = |c: f64| ErrorMotions {
            exc_um: 0.8 * (2.0 * c.to_radians()).cos(),
            ..Default::default()
        };
        let at = |t: f64, c: f64| {
            let mut m = motions(c, 0.0);
            if t > 0.0 {
                m.exc_um += change(c).exc_um;
            }
            m
        };
        let items = [0.0, 20.0]
            .iter()
            .map(|&t| Measurement {
                experiment: 3,
                time_min: t,
                angles_deg: angles(),
                dl_um: (0..5)
                    .map(|m| {
                        angles()
                            .iter()
                            .map(|&c| predicted_dl_um(&s, c, &at(t, c))[m] + 7.0)
                            .collect()
                    })
                    .collect(),
                first_line: 2,
            })
            .collect();
        let measured = Measurements { items };
        let rows = |f: &dyn Fn(f64, f64) -> ErrorMotions| -> Vec<MotionRow> {
            [0.0, 20.0]
                .iter()
                .flat_map(|&t| angles().into_iter().map(move |c| (t, c)))
                .map(|(t, c)| MotionRow {
                    experiment: 3,
                    time_min: t,
                    angle_deg: c,
                    motions: f(t, c).observable(),
                })
                .collect()
        };
        let exact = compare_readings(&s, &measured, 3, &rows(&at)).unwrap();
        assert_eq!(exact.n, 2 * 5 * N);
        assert!(exact.max_abs_residual_um < 1e-9 && exact.residual_ratio < 1e-9);
        assert!(exact.max_abs_measured_um > 1.0);
        let stale = compare_readings(&s, &measured, 3, &rows(&|_, c| at(0.0, c))).unwrap();
        // the t = 20 readings differ by the change's readings, cleaned like every signal
        let mut want = 0.0f64;
        for m in 0..5 {
            let sig: Vec<f64> = angles()
                .iter()
                .map(|&c| predicted_dl_um(&s, c, &change(c))[m])
                .collect();
            for v in remove_mean_and_first_harmonic(&angles(), &sig).unwrap() {
                want = want.max(v.abs());
            }
        }
        assert!(want > 0.3, "{want}");
        assert!((stale.max_abs_residual_um - want).abs() < 1e-9);
        assert!((stale.change_max_abs_measured_um - want).abs() < 1e-9);
        assert!((stale.change_residual_ratio - 1.0).abs() < 1e-9);
        // MAE by hand: zero at t = 0, |change| at t = 20, over 2 × 5 × N readings
        let rows20 = reading_rows(&s, &measured, 3, &rows(&|_, c| at(0.0, c))).unwrap();
        assert_eq!(rows20.len(), 2 * 5 * N);
        assert_eq!(rows20[N].mode, 2);
        let mae: f64 = rows20
            .iter()
            .map(|r| r.measured_change_um.abs())
            .sum::<f64>()
            / (2 * 5 * N) as f64;
        assert!((stale.mae_um - mae).abs() < 1e-9 && stale.mae_um > 0.05);
        assert!(exact.mae_um < 1e-9);
        // an experiment without measurements is refused
        assert!(compare_readings(&s, &measured, 4, &rows(&at)).is_err());
    }

    #[test]
    fn harmonic_feature_names_parse_back() {
        for name in harmonic_feature_names("angle_deg", 3) {
            let h = HarmonicFeature::parse(&name).unwrap();
            assert_eq!(h.column, "angle_deg");
            assert_eq!(
                harmonic_feature_names(&h.column, h.order)
                    [2 * (h.order as usize - 1) + usize::from(h.trig == Trig::Sin)],
                name
            );
        }
        let h = HarmonicFeature::parse("sin_3(c_deg)").unwrap();
        assert!((h.value(30.0) - 1.0).abs() < 1e-12); // sin 90°
        for bad in [
            "cos_0(a)", "cos_1()", "tan_1(a)", "cos_x(a)", "cos_1(a", "T1_c",
        ] {
            assert!(HarmonicFeature::parse(bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn dataset_needs_a_temperature_row_for_every_measurement() {
        let row = |t: f64, c: f64| IdentifiedRow {
            experiment: 1,
            time_min: t,
            angle_deg: c,
            motions: motions(c, 0.0),
        };
        let temps = TemperatureLog {
            sensor_names: vec!["T1_c".into(), "T2_c".into()],
            rows: [
                ((1, 0), vec![20.0, 20.1]),
                ((1, key(20.0)), vec![21.0, 20.5]),
            ]
            .into_iter()
            .collect(),
        };
        let rows = vec![
            row(20.0, 90.0),
            row(0.0, 0.0),
            row(0.0, 90.0),
            row(20.0, 0.0),
        ];
        let d = RotaryDataset::build(&temps, &rows, AngleEncoding::Degrees).unwrap();
        assert_eq!(d.data.feature_names, ["T1_c", "T2_c", "angle_deg"]);
        let seq = &d.data.experiments[0].sequences[1]; // angle 90, times in order
        assert_eq!(
            seq.features,
            vec![vec![20.0, 20.1, 90.0], vec![21.0, 20.5, 90.0]]
        );
        assert_eq!(d.labels[&1][1], (90.0, vec![0.0, 20.0]));
        let cs = RotaryDataset::build(&temps, &rows, AngleEncoding::Harmonics(2)).unwrap();
        assert_eq!(
            cs.data.feature_names[2..],
            [
                "cos_1(angle_deg)",
                "sin_1(angle_deg)",
                "cos_2(angle_deg)",
                "sin_2(angle_deg)"
            ]
        );
        // angle 90°: cos 90 = 0, sin 90 = 1, cos 180 = −1, sin 180 = 0
        let f = &cs.data.experiments[0].sequences[1].features[0][2..];
        for (got, want) in f.iter().zip([0.0, 1.0, -1.0, 0.0]) {
            assert!((got - want).abs() < 1e-12, "{f:?}");
        }
        // as thermal data: one sequence per angle, rows in time order; labels from its rows
        let data = rotary_data(&temps, &rows, AngleEncoding::Degrees).unwrap();
        assert_eq!(data.time_min, vec![0.0, 20.0, 0.0, 20.0]);
        assert_eq!(
            data.sequence.as_ref().unwrap().1,
            vec![0.0, 0.0, 90.0, 90.0]
        );
        assert_eq!(data.segments(), vec![(0, 2), (2, 4)]);
        assert_eq!(data.sensor_names, ["T1_c", "T2_c", "angle_deg"]);
        assert_eq!((data.temps_c[(3, 0)], data.temps_c[(3, 2)]), (21.0, 90.0));
        assert_eq!(data.targets().len(), 5);
        let y: Vec<Vec<f64>> = (0..4)
            .map(|i| data.targets().iter().map(|(_, v)| v[i]).collect())
            .collect();
        let labelled = motion_rows(&data, &y).unwrap();
        assert_eq!(
            labelled[3],
            MotionRow {
                experiment: 1,
                time_min: 20.0,
                angle_deg: 90.0,
                motions: motions(90.0, 0.0).observable(),
            }
        );
        assert!(motion_rows(&data, &y[..3]).is_err());
        let mut missing = rows.clone();
        missing.push(row(40.0, 0.0));
        let e = RotaryDataset::build(&temps, &missing, AngleEncoding::Degrees).unwrap_err();
        assert!(e.to_string().contains("experiment 1 at 40 min"), "{e}");
    }
}
