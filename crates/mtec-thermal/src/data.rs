//! The thermal data set: temperatures, optional ambient and axis position, and the drift target.
//!
//! File format (SPEC §4): `experiment,time_min,<sensor>_c…,[ambient_c],[position_mm],<target>_um`.
//! Decisions where the spec is silent:
//! - every `_c` column except `ambient_c` is a sensor; other columns (e.g. `spindle_rpm`, other
//!   `_um` channels) are ignored unless named as the target;
//! - `experiment` may be absent (a single continuous record, as the real `fl-thermal` file):
//!   all rows are then experiment `1`;
//! - within one experiment `time_min` must not decrease (the lag filters run along it).

use crate::error::ThermalError;
use mtec_io::{InputError, Table};
use nalgebra::DMatrix;
use std::path::PathBuf;

/// One thermal log, column-wise, with the line of each row for located messages.
#[derive(Debug, Clone)]
pub struct ThermalData {
    /// Experiment (run) label of each row.
    pub experiment: Vec<String>,
    pub time_min: Vec<f64>,
    /// Sensor column names (with their `_c` suffix), in file order.
    pub sensor_names: Vec<String>,
    /// Sensor temperatures, one row per sample, one column per sensor (°C).
    pub temps_c: DMatrix<f64>,
    pub ambient_c: Option<Vec<f64>>,
    pub position_mm: Option<Vec<f64>>,
    /// Target column name (with `_um`) and values, when the file holds it.
    pub target: Option<(String, Vec<f64>)>,
    /// Further targets after `target`, for a model of several outputs (a network of the five
    /// rotary error motions); empty for the regression models, which fit `target` alone.
    pub more_targets: Vec<(String, Vec<f64>)>,
    /// The column that splits each experiment into sequences and its value on every row (e.g.
    /// `angle_deg`: one time series per table angle); [`ThermalData::segments`] then also break
    /// where it changes. `None` for a plain log (one sequence per experiment).
    pub sequence: Option<(String, Vec<f64>)>,
    /// File and header line it came from (for messages), and the line of each row.
    pub source: Option<(PathBuf, usize)>,
    pub lines: Vec<usize>,
}

/// The temperatures a machine tool's structure, coolant, motors and shop air can have (°C): a
/// value outside is a logger's error code (−9999, −273.2, 9999.9, an open thermocouple's full
/// scale), not a reading.
pub const PLAUSIBLE_C: (f64, f64) = (-60.0, 300.0);

/// Normalises a target name: `ch1` and `ch1_um` both mean the column `ch1_um`.
pub fn target_column(name: &str) -> String {
    if name.ends_with("_um") {
        name.to_string()
    } else {
        format!("{name}_um")
    }
}

