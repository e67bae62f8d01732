//! The report section of a `[[thermal]]` stage, written from the model file that `thermal fit`
//! wrote (issue 24): what the section says is the fitted model's kind, inputs and terms; the
//! training and test rows are shown apart, with a warning when the model makes the drift worse on
//! rows it did not see; the ridge trace appears only for a model the ridge-trace selection made.

use mtec_report::{line_chart, Band, Section, Series};
use mtec_thermal::model::LinearMethod;
use mtec_thermal::{Metrics, ModelFile, ThermalModel};
use serde_json::Value;

/// The numbers of one set of rows as the CLI prints them (`thermal fit`).
fn metrics_row(name: &str, m: &Metrics) -> Vec<String> {
    vec![
        name.to_string(),
        m.n.to_string(),
        format!("{:.3}", m.rmse_um),
        format!("{:.3}", m.max_abs_residual_um),
        m.compensation_rate
            .map(|c| format!("{:.1} %", 100.0 * c))
            .unwrap_or_else(|| "-".into()),
    ]
}

/// Which rows of `table` the model was tested on (its split), or none.
fn test_rows(table: &mtec_io::Table, file: &ModelFile, n: usize) -> Vec<bool> {
    let split = &file.split;
    if split.test_rows == 0 {
        return vec![false; n];
    }
    if let Some(until) = split.train_until_min {
        if let Ok(t) = table.f64_column("time_min") {
            return t.iter().map(|&x| x > until).collect();
        }
    }
    if !split.test_experiments.is_empty() {
        if let Ok(e) = table.str_column("experiment") {
            return e
                .iter()
                .map(|x| split.test_experiments.iter().any(|t| t == x.trim()))
                .collect();
        }
    }
    vec![false; n]
}

/// Contiguous runs of `true` as [start, end] sample indices.
fn runs(flags: &[bool]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, &f) in flags.iter().enumerate() {
        match (f, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s, i - 1));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s, flags.len() - 1));
    }
    out
}

/// What the fitted model is, how well it does on training and test rows, and the drift it
/// predicts. `model` is the file `thermal fit` wrote, `predictions` `thermal predict`'s values on
/// every row of `table`. Returns whether the model is a ridge-trace selection (the caller then
/// adds the trace).
pub fn section(
    sec: &mut Section,
    model: &Value,
    table: Option<&mtec_io::Table>,
    target: &str,
    predictions: Option<&[f64]>,
) -> bool {
    let file: Option<ModelFile> = serde_json::from_value(model.clone()).ok();
    let Some(file) = file else {
        // a neural model file: its own format, no equation to show
        let format = model.get("format").and_then(Value::as_str).unwrap_or("?");
        sec.text(format!(
            "Neural thermal model ({format}); its layers and training are in the model file. \
             The plot shows its prediction against the measured drift."
        ));
        if let (Some(t), Some(p)) = (table, predictions) {
            drift_figure(sec, t, target, p, &[]);
        }
        return false;
    };
    let summary = file.model.summary();
    sec.text(summary.description.clone());
    sec.table(
        &["term", "value", "unit"],
        summary
            .terms
            .iter()
            .map(|t| vec![t.name.clone(), format!("{:.6}", t.value), t.unit.clone()])
            .collect(),
    );
    let mut rows = vec![metrics_row("training rows", &file.train_metrics)];
    if let Some(t) = &file.test_metrics {
        rows.push(metrics_row("test rows", t));
    }
    sec.table(
        &[
            "rows",
            "n",
            "RMSE (µm)",
            "max |residual| (µm)",
            "compensation",
        ],
        rows,
    );
    if let Some(v) = &file.validation {
        sec.text(format!(
            "Forward validation on the training rows (each block predicted by a model fitted on \
             the rows before it only): pooled RMSE {:.3} µm over {} block(s).",
            v.pooled_rmse_um,
            v.folds.len()
        ));
    }
    match &file.test_metrics {
        Some(t) if t.compensation_rate.is_some_and(|c| c < 0.0) => {
            sec.note(format!(
                "Warning: on the test rows the model makes the drift worse than no compensation \
                 (compensation {:.1} %, RMSE {:.3} µm). Do not use it on this machine as it is: \
                 the test rows are outside what it learnt.",
                100.0 * t.compensation_rate.unwrap_or(0.0),
                t.rmse_um
            ));
        }
        Some(_) => {}
        None => {
            sec.note(
                "In-sample only: the model was fitted on every row shown, so these numbers say \
                 how well it fits, not how well it predicts (fit with a train/test split or see \
                 the forward validation).",
            );
        }
    }
    for w in &file.warnings {
        sec.note(format!("Warning from the fit: {w}"));
    }
    if let (Some(t), Some(p)) = (table, predictions) {
        let test = test_rows(t, &file, p.len());
        drift_figure(sec, t, target, p, &test);
    }
    matches!(
        &file.model,
        ThermalModel::Linear(m) if m.method == LinearMethod::RidgeSelect
    )
}

