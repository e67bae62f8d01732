//! Validation by whole blocks: train/test splits by experiment or by time, forward-in-time
//! (rolling-origin) validation, and leave-one-block-out cross-validation. Thermal drift is
//! strongly autocorrelated, so a random-row split would put the neighbours of every test row into
//! the training set and report an accuracy no unseen duty cycle will see. mtec never splits by
//! random rows.
//!
//! **Forward validation is the default** (Tashman 2000, "Out-of-sample tests of forecasting
//! accuracy", rolling-origin evaluation): the record is cut into blocks that follow its duty
//! cycle ([`duty_cycle_blocks`]: a new block where the heat-source input steps, e.g. a spindle
//! speed change), and fold f trains on every block before block f and scores block f
//! ([`forward_folds`]). A model is never scored on a block whose future it has seen, which is the
//! situation of a compensation on the machine: it is fitted on what has happened and must predict
//! what comes next. Leave-one-block-out ([`block_cv`]) trains on blocks after the scored one as
//! well, so it lets a model interpolate between a block's past and its future; on the real
//! fl-thermal record it reported 1.95 µm for a model that drifted 59 µm on the next duty cycle.
//! It is kept as a second, **optimistic** opinion.

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::fit::{Fit, Predict};
use crate::linear::RidgeProblem;
use crate::metrics::Metrics;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

// a column of the data ([`crate::data`]) and the block options ([`crate::options`]); kept here
// under their old paths
pub use crate::data::input_column;
pub use crate::options::BlockSpec;

/// Rows of the listed experiments.
pub fn rows_of_experiments(
    data: &ThermalData,
    exps: &[String],
) -> Result<Vec<usize>, ThermalError> {
    for e in exps {
        if !data.experiment.contains(e) {
            return Err(ThermalError::Invalid(format!(
                "experiment `{e}` is not in the data (it has: {})",
                data.experiments().join(", ")
            )));
        }
    }
    Ok((0..data.len())
        .filter(|&i| exps.contains(&data.experiment[i]))
        .collect())
}

/// Rows with `time_min ≤ until` (training) and the rest (test).
pub fn split_at_time(data: &ThermalData, until_min: f64) -> (Vec<usize>, Vec<usize>) {
    (0..data.len()).partition(|&i| data.time_min[i] <= until_min)
}

/// Consecutive time blocks of `block_min` minutes from the start of the record (for a duty cycle
/// of run/rest periods, a block is one run followed by its rest). A trailing block shorter than
/// half a block joins the one before it (too short to validate on its own).
pub fn time_blocks(data: &ThermalData, block_min: f64) -> Vec<Vec<usize>> {
    let t0 = data.time_min.first().copied().unwrap_or(0.0);
    let mut blocks: Vec<Vec<usize>> = Vec::new();
    for i in 0..data.len() {
        let b = ((data.time_min[i] - t0) / block_min).floor() as usize;
        while blocks.len() <= b {
            blocks.push(Vec::new());
        }
        blocks[b].push(i);
    }
    blocks.retain(|b| !b.is_empty());
    if blocks.len() >= 2 {
        let last = &blocks[blocks.len() - 1];
        let span = data.time_min[last[last.len() - 1]] - data.time_min[last[0]];
        if span < 0.5 * block_min {
            let tail = blocks.pop().unwrap_or_default();
            if let Some(prev) = blocks.last_mut() {
                prev.extend(tail);
            }
        }
    }
    blocks
}

/// Result of leave-one-block-out cross-validation (optimistic: see the module docs).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BlockCv {
    /// Metrics of each held-out block, predicted by the model fitted on all other blocks.
    pub per_block: Vec<Metrics>,
    /// RMSE over all held-out predictions together (µm).
    pub pooled_rmse_um: f64,
    pub pooled_max_abs_um: f64,
}

/// Leave-one-block-out: for each block, fit on the others (its future included), predict it.
/// Optimistic for a model that must predict forward in time; [`forward_cv`] is the default.
pub fn block_cv<F: Fit>(
    fitter: &F,
    data: &ThermalData,
    blocks: &[Vec<usize>],
) -> Result<BlockCv, ThermalError> {
    let y = data.target_um()?;
    let mut per_block = Vec::new();
    let (mut sse, mut n, mut max) = (0.0, 0usize, 0.0_f64);
    for (b, test) in blocks.iter().enumerate() {
        let train: Vec<usize> = blocks
            .iter()
            .enumerate()
            .filter(|(c, _)| *c != b)
            .flat_map(|(_, r)| r.iter().copied())
            .collect();
        let model = fitter.fit_rows(data, &train)?;
        let pred = model.predict(data)?;
        let yt: Vec<f64> = test.iter().map(|&i| y[i]).collect();
        let pt: Vec<f64> = test.iter().map(|&i| pred[i]).collect();
        let m = Metrics::new(&yt, &pt, model.predictors());
        sse += m.sse_um2;
        n += m.n;
        max = max.max(m.max_abs_residual_um);
        per_block.push(m);
    }
    Ok(BlockCv {
        per_block,
        pooled_rmse_um: (sse / n as f64).sqrt(),
        pooled_max_abs_um: max,
    })
}