impl ThermalData {
    /// Reads the thermal columns of a table. `target` is required when `require_target`.
    pub fn from_table(
        table: &Table,
        target: Option<&str>,
        require_target: bool,
    ) -> Result<ThermalData, InputError> {
        let time_min = table.f64_column("time_min")?;
        let experiment = if table.has("experiment") {
            table.str_column("experiment")?
        } else {
            vec!["1".to_string(); table.rows.len()]
        };
        let sensor_names: Vec<String> = table
            .columns_with_suffix("_c")
            .into_iter()
            .filter(|c| c != "ambient_c")
            .collect();
        if sensor_names.is_empty() {
            return Err(InputError::line(
                &table.path,
                table.header_line,
                "no temperature columns: sensor columns end in `_c` (e.g. `spindle_c`)",
            ));
        }
        let n = table.rows.len();
        let mut temps_c = DMatrix::zeros(n, sensor_names.len());
        for (j, s) in sensor_names.iter().enumerate() {
            for (i, v) in table.f64_column(s)?.into_iter().enumerate() {
                temps_c[(i, j)] = v;
            }
        }
        let ambient_c = if table.has("ambient_c") {
            Some(table.f64_column("ambient_c")?)
        } else {
            None
        };
        let position_mm = if table.has("position_mm") {
            Some(table.f64_column("position_mm")?)
        } else {
            None
        };
        let target = match target {
            Some(t) => {
                let col = target_column(t);
                if table.has(&col) {
                    Some((col.clone(), table.f64_column(&col)?))
                } else if require_target {
                    // `column` explains what is there instead (e.g. the wrong unit suffix)
                    return Err(table.column(&col).err().unwrap_or_else(|| {
                        InputError::line(
                            &table.path,
                            table.header_line,
                            format!("missing target column `{col}`"),
                        )
                    }));
                } else {
                    None
                }
            }
            None => None,
        };
        // a logger's error code (−9999, −273.2, an open thermocouple's full scale) is not a
        // temperature: refused at its line, never fitted
        let plausible = |name: &str, values: &[f64]| -> Result<(), InputError> {
            let Some(i) = values
                .iter()
                .position(|v| !(PLAUSIBLE_C.0..=PLAUSIBLE_C.1).contains(v))
            else {
                return Ok(());
            };
            let v = values[i];
            let v = if v.abs() < 1e6 {
                v.to_string()
            } else {
                format!("{v:e}")
            };
            Err(table.error_at(
                &table.rows[i],
                name,
                format!(
                    "`{name}` is {v} °C: no machine tool is at that temperature (mtec accepts {}…{} °C); a logger's error code for a disconnected or failed sensor? Remove those rows, or the sensor's column",
                    PLAUSIBLE_C.0, PLAUSIBLE_C.1
                ),
            ))
        };
        for (j, name) in sensor_names.iter().enumerate() {
            plausible(name, temps_c.column(j).as_slice())?;
        }
        if let Some(a) = &ambient_c {
            plausible("ambient_c", a)?;
        }
        // time must not decrease within an experiment
        for i in 1..n {
            if experiment[i] == experiment[i - 1] && time_min[i] < time_min[i - 1] {
                return Err(table.error_at(
                    &table.rows[i],
                    "time_min",
                    format!(
                        "time goes back ({} after {}) within experiment `{}`: rows must be in time order",
                        time_min[i], time_min[i - 1], experiment[i]
                    ),
                ));
            }
        }
        Ok(ThermalData {
            experiment,
            time_min,
            sensor_names,
            temps_c,
            ambient_c,
            position_mm,
            target,
            more_targets: Vec::new(),
            sequence: None,
            source: Some((table.path.clone(), table.header_line)),
            lines: table.rows.iter().map(|r| r.line).collect(),
        })
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.time_min.len()
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.time_min.is_empty()
    }

    /// Target values, or an error naming the missing target.
    pub fn target_um(&self) -> Result<&[f64], ThermalError> {
        self.target
            .as_ref()
            .map(|(_, v)| v.as_slice())
            .ok_or_else(|| ThermalError::MissingColumn("<target>_um".into()))
    }

    /// Target column name.
    pub fn target_name(&self) -> Option<&str> {
        self.target.as_ref().map(|(n, _)| n.as_str())
    }

    /// Every target (`target`, then `more_targets`) by name; empty when the data hold none.
    pub fn targets(&self) -> Vec<(&str, &[f64])> {
        self.target
            .iter()
            .chain(&self.more_targets)
            .map(|(n, v)| (n.as_str(), v.as_slice()))
            .collect()
    }

    /// Index of a sensor column (accepts `name` or `name_c`).
    pub fn sensor_index(&self, name: &str) -> Result<usize, ThermalError> {
        let full = if name.ends_with("_c") {
            name.to_string()
        } else {
            format!("{name}_c")
        };
        self.sensor_names
            .iter()
            .position(|s| *s == full)
            .ok_or(ThermalError::MissingColumn(full))
    }

    /// One sensor's temperatures as a vector.
    pub fn sensor(&self, j: usize) -> Vec<f64> {
        self.temps_c.column(j).iter().copied().collect()
    }

    /// The distinct experiment labels in order of first appearance.
    pub fn experiments(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for e in &self.experiment {
            if !out.contains(e) {
                out.push(e.clone());
            }
        }
        out
    }

    /// Start and end (exclusive) row of each contiguous experiment segment (of each sequence,
    /// when the data have a sequence column).
    pub fn segments(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut start = 0;
        let seq = self.sequence.as_ref().map(|(_, v)| v);
        for i in 1..=self.len() {
            if i == self.len()
                || self.experiment[i] != self.experiment[start]
                || seq.is_some_and(|v| v[i] != v[start])
            {
                out.push((start, i));
                start = i;
            }
        }
        out
    }

