//! Bringing a stateful model to the machine's state now from a log of its readings
//! (`compensate gcode|table --state LOG.csv`).
//!
//! A model with a state (non-empty [`ErrorModel::state_inputs`], e.g. `mtec.machine-error/1`)
//! gives its thermal part only after readings have started it; an offline output (a rewritten
//! program, a controller table) made from an unstarted state would silently leave the thermal
//! part out. [`advance_through_log`] runs every row of a log (`time_min` plus one column per
//! state input) through [`ErrorModel::update_state`], in order, with the time since the row
//! before; the state after the last row is the one the output is made for. [`WithState`] then
//! carries that fact into the output's provenance line.

use crate::model::{StateError, StateStatus};
use crate::ErrorModel;
use mtec_io::{InputError, Table};

/// What running a log did.
#[derive(Debug, Clone, PartialEq)]
pub struct LogStatus {
    /// Rows read.
    pub rows: usize,
    /// `time_min` of the first and the last row.
    pub first_min: f64,
    pub last_min: f64,
    /// Status of the last update (the state the output uses).
    pub last: StateStatus,
    /// The name of the input furthest outside the training envelope at the last row.
    pub outside: Option<String>,
    /// Rows at which the thermal part was faded (weight < 1).
    pub faded_rows: usize,
}

impl LogStatus {
    /// One line for an output's provenance.
    pub fn describe(&self, log: &str) -> String {
        let mut s = format!(
            "state after {log} ({} readings, time {}–{} min; thermal weight {:.3} at the last",
            self.rows, self.first_min, self.last_min, self.last.thermal_weight
        );
        if let Some(name) = &self.outside {
            s.push_str(&format!(", `{name}` outside the training envelope"));
        }
        s.push(')');
        s
    }
}

/// Runs every row of `log` through `model.update_state` (module docs) and returns the status of
/// the last. Refuses, located at the row and column: a missing column, a non-number, a time that
/// goes back, a log without rows (the caller refuses a static model before calling).
pub fn advance_through_log(
    model: &mut dyn ErrorModel,
    log: &Table,
) -> Result<LogStatus, InputError> {
    let names: Vec<String> = model.state_inputs().to_vec();
    let time_col = log.column("time_min")?;
    let cols: Vec<usize> = names
        .iter()
        .map(|n| log.column(n))
        .collect::<Result<_, _>>()?;
    let mut readings = vec![0.0; names.len()];
    let mut status = LogStatus {
        rows: 0,
        first_min: f64::NAN,
        last_min: f64::NAN,
        last: StateStatus::default(),
        outside: None,
        faded_rows: 0,
    };
    let mut prev: Option<f64> = None;
    for row in &log.rows {
        let t = log.cell_f64(row, time_col)?;
        let dt_min = match prev {
            Some(p) if t < p => {
                return Err(InputError::at(
                    &log.path,
                    row.line,
                    time_col + 1,
                    format!("time goes back ({t} after {p} min): rows must be in time order"),
                ))
            }
            Some(p) => t - p,
            None => 0.0,
        };
        for (r, &c) in readings.iter_mut().zip(&cols) {
            *r = log.cell_f64(row, c)?;
        }
        let s = model
            .update_state(&readings, dt_min * 60.0)
            .map_err(|e| match e {
                StateError::NotFinite { index } => {
                    InputError::at(&log.path, row.line, cols[index] + 1, e.to_string())
                }
                other => InputError::line(&log.path, row.line, other.to_string()),
            })?;
        if s.thermal_weight < 1.0 {
            status.faded_rows += 1;
        }
        if status.rows == 0 {
            status.first_min = t;
        }
        status.rows += 1;
        status.last_min = t;
        status.last = s;
        status.outside = s.outside.map(|j| names[j].clone());
        prev = Some(t);
    }
    if status.rows == 0 {
        return Err(InputError::file(&log.path, "the state log has no rows"));
    }
    Ok(status)
}

/// A model whose provenance line also says which state it is in (module docs); evaluates
/// exactly like the model it wraps.
pub struct WithState {
    model: Box<dyn ErrorModel>,
    describe: String,
}

impl WithState {
    /// `model` (already advanced) with `state` appended to its provenance.
    pub fn new(model: Box<dyn ErrorModel>, state: &str) -> WithState {
        let describe = format!("{}; {state}", model.describe());
        WithState { model, describe }
    }
}

impl ErrorModel for WithState {
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3] {
        self.model.error_um(p_mm)
    }
    fn describe(&self) -> String {
        self.describe.clone()
    }
    fn as_grid(&self) -> Option<&crate::GridMap> {
        self.model.as_grid()
    }
    fn domain_mm(&self) -> Option<[[f64; 2]; 3]> {
        self.model.domain_mm()
    }
    // the state is fixed from here on: no inputs, no updates (the default implementations)
}
