//! Running the model over the temperature log up to now: the state at the last row (and, when
//! asked, at the moment the offset was last set), as the drift line of the axis.

use super::source::{History, OffsetModel};
use super::OffsetError;
use crate::ErrorModel;
use mtec_io::{InputError, Table};

/// A log shorter than this many slowest time constants is refused unless it starts at rest:
/// a first-order lag forgets its starting value as e^(−t/τ), and e^(−5) < 1 %.
pub const HISTORY_TAUS: f64 = 5.0;

/// The thermal drift of the axis at one moment: δ(x) = k·x + b (µm) along the model's position
/// coordinate x (mm), before the envelope weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriftLine {
    pub k_um_per_mm: f64,
    pub b_um: f64,
}

impl DriftLine {
    /// δ(x) = k·x + b.
    pub fn at(&self, x_mm: f64) -> f64 {
        self.k_um_per_mm * x_mm + self.b_um
    }
}

/// An input outside its training range at a moment.
#[derive(Debug, Clone, PartialEq)]
pub struct Outside {
    pub input: String,
    pub value: f64,
    pub range: [f64; 2],
}

/// The model's state at one row of the log.
#[derive(Debug, Clone, PartialEq)]
pub struct Moment {
    /// Line of the row in the log.
    pub line: usize,
    pub time_min: f64,
    pub drift: DriftLine,
    /// Envelope weight (1 inside the training ranges, fading to 0 outside: `crate::machine`).
    pub weight: f64,
    pub outside: Option<Outside>,
}

/// Options of [`run_log`].
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    /// The first row is the machine at rest, in equilibrium with the room (the filters and
    /// exp-ambient's rises start there, as in training).
    pub starts_at_rest: bool,
    /// The log time (min) at which the work offset was last set (touched off or probed): the
    /// update is then relative to the drift at that moment.
    pub zeroed_at_min: Option<f64>,
}

/// The log run: the state now (the last row) and at the zeroing moment.
#[derive(Debug, Clone, PartialEq)]
pub struct LogRun {
    pub now: Moment,
    pub zeroed: Option<Moment>,
    /// Line and time of the first row (where the filters started).
    pub first_line: usize,
    pub first_time_min: f64,
    /// Rows before now outside the envelope (for a note: the state carries their history).
    pub earlier_outside: usize,
    pub history: History,
    /// Whether the drift depends on the axis position.
    pub position_dependent: bool,
    /// The caller stated that the first row is the machine at rest.
    pub starts_at_rest: bool,
}

/// Runs `model` over every row of `log` (columns `time_min` and the model's inputs; an
/// `experiment` column, if present, must hold one value) and returns the state now.
pub fn run_log(
    model: &mut OffsetModel,
    log: &Table,
    opts: RunOptions,
) -> Result<LogRun, OffsetError> {
    let t_col = log.column("time_min")?;
    let cols: Vec<usize> = model
        .inputs()
        .iter()
        .map(|n| log.column(n))
        .collect::<Result<_, _>>()?;
    let exp_col = log
        .has("experiment")
        .then(|| log.column("experiment"))
        .transpose()?;
    let first = &log.rows[0];
    let first_time = log.cell_f64(first, t_col)?;
    let mut readings = vec![0.0; cols.len()];
    let mut prev_time = first_time;
    let mut moment: Option<Moment> = None;
    let mut zeroed: Option<Moment> = None;
    let mut earlier_outside = 0;
    for (i, row) in log.rows.iter().enumerate() {
        let t = log.cell_f64(row, t_col)?;
        if let Some(c) = exp_col {
            if row.fields[c] != first.fields[c] {
                return Err(InputError::at(
                    &log.path,
                    row.line,
                    c + 1,
                    format!(
                        "experiment `{}` after `{}`: the log up to now must be one continuous record (the model's filters run along it)",
                        row.fields[c], first.fields[c]
                    ),
                )
                .into());
            }
        }
        if t < prev_time {
            return Err(InputError::at(
                &log.path,
                row.line,
                t_col + 1,
                format!("time goes back ({t} after {prev_time}): rows must be in time order"),
            )
            .into());
        }
        for (r, &c) in readings.iter_mut().zip(&cols) {
            *r = log.cell_f64(row, c)?;
        }
        let status = model
            .machine
            .update_state(&readings, (t - prev_time) * 60.0)
            .map_err(|e| InputError::line(&log.path, row.line, e.to_string()))?;
        prev_time = t;
        let outside = status.outside.map(|j| Outside {
            input: model.inputs()[j].clone(),
            value: readings[j],
            range: model.machine.envelope()[j],
        });
        if moment.as_ref().is_some_and(|m| m.outside.is_some()) {
            earlier_outside += 1;
        }
        let m = Moment {
            line: row.line,
            time_min: t,
            drift: drift_line(model, &log.path, row.line)?,
            weight: status.thermal_weight,
            outside,
        };
        if let Some(tz) = opts.zeroed_at_min {
            let next = log
                .rows
                .get(i + 1)
                .map(|r| log.cell_f64(r, t_col))
                .transpose()?;
            if t <= tz && next.is_none_or(|n| n > tz) {
                zeroed = Some(m.clone());
            }
        }
        moment = Some(m);
    }
    // Table::read guarantees at least one data row
    let now = moment.ok_or_else(|| InputError::file(&log.path, "no data rows"))?;
    if let Some(tz) = opts.zeroed_at_min {
        if !(tz >= first_time && tz <= now.time_min) {
            return Err(OffsetError::Usage(format!(
                "--zeroed-at-min {tz}: the log {} runs from {first_time} to {} min; the moment the offset was set must be inside it",
                log.path.display(),
                now.time_min
            )));
        }
    }
    check_history(
        model.history,
        log,
        first.line,
        now.time_min - first_time,
        opts,
    )?;
    Ok(LogRun {
        now,
        zeroed,
        first_line: first.line,
        first_time_min: first_time,
        earlier_outside,
        history: model.history,
        position_dependent: model.position_dependent,
        starts_at_rest: opts.starts_at_rest,
    })
}

