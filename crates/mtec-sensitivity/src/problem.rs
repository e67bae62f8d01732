//! The problem (named inputs with distributions), the model the user implements, the sample
//! matrix, and parallel evaluation.
//!
//! Like argmin's `CostFunction`, the model is a trait the user implements for their own type, so
//! any function of a vector of inputs can be analysed; a closure works through [`FnModel`].
//! Samplers return a [`SampleMatrix`]; [`evaluate`] runs the model on its rows in parallel
//! (rayon) and returns one output column per model output. Analysis functions take that
//! matrix/outputs pair, which may equally come from elsewhere (another program, a file).

use crate::distribution::{validate_all, Distribution};
use crate::SensitivityError;
use rayon::prelude::*;

/// The uncertain inputs of an analysis: one name and one distribution each.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub names: Vec<String>,
    pub distributions: Vec<Distribution>,
}

impl Problem {
    /// A checked problem: at least one input, unique names, valid distributions.
    pub fn new(
        names: Vec<String>,
        distributions: Vec<Distribution>,
    ) -> Result<Problem, SensitivityError> {
        if names.is_empty() {
            return Err(SensitivityError::Problem("no inputs".into()));
        }
        if names.len() != distributions.len() {
            return Err(SensitivityError::Problem(format!(
                "{} names but {} distributions",
                names.len(),
                distributions.len()
            )));
        }
        for (i, n) in names.iter().enumerate() {
            if names[..i].contains(n) {
                return Err(SensitivityError::Problem(format!(
                    "input `{n}` appears twice"
                )));
            }
        }
        validate_all(&names, &distributions)?;
        Ok(Problem {
            names,
            distributions,
        })
    }

    /// Number of inputs D.
    pub fn dim(&self) -> usize {
        self.names.len()
    }

    /// Maps one row of the unit hypercube to input space through each input's quantile function.
    pub(crate) fn scale_row(&self, unit: &mut [f64]) {
        for (u, d) in unit.iter_mut().zip(&self.distributions) {
            *u = d.quantile(*u);
        }
    }
}

/// A model y = f(x) with `n_outputs()` outputs; implement it for your own type.
///
/// `evaluate` must be a pure function of `x` (it is called from several threads at once).
pub trait Model: Sync {
    /// Number of outputs the model writes.
    fn n_outputs(&self) -> usize {
        1
    }
    /// Writes f(x) into `out` (length `n_outputs()`).
    fn evaluate(&self, x: &[f64], out: &mut [f64]);
    /// Writes f at each row of `xs` (rows of `dim` inputs) into `out` (`n_outputs()` per row).
    /// The default calls [`Model::evaluate`] row by row; a model whose arithmetic vectorises
    /// across rows overrides it (it must give the same values as `evaluate`).
    fn evaluate_rows(&self, xs: &[f64], dim: usize, out: &mut [f64]) {
        for (o, x) in out
            .chunks_exact_mut(self.n_outputs())
            .zip(xs.chunks_exact(dim))
        {
            self.evaluate(x, o);
        }
    }
}

/// A scalar model made from a closure `Fn(&[f64]) -> f64`.
pub struct FnModel<F>(pub F);

impl<F: Fn(&[f64]) -> f64 + Sync> Model for FnModel<F> {
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        out[0] = (self.0)(x);
    }
}

/// Largest design a method may draw (rows × inputs values, 160 MB of f64): a count of 10⁹
/// asked for hundreds of gigabytes and aborted the process.
pub const MAX_DESIGN_VALUES: usize = 20_000_000;

/// Refuses a design of `rows` rows (`None`: the count overflowed) of `dim` inputs beyond
/// [`MAX_DESIGN_VALUES`]; `what` says how the rows were counted.
pub fn check_design_size(
    rows: Option<usize>,
    dim: usize,
    what: &str,
) -> Result<(), SensitivityError> {
    match rows.and_then(|r| r.checked_mul(dim.max(1))) {
        Some(v) if v <= MAX_DESIGN_VALUES => Ok(()),
        _ => Err(SensitivityError::Settings(format!(
            "{what} with {dim} inputs is a design of more than {MAX_DESIGN_VALUES} values: use fewer samples"
        ))),
    }
}

