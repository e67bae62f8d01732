//! The identified motions as a table (`motions.csv`, docs/formats.md): one record per
//! experiment, time and angle, with the temperatures of that experiment and time joined in.

use super::identify::Identification;
use super::temps::TemperatureLog;
use mtec_io::CsvWriter;
use serde::Serialize;
use std::collections::BTreeMap;

/// The header of `motions.csv` before the temperature columns.
pub const MOTIONS_HEADER: &str =
    "experiment,time_min,angle_deg,EXC_um,EYC_um,EZC_um,EAC_urad,EBC_urad";

/// One identified angle with its temperatures: a row of `motions.csv`, an element of the
/// `motions` array of `mtec.ballbar-identification/1`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionRecord {
    pub experiment: i64,
    pub time_min: f64,
    pub angle_deg: f64,
    #[serde(rename = "EXC_um")]
    pub exc_um: f64,
    #[serde(rename = "EYC_um")]
    pub eyc_um: f64,
    #[serde(rename = "EZC_um")]
    pub ezc_um: f64,
    #[serde(rename = "EAC_urad")]
    pub eac_urad: f64,
    #[serde(rename = "EBC_urad")]
    pub ebc_urad: f64,
    /// `<sensor>_c` → temperature (°C) at this experiment and time; empty without a log.
    #[serde(flatten)]
    pub temperatures_c: BTreeMap<String, f64>,
}

/// The records of every identified angle, in the identification's order. An (experiment, time)
/// the log does not hold gets no temperatures (callers check the join first).
pub fn motion_records(
    result: &Identification,
    temps: Option<&TemperatureLog>,
) -> Vec<MotionRecord> {
    result
        .rows
        .iter()
        .map(|r| MotionRecord {
            experiment: r.experiment,
            time_min: r.time_min,
            angle_deg: r.angle_deg,
            exc_um: r.motions.exc_um,
            eyc_um: r.motions.eyc_um,
            ezc_um: r.motions.ezc_um,
            eac_urad: r.motions.eac_urad,
            ebc_urad: r.motions.ebc_urad,
            temperatures_c: match temps.and_then(|t| t.at(r.experiment, r.time_min).map(|v| (t, v)))
            {
                Some((t, v)) => t
                    .sensor_names
                    .iter()
                    .cloned()
                    .zip(v.iter().copied())
                    .collect(),
                None => BTreeMap::new(),
            },
        })
        .collect()
}

/// `motions.csv`: [`MOTIONS_HEADER`] and the log's sensor columns in its order; translations
/// to 0.1 nm, rotations to 1 nrad, temperatures as read. An (experiment, time) the log does not
/// hold gets empty temperature cells.
pub fn motions_csv(result: &Identification, temps: Option<&TemperatureLog>) -> String {
    let sensors = temps.map_or(&[][..], |t| &t.sensor_names[..]);
    let mut w = CsvWriter::new(
        MOTIONS_HEADER
            .split(',')
            .chain(sensors.iter().map(|s| s.as_str())),
    );
    for r in &result.rows {
        let m = &r.motions;
        let mut row = vec![
            r.experiment.to_string(),
            r.time_min.to_string(),
            r.angle_deg.to_string(),
        ];
        row.extend([m.exc_um, m.eyc_um, m.ezc_um].map(|v| format!("{v:.4}")));
        row.extend([m.eac_urad, m.ebc_urad].map(|v| format!("{v:.3}")));
        if let Some(t) = temps {
            match t.at(r.experiment, r.time_min) {
                Some(v) => row.extend(v.iter().map(|v| v.to_string())),
                None => row.extend(sensors.iter().map(|_| String::new())),
            }
        }
        w.row(row);
    }
    w.finish()
}