/// δ(x) = k·x + b from the model at x = 0 and x = 1000 mm, checked at x = −1000 mm: every
/// model mtec fits is linear in the position (exp-ambient by its equation, the others do not
/// depend on it); a model that is not is refused rather than misrepresented.
fn drift_line(
    model: &OffsetModel,
    log: &std::path::Path,
    line: usize,
) -> Result<DriftLine, InputError> {
    let a = model.axis.index();
    let at = |x: f64| {
        let mut p = [0.0; 3];
        p[a] = x;
        model.machine.thermal_um(p)[a]
    };
    let (d0, d1, dm) = (at(0.0), at(1000.0), at(-1000.0));
    let line_fit = DriftLine {
        k_um_per_mm: (d1 - d0) / 1000.0,
        b_um: d0,
    };
    let scale = 1.0 + d0.abs() + d1.abs();
    if !(d0.is_finite() && d1.is_finite() && (dm - line_fit.at(-1000.0)).abs() <= 1e-9 * scale) {
        return Err(InputError::line(
            log,
            line,
            format!(
                "the model's drift here is not a straight line in the {} position ({d0} um at 0, {d1} um at 1000 mm, {dm} um at -1000 mm): thermal-offset handles models of the form k*x + b",
                model.axis.letter()
            ),
        ));
    }
    Ok(line_fit)
}

/// Refuses a log that cannot have brought the model's state to now (module docs).
fn check_history(
    history: History,
    log: &Table,
    first_line: usize,
    span_min: f64,
    opts: RunOptions,
) -> Result<(), InputError> {
    if opts.starts_at_rest {
        return Ok(());
    }
    match history {
        History::None => Ok(()),
        History::Lags { slowest_tau_min } if span_min >= HISTORY_TAUS * slowest_tau_min => Ok(()),
        History::Lags { slowest_tau_min } => Err(InputError::line(
            &log.path,
            first_line,
            format!(
                "the log starts here and spans {span_min} min, but the model's slowest lag filter (tau = {slowest_tau_min:.1} min) needs {:.0} min of history to forget where it started; give the temperature log since the machine was last at rest and --starts-at-rest (the filters start at the first row, in equilibrium), or a longer log",
                HISTORY_TAUS * slowest_tau_min
            ),
        )),
        History::FromStart => Err(InputError::line(
            &log.path,
            first_line,
            "the log starts here: the model's temperature rises (exp-ambient) are measured from the first row, which must be the machine at rest in equilibrium with the room, as in its training runs; give the log since that moment and --starts-at-rest",
        )),
    }
}
