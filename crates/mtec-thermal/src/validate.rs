//! Validation by whole blocks: train/test splits by experiment or by time, and leave-one-block-out
//! cross-validation. Thermal drift is strongly autocorrelated, so a random-row split would put
//! the neighbours of every test row into the training set and report an accuracy no unseen duty
//! cycle will see. mtec never splits by random rows.

use crate::data::ThermalData;
use crate::error::ThermalError;
use crate::metrics::Metrics;
use crate::model::{Fit, Predict};
use serde::{Deserialize, Serialize};

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

/// Result of leave-one-block-out cross-validation.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BlockCv {
    /// Metrics of each held-out block, predicted by the model fitted on all other blocks.
    pub per_block: Vec<Metrics>,
    /// RMSE over all held-out predictions together (µm).
    pub pooled_rmse_um: f64,
    pub pooled_max_abs_um: f64,
}

/// Leave-one-block-out: for each block, fit on the others, predict it.
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