/// Sample points, one per row (row-major), in input space.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleMatrix {
    pub n_rows: usize,
    pub n_cols: usize,
    pub data: Vec<f64>,
}

impl SampleMatrix {
    /// A matrix from row-major data; `data.len()` must be `n_rows * n_cols`.
    pub fn from_rows(n_cols: usize, data: Vec<f64>) -> Result<SampleMatrix, SensitivityError> {
        if n_cols == 0 || data.len() % n_cols != 0 {
            return Err(SensitivityError::Settings(format!(
                "{} values do not form rows of {n_cols} columns",
                data.len()
            )));
        }
        Ok(SampleMatrix {
            n_rows: data.len() / n_cols,
            n_cols,
            data,
        })
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.n_cols..(i + 1) * self.n_cols]
    }

    /// Rows as slices.
    pub fn rows(&self) -> impl Iterator<Item = &[f64]> {
        self.data.chunks_exact(self.n_cols)
    }
}

/// Evaluates `model` on every row of `samples` in parallel; returns one column per output
/// (`result[k][i]` = output k at row i).
pub fn evaluate<M: Model + ?Sized>(model: &M, samples: &SampleMatrix) -> Vec<Vec<f64>> {
    let k = model.n_outputs();
    let mut flat = vec![0.0; samples.n_rows * k];
    // Chunks of rows per task keep rayon's overhead small for cheap models.
    const ROWS_PER_TASK: usize = 256;
    flat.par_chunks_mut(ROWS_PER_TASK * k)
        .zip(samples.data.par_chunks(ROWS_PER_TASK * samples.n_cols))
        .for_each(|(out, xs)| model.evaluate_rows(xs, samples.n_cols, out));
    if k == 1 {
        return vec![flat]; // one output: the rows' values are already its column
    }
    (0..k)
        .map(|j| flat.iter().skip(j).step_by(k).copied().collect())
        .collect()
}

/// Checks that an output vector fits a design of `expected` rows and holds finite numbers.
pub(crate) fn check_outputs(y: &[f64], expected: usize) -> Result<(), SensitivityError> {
    if y.len() != expected {
        return Err(SensitivityError::Outputs(format!(
            "{} outputs for a design of {expected} rows",
            y.len()
        )));
    }
    if let Some(i) = y.iter().position(|v| !v.is_finite()) {
        return Err(SensitivityError::Outputs(format!(
            "output of row {i} is {} (not finite)",
            y[i]
        )));
    }
    Ok(())
}

/// Sensitivity indices of one output: first-order S1 and total ST per input, with the half
/// widths of their confidence intervals where the method provides them.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Indices {
    pub inputs: Vec<String>,
    #[serde(rename = "S1")]
    pub s1: Vec<f64>,
    #[serde(rename = "ST")]
    pub st: Vec<f64>,
    #[serde(rename = "S1_conf", skip_serializing_if = "Option::is_none")]
    pub s1_conf: Option<Vec<f64>>,
    #[serde(rename = "ST_conf", skip_serializing_if = "Option::is_none")]
    pub st_conf: Option<Vec<f64>>,
    /// The replicate estimates the intervals come from (bootstrap replicates for Sobol,
    /// independent designs for EFAST), kept so that indices aggregated over poses get intervals
    /// too (`interval` module docs); not part of the JSON.
    #[serde(skip)]
    pub replicates: Option<Replicates>,
    /// Variance of the output over the design.
    pub variance: f64,
}

/// Replicate estimates of S1 and ST: `s1[k][i]` is replicate k's S1 of input i.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Replicates {
    pub s1: Vec<Vec<f64>>,
    pub st: Vec<Vec<f64>>,
}