/// Shortest block (min) [`duty_cycle_blocks`] keeps on its own: a step shorter than this joins
/// the next one (30 min: shorter than the thermal time constants that matter, too short to score).
pub const MIN_BLOCK_MIN: f64 = 30.0;

/// Number of equal time blocks of a single record without input steps or `block_min`.
pub const DEFAULT_TIME_BLOCKS: usize = 8;

/// Validation blocks of `rows` (in time order), following the duty cycle.
///
/// - several experiments and no `block_min`: one block per experiment, in order of appearance
///   (taken as the order in time);
/// - `block_min`: consecutive time blocks of that length from the first row (a trailing block
///   shorter than half a block joins the one before);
/// - else, when the input column is present and steps inside the rows: a block starts at every
///   step of the input (its value changes from one row to the next), and a block shorter than
///   [`MIN_BLOCK_MIN`] or than 1/16 of the span joins the following one (the last joins the one
///   before);
/// - else [`DEFAULT_TIME_BLOCKS`] equal time blocks.
pub fn duty_cycle_blocks(data: &ThermalData, rows: &[usize], spec: &BlockSpec) -> Vec<Vec<usize>> {
    if rows.is_empty() {
        return Vec::new();
    }
    let exps: Vec<&String> = {
        let mut v: Vec<&String> = Vec::new();
        for &i in rows {
            if !v.contains(&&data.experiment[i]) {
                v.push(&data.experiment[i]);
            }
        }
        v
    };
    if exps.len() > 1 && spec.block_min.is_none() {
        return exps
            .iter()
            .map(|e| {
                rows.iter()
                    .copied()
                    .filter(|&i| data.experiment[i] == **e)
                    .collect()
            })
            .collect();
    }
    let t0 = data.time_min[rows[0]];
    let span = data.time_min[rows[rows.len() - 1]] - t0;
    let by_length = |len: f64| -> Vec<Vec<usize>> {
        let mut blocks: Vec<Vec<usize>> = Vec::new();
        let mut keys: Vec<i64> = Vec::new();
        for &i in rows {
            let b = ((data.time_min[i] - t0) / len).floor() as i64;
            if keys.last() != Some(&b) {
                keys.push(b);
                blocks.push(Vec::new());
            }
            if let Some(last) = blocks.last_mut() {
                last.push(i);
            }
        }
        join_short_tail(data, blocks, 0.5 * len)
    };
    if let Some(len) = spec.block_min {
        return by_length(len);
    }
    let steps = spec.input.as_deref().and_then(|n| input_column(data, n));
    if let Some(u) = steps {
        let min_len = MIN_BLOCK_MIN.max(span / 16.0);
        let mut blocks: Vec<Vec<usize>> = vec![Vec::new()];
        for (r, &i) in rows.iter().enumerate() {
            let step = r > 0 && u[i] != u[rows[r - 1]];
            let cur = blocks.last().expect("never empty");
            let cur_len = cur
                .first()
                .map(|&a| data.time_min[i] - data.time_min[a])
                .unwrap_or(0.0);
            if step && cur_len >= min_len {
                blocks.push(Vec::new());
            }
            blocks.last_mut().expect("never empty").push(i);
        }
        let blocks = join_short_tail(data, blocks, min_len);
        if blocks.len() >= 2 {
            return blocks;
        }
    }
    by_length((span / DEFAULT_TIME_BLOCKS as f64).max(f64::MIN_POSITIVE) * (1.0 + 1e-9))
}

/// Joins a last block spanning less than `min_len` minutes to the one before it.
fn join_short_tail(
    data: &ThermalData,
    mut blocks: Vec<Vec<usize>>,
    min_len: f64,
) -> Vec<Vec<usize>> {
    blocks.retain(|b| !b.is_empty());
    if blocks.len() >= 2 {
        let last = &blocks[blocks.len() - 1];
        let len = data.time_min[last[last.len() - 1]] - data.time_min[last[0]];
        if len < min_len {
            let tail = blocks.pop().unwrap_or_default();
            if let Some(prev) = blocks.last_mut() {
                prev.extend(tail);
            }
        }
    }
    blocks
}

