//! The temperature log that goes with a ballbar campaign (SPEC §4: `experiment,time_min,
//! <sensor>_c…`): one row of sensor temperatures per experiment and measurement time, looked up
//! by the measurements' (experiment, time). Read by `mtec identify ballbar --temps` and by the
//! neural rotary models.

use mtec_io::{InputError, Table};
use std::collections::BTreeMap;

/// Key of a time (min) in µmin, so that 20.0 and 20.000000001 meet.
pub fn time_key(t_min: f64) -> i64 {
    (t_min * 1e6).round() as i64
}

/// Temperatures (°C) of every sensor at each (experiment, time).
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureLog {
    pub sensor_names: Vec<String>,
    /// (experiment, time in µmin) → temperatures in `sensor_names` order.
    pub rows: BTreeMap<(i64, i64), Vec<f64>>,
}

impl TemperatureLog {
    /// Reads `experiment,time_min,<sensor>_c...` (every `_c` column is a sensor). A repeated
    /// (experiment, time) is an error at its line.
    pub fn from_table(t: &Table) -> Result<TemperatureLog, InputError> {
        t.require(&["experiment", "time_min"])?;
        let sensor_names = t.columns_with_suffix("_c");
        if sensor_names.is_empty() {
            return Err(InputError::line(
                &t.path,
                t.header_line,
                "no temperature column: expected columns named <sensor>_c (degrees Celsius)",
            ));
        }
        let exp = t.i64_column("experiment")?;
        let time = t.f64_column("time_min")?;
        let cols: Vec<Vec<f64>> = sensor_names
            .iter()
            .map(|n| t.f64_column(n))
            .collect::<Result<_, _>>()?;
        let mut rows = BTreeMap::new();
        for (i, row) in t.rows.iter().enumerate() {
            let temps: Vec<f64> = cols.iter().map(|c| c[i]).collect();
            if rows.insert((exp[i], time_key(time[i])), temps).is_some() {
                return Err(t.error_at(
                    row,
                    "time_min",
                    format!(
                        "experiment {} at {} min appears twice in the temperature file",
                        exp[i], time[i]
                    ),
                ));
            }
        }
        Ok(TemperatureLog { sensor_names, rows })
    }

    /// Reads a temperature file (see [`TemperatureLog::from_table`]).
    pub fn read(path: &std::path::Path) -> Result<TemperatureLog, InputError> {
        TemperatureLog::from_table(&Table::read(path)?)
    }

    /// The temperatures at (experiment, time), in `sensor_names` order.
    pub fn at(&self, experiment: i64, time_min: f64) -> Option<&Vec<f64>> {
        self.rows.get(&(experiment, time_key(time_min)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn parse(text: &str) -> Result<TemperatureLog, InputError> {
        TemperatureLog::from_table(&Table::parse(Path::new("temps.csv"), text).unwrap())
    }

    #[test]
    fn rows_by_experiment_and_time() {
        let log = parse("experiment,time_min,T1_c,T2_c\n1,0,20.0,20.5\n1,20,21.0,20.75\n").unwrap();
        assert_eq!(log.sensor_names, ["T1_c", "T2_c"]);
        assert_eq!(log.at(1, 20.000000001), Some(&vec![21.0, 20.75]));
        assert_eq!(log.at(2, 20.0), None);
    }

    #[test]
    fn repeated_time_and_missing_sensors_are_located() {
        let e = parse("experiment,time_min,T1_c\n1,0,20\n1,0,21\n").unwrap_err();
        assert_eq!((e.line, e.column), (Some(3), Some(2)), "{e}");
        assert!(e.message.contains("appears twice"), "{e}");
        let e = parse("experiment,time_min,speed\n1,0,20\n").unwrap_err();
        assert_eq!(e.line, Some(1), "{e}");
        assert!(e.message.contains("no temperature column"), "{e}");
    }
}