    /// A new data set holding only the given rows (in the given order).
    pub fn rows(&self, idx: &[usize]) -> ThermalData {
        let pick = |v: &Vec<f64>| idx.iter().map(|&i| v[i]).collect::<Vec<_>>();
        ThermalData {
            experiment: idx.iter().map(|&i| self.experiment[i].clone()).collect(),
            time_min: pick(&self.time_min),
            sensor_names: self.sensor_names.clone(),
            temps_c: self.temps_c.select_rows(idx.iter()),
            ambient_c: self.ambient_c.as_ref().map(pick),
            position_mm: self.position_mm.as_ref().map(pick),
            target: self.target.as_ref().map(|(n, v)| (n.clone(), pick(v))),
            more_targets: (self.more_targets.iter())
                .map(|(n, v)| (n.clone(), pick(v)))
                .collect(),
            sequence: self.sequence.as_ref().map(|(n, v)| (n.clone(), pick(v))),
            source: self.source.clone(),
            lines: idx.iter().map(|&i| self.lines[i]).collect(),
        }
    }

    /// The log `self` (the history) followed by `next`, as one record whose filters run through
    /// both: the columns must match, and `next` must start after the history ends (its first
    /// experiment continues the history's last). The result has no target (metrics are taken on
    /// `next` alone); rows of `next` start at index `self.len()`.
    pub fn followed_by(&self, next: &ThermalData) -> Result<ThermalData, ThermalError> {
        if self.sensor_names != next.sensor_names
            || self.ambient_c.is_some() != next.ambient_c.is_some()
            || self.position_mm.is_some() != next.position_mm.is_some()
        {
            return Err(ThermalError::Invalid(format!(
                "the history's columns ({}) differ from the data's ({})",
                self.sensor_names.join(", "),
                next.sensor_names.join(", ")
            )));
        }
        let (Some(h_end), Some(d_start)) = (self.time_min.last(), next.time_min.first()) else {
            return Err(ThermalError::Invalid(
                "the history or the data has no rows".into(),
            ));
        };
        if !(d_start > h_end) {
            return Err(ThermalError::Invalid(format!(
                "the data starts at time_min {d_start}, not after the history's last row ({h_end}): the history must be the log just before the data"
            )));
        }
        // the history's last experiment continues into the data's first
        let last = self.experiment.last().cloned().unwrap_or_default();
        let first = next.experiment[0].clone();
        let mut experiment: Vec<String> = self.experiment.clone();
        experiment.extend(next.experiment.iter().map(|e| {
            if *e == first {
                last.clone()
            } else {
                e.clone()
            }
        }));
        let cat = |a: &Option<Vec<f64>>, b: &Option<Vec<f64>>| match (a, b) {
            (Some(a), Some(b)) => Some(a.iter().chain(b).copied().collect()),
            _ => None,
        };
        let mut temps = DMatrix::zeros(self.len() + next.len(), self.sensor_names.len());
        temps.rows_mut(0, self.len()).copy_from(&self.temps_c);
        temps
            .rows_mut(self.len(), next.len())
            .copy_from(&next.temps_c);
        Ok(ThermalData {
            experiment,
            time_min: self
                .time_min
                .iter()
                .chain(&next.time_min)
                .copied()
                .collect(),
            sensor_names: self.sensor_names.clone(),
            temps_c: temps,
            ambient_c: cat(&self.ambient_c, &next.ambient_c),
            position_mm: cat(&self.position_mm, &next.position_mm),
            target: None,
            more_targets: Vec::new(),
            sequence: None,
            source: next.source.clone(),
            lines: self.lines.iter().chain(&next.lines).copied().collect(),
        })
    }

    /// A message located at the header (used for a column a model needs but the file lacks).
    pub fn header_error(&self, message: impl Into<String>) -> InputError {
        match &self.source {
            Some((p, l)) => InputError::line(p, *l, message),
            None => InputError::file(std::path::Path::new("<data>"), message),
        }
    }
}

/// The target on the given rows.
pub fn target_rows(data: &ThermalData, rows: &[usize]) -> Result<Vec<f64>, ThermalError> {
    let y = data.target_um()?;
    Ok(rows.iter().map(|&i| y[i]).collect())
}

/// Values of a non-temperature column attached to the data (see
/// [`crate::heat_input::with_input`]), by its exact name.
pub fn input_column(data: &ThermalData, name: &str) -> Option<Vec<f64>> {
    data.sensor_names
        .iter()
        .position(|s| s == name)
        .map(|j| data.sensor(j))
}