/// Share of the rows the first forward fold trains on, at least (the earlier folds would fit on
/// too little of the duty cycle to say anything about the final model).
pub const MIN_TRAIN_FRACTION: f64 = 0.5;

/// One rolling-origin fold: fit on `train` (every block before), score `test` (the next block).
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardFold {
    pub train: Vec<usize>,
    pub test: Vec<usize>,
}

/// Rolling-origin folds over time-ordered blocks: fold f trains on blocks 0..f and scores block
/// f, for every f whose training blocks hold at least [`MIN_TRAIN_FRACTION`] of the rows (and at
/// least one block). Never a row of the future in a training set.
pub fn forward_folds(blocks: &[Vec<usize>]) -> Vec<ForwardFold> {
    let total: usize = blocks.iter().map(|b| b.len()).sum();
    let mut folds = Vec::new();
    let mut train: Vec<usize> = Vec::new();
    for (f, b) in blocks.iter().enumerate() {
        if f >= 1 && (train.len() as f64) >= MIN_TRAIN_FRACTION * total as f64 {
            folds.push(ForwardFold {
                train: train.clone(),
                test: b.clone(),
            });
        }
        train.extend(b.iter().copied());
    }
    if folds.is_empty() && blocks.len() >= 2 {
        // two blocks: train on the first, score the second
        let n = blocks.len();
        folds.push(ForwardFold {
            train: blocks[..n - 1].iter().flatten().copied().collect(),
            test: blocks[n - 1].clone(),
        });
    }
    folds
}

/// The forward folds of `rows` (blocks by [`duty_cycle_blocks`]).
pub fn forward_folds_of(data: &ThermalData, rows: &[usize], spec: &BlockSpec) -> Vec<ForwardFold> {
    forward_folds(&duty_cycle_blocks(data, rows, spec))
}

/// The score of one forward fold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoldScore {
    /// Time span of the training rows and of the scored block (min).
    pub train_from_min: f64,
    pub train_to_min: f64,
    pub test_from_min: f64,
    pub test_to_min: f64,
    pub metrics: Metrics,
    /// RMS of the measured drift on the block: the error left without compensation (µm).
    pub uncompensated_rmse_um: f64,
}

impl FoldScore {
    /// The model leaves more error than no compensation on this block.
    pub fn worse_than_uncompensated(&self) -> bool {
        !(self.metrics.rmse_um <= self.uncompensated_rmse_um)
    }
}

/// Result of forward (rolling-origin) validation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForwardCv {
    pub folds: Vec<FoldScore>,
    /// RMSE over all scored rows together (µm).
    pub pooled_rmse_um: f64,
    pub pooled_max_abs_um: f64,
    /// Standard error of the mean fold RMSE, sd(fold RMSE)/√folds (µm), for the 1-SE rule.
    pub rmse_std_error_um: f64,
}

impl ForwardCv {
    /// 1-based numbers of the folds where the model is worse than no compensation.
    pub fn folds_worse_than_uncompensated(&self) -> Vec<usize> {
        self.folds
            .iter()
            .enumerate()
            .filter(|(_, f)| f.worse_than_uncompensated())
            .map(|(i, _)| i + 1)
            .collect()
    }
    /// Mean of the fold RMSEs (µm).
    pub fn mean_rmse_um(&self) -> f64 {
        self.folds.iter().map(|f| f.metrics.rmse_um).sum::<f64>() / self.folds.len() as f64
    }
}

/// Scores precomputed predictions of the folds (`preds[f]` holds the predictions of fold f's
/// test rows, in order).
pub fn score_folds(
    data: &ThermalData,
    folds: &[ForwardFold],
    preds: &[Vec<f64>],
    predictors: usize,
) -> Result<ForwardCv, ThermalError> {
    let y = data.target_um()?;
    let span = |r: &[usize]| {
        (
            r.first().map(|&i| data.time_min[i]).unwrap_or(f64::NAN),
            r.last().map(|&i| data.time_min[i]).unwrap_or(f64::NAN),
        )
    };
    let (mut sse, mut n, mut max) = (0.0, 0usize, 0.0_f64);
    let mut out = Vec::new();
    for (fold, pred) in folds.iter().zip(preds) {
        let yt: Vec<f64> = fold.test.iter().map(|&i| y[i]).collect();
        let m = Metrics::new(&yt, pred, predictors);
        sse += m.sse_um2;
        n += m.n;
        max = max.max(m.max_abs_residual_um);
        let (a, b) = span(&fold.train);
        let (c, d) = span(&fold.test);
        out.push(FoldScore {
            train_from_min: a,
            train_to_min: b,
            test_from_min: c,
            test_to_min: d,
            uncompensated_rmse_um: crate::metrics::rms(&yt),
            metrics: m,
        });
    }
    if out.is_empty() {
        return Err(ThermalError::Undetermined(
            "forward validation needs at least two blocks (a longer record, experiments, or --block-min)".into(),
        ));
    }
    let k = out.len() as f64;
    let mean = out.iter().map(|f| f.metrics.rmse_um).sum::<f64>() / k;
    let sd = if out.len() > 1 {
        (out.iter()
            .map(|f| (f.metrics.rmse_um - mean).powi(2))
            .sum::<f64>()
            / (k - 1.0))
            .sqrt()
    } else {
        0.0
    };
    Ok(ForwardCv {
        folds: out,
        pooled_rmse_um: (sse / n as f64).sqrt(),
        pooled_max_abs_um: max,
        rmse_std_error_um: sd / k.sqrt(),
    })
}