/// Measured and predicted drift and the residual, the test rows shaded.
/// The x axis of a thermal record's plots: its time when `time_min` runs forward through the
/// whole file (hours past 10 h), else the row number (several experiments restart their time).
pub fn time_axis(table: &mtec_io::Table, rows: usize) -> (Vec<f64>, &'static str) {
    if let Ok(t) = table.f64_column("time_min") {
        if t.len() == rows && t.windows(2).all(|w| w[1] > w[0]) {
            return if t.last().is_some_and(|l| l - t[0] > 600.0) {
                (t.iter().map(|m| m / 60.0).collect(), "time (h)")
            } else {
                (t, "time (min)")
            };
        }
    }
    (
        (0..rows).map(|i| i as f64).collect(),
        "row of the data file",
    )
}

fn drift_figure(
    sec: &mut Section,
    table: &mtec_io::Table,
    target: &str,
    pred: &[f64],
    test: &[bool],
) {
    let Ok(y) = table.f64_column(target) else {
        return;
    };
    if y.len() != pred.len() || (!test.is_empty() && test.len() != y.len()) {
        return;
    }
    let (xs, x_label) = time_axis(table, y.len());
    let series = [
        Series::new(
            "measured",
            xs.iter().zip(&y).map(|(a, b)| (*a, *b)).collect(),
        ),
        Series::new(
            "predicted",
            xs.iter().zip(pred).map(|(a, b)| (*a, *b)).collect(),
        ),
        Series::new(
            "residual",
            xs.iter()
                .zip(y.iter().zip(pred))
                .map(|(a, (m, q))| (*a, m - q))
                .collect(),
        ),
    ];
    let all = y
        .iter()
        .chain(pred)
        .chain(
            y.iter()
                .zip(pred)
                .map(|(m, q)| m - q)
                .collect::<Vec<_>>()
                .iter(),
        )
        .cloned()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    let bands: Vec<Band> = runs(test)
        .into_iter()
        .map(|(a, b)| Band {
            name: "test rows".into(),
            x: vec![xs[a], xs[b]],
            lower: vec![all.0; 2],
            upper: vec![all.1; 2],
        })
        .collect();
    let caption = if bands.is_empty() {
        "Measured thermal drift, the model's prediction and the residual (every row was a \
         training row)."
    } else {
        "Measured thermal drift, the model's prediction and the residual; the shaded rows are \
         the test rows, which the fit did not see."
    };
    sec.figure(
        line_chart(
            "Measured and predicted drift",
            x_label,
            "drift (µm)",
            &series,
            &bands,
        ),
        caption,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_are_the_contiguous_test_rows() {
        let f = [false, true, true, false, true];
        assert_eq!(runs(&f), vec![(1, 2), (4, 4)]);
        assert!(runs(&[false, false]).is_empty());
    }
}