/// Forward (rolling-origin) validation of a fitter: for each fold, fit on its training rows only
/// (every choice the fitter makes inside happens on those rows: nested), predict, score the
/// next block.
pub fn forward_cv<F: Fit>(
    fitter: &F,
    data: &ThermalData,
    folds: &[ForwardFold],
) -> Result<ForwardCv, ThermalError> {
    let mut preds = Vec::new();
    let mut predictors = 0;
    for fold in folds {
        let model = fitter.fit_rows(data, &fold.train)?;
        let pred = model.predict(data)?;
        predictors = model.predictors();
        preds.push(fold.test.iter().map(|&i| pred[i]).collect());
    }
    score_folds(data, folds, &preds, predictors)
}

/// The folds with their rows thinned to at most one per `min_dt_min` minutes (selection scores
/// on a 15-s log need not fit every row: the thermal time constants are tens of minutes; the
/// features are still computed on every row, so the thinned rows carry the full history).
pub fn thin_folds(data: &ThermalData, folds: &[ForwardFold], min_dt_min: f64) -> Vec<ForwardFold> {
    let thin = |rows: &[usize]| -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        for &i in rows {
            match out.last() {
                Some(&l)
                    if data.experiment[l] == data.experiment[i]
                        && data.time_min[i] - data.time_min[l] < min_dt_min => {}
                _ => out.push(i),
            }
        }
        out
    };
    folds
        .iter()
        .map(|f| ForwardFold {
            train: thin(&f.train),
            test: thin(&f.test),
        })
        .collect()
}

/// Forward-fold scores of ridge regressions (correlation form, [`RidgeProblem`]) of `y` on the
/// columns `cols` (each over every row of the data) for every k in `ks`: the pooled RMSE and the
/// fold RMSEs of each k. A fold where the design cannot be fitted (constant or dependent
/// columns) scores ∞.
pub fn ridge_forward_scores(
    cols: &[&[f64]],
    y: &[f64],
    folds: &[ForwardFold],
    ks: &[f64],
) -> Vec<(f64, Vec<f64>)> {
    let p = cols.len();
    let mut sse = vec![0.0; ks.len()];
    let mut per_fold = vec![Vec::with_capacity(folds.len()); ks.len()];
    let mut n = 0usize;
    let names: Vec<String> = (0..p).map(|j| format!("x{j}")).collect();
    for fold in folds {
        n += fold.test.len();
        let x = DMatrix::from_fn(fold.train.len(), p, |r, j| cols[j][fold.train[r]]);
        let ytr: Vec<f64> = fold.train.iter().map(|&i| y[i]).collect();
        let Ok(prob) = RidgeProblem::new(&x, &ytr, &names) else {
            for (s, f) in sse.iter_mut().zip(per_fold.iter_mut()) {
                *s = f64::INFINITY;
                f.push(f64::INFINITY);
            }
            continue;
        };
        for (ki, &k) in ks.iter().enumerate() {
            let Ok(beta) = prob.standardised(k) else {
                sse[ki] = f64::INFINITY;
                per_fold[ki].push(f64::INFINITY);
                continue;
            };
            let (b0, b) = prob.destandardise(&beta);
            let s: f64 = fold
                .test
                .iter()
                .map(|&i| {
                    let f = b0 + (0..p).map(|j| b[j] * cols[j][i]).sum::<f64>();
                    (y[i] - f).powi(2)
                })
                .sum();
            sse[ki] += s;
            per_fold[ki].push((s / fold.test.len() as f64).sqrt());
        }
    }
    sse.into_iter()
        .zip(per_fold)
        .map(|(s, f)| ((s / n.max(1) as f64).sqrt(), f))
        .collect()
}

/// Row spacing (min) of the rows that selection scores (see [`thin_folds`]).
pub const SELECTION_DT_MIN: f64 = 1.0;
