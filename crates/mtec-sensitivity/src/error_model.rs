//! Global sensitivity of a machine's volumetric error to its geometric error elements: the
//! source method (EFAST on the first-order 3-axis error model, inputs = error elements with
//! measured normal distributions, outputs Ex, Ey, Ez), plus Sobol and Morris as cross-checks,
//! the ranking of key and coupled errors, and a tolerance allocation.
//!
//! Decisions where the spec is silent:
//! - **Model.** The first-order volumetric model of `mtec-model`: at a commanded pose q,
//!   E(q) = J(q)·e with J the first-order Jacobian (µm per µm or per µrad) and e the element
//!   values. Ex, Ey, Ez are linear in e, so for them S1 = ST = J_i²σ_i²/Σ_j J_j²σ_j² exactly
//!   (the tests use this as ground truth); the fourth output, the total volumetric error
//!   |E| = √(Ex² + Ey² + Ez²), is non-linear and is where the elements couple (ST > S1).
//! - **Inputs.** Every element of the statistics file with std > 0 is an input, normal with its
//!   mean and std; elements with std = 0 stay fixed at their mean (they shift E, and so |E|,
//!   but have no index). Elements the machine's chain does not have are refused.
//! - **Several points** (`--points`): all points share one sample of the element values (the
//!   machine has one set of errors). Indices are aggregated per output with variance weights,
//!   S_i = Σ_p V_p S_{i,p} / Σ_p V_p, the generalised index of Gamboa, Janon, Klein & Lagnoux
//!   (2014, Electron. J. Stat. 8:575–603) for a vector output: the share of the total variance
//!   over the workspace that input i explains. Points where an output does not vary get weight 0.
//! - **Key errors** are ranked by S1 of |E| (and per axis); **coupled errors** by ST − S1 of |E|,
//!   listed when ST − S1 ≥ 0.03 (above EFAST's leakage floor, see [`COUPLING_THRESHOLD`]).
//! - **Tolerance allocation** (equal-effects rule of tolerance design): the target accuracy T
//!   (default 25 µm) bounds each of Ex, Ey, Ez at a coverage factor k (default 2, ≈ 95 %), so each
//!   axis may have a standard deviation σ_T = T/k. From the indices, element i's effective
//!   coefficient on output a is c_{i,a} = √(ST_{i,a}·V_a)/σ_i (exactly |J_{a,i}| at one point;
//!   its RMS over several points). Giving each of the n_a elements that reach output a an equal
//!   share of σ_T² gives the allowed std σ_i,a = σ_T / (√n_a · c_{i,a}); the table reports the
//!   smallest over the three axes and which axis binds. The means (systematic errors) are left
//!   to compensation and are not part of the budget.

use crate::efast::{self, EfastSettings};
use crate::interval::{bootstrap_half_widths, replicate_half_widths};
use crate::morris::{self, MorrisSettings};
use crate::problem::{evaluate, Model, Problem};
use crate::sobol::{self, Bootstrap};
use crate::{Distribution, SensitivityError};
use mtec_io::{InputError, Table};
use mtec_model::{ErrorElement, ErrorSet, Machine, VolumetricModel};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Output channel names, in order.
pub const OUTPUTS: [&str; 4] = ["Ex", "Ey", "Ez", "E"];

/// Measured statistics of one error element.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementStat {
    pub element: String,
    pub mean: f64,
    pub std: f64,
    /// `um` or `urad`, as the element requires.
    pub unit: String,
}

/// Positions per travel at which [`ErrorStatistics::of_identified`] samples each function.
pub const IDENTIFIED_SAMPLES: usize = 101;

/// The error-statistics file (SPEC §4: `element,mean,std,unit`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorStatistics {
    pub elements: Vec<ElementStat>,
}

impl ErrorStatistics {
    /// Reads and checks a statistics CSV: known ISO 230-1 names, each once, finite mean,
    /// std ≥ 0, unit matching the element (`um` for translations, `urad` for rotations).
    pub fn read(path: &Path) -> Result<ErrorStatistics, InputError> {
        let t = Table::read(path)?;
        t.require(&["element", "mean", "std", "unit"])?;
        let (ce, cm, cs, cu) = (
            t.column("element")?,
            t.column("mean")?,
            t.column("std")?,
            t.column("unit")?,
        );
        let mut elements: Vec<ElementStat> = Vec::new();
        for row in &t.rows {
            let name = row.fields[ce].trim().to_string();
            let el = ErrorElement::parse(&name)
                .map_err(|e| InputError::at(path, row.line, ce + 1, e.to_string()))?;
            let canonical = el.name();
            if elements.iter().any(|s| s.element == canonical) {
                return Err(InputError::at(
                    path,
                    row.line,
                    ce + 1,
                    format!("element `{canonical}` is listed twice"),
                ));
            }
            let mean = t.cell_f64(row, cm)?;
            let std = t.cell_f64(row, cs)?;
            if std < 0.0 {
                return Err(InputError::at(
                    path,
                    row.line,
                    cs + 1,
                    format!("std is {std}: a standard deviation cannot be negative"),
                ));
            }
            let unit = row.fields[cu].trim().to_string();
            let want = el.unit();
            let unit_ok = unit == want
                || (want == "um" && unit == "µm")
                || (want == "urad" && unit == "µrad");
            if !unit_ok {
                return Err(InputError::at(
                    path,
                    row.line,
                    cu + 1,
                    format!(
                        "unit `{unit}` does not fit {canonical}: expected `{want}` ({} error)",
                        if el.is_angular() { "angular" } else { "linear" }
                    ),
                ));
            }
            elements.push(ElementStat {
                element: canonical,
                mean,
                std,
                unit: want.to_string(),
            });
        }
        Ok(ErrorStatistics { elements })
    }

    /// Statistics of an error set over the machine's travels: each element's function sampled
    /// at `samples` evenly spaced positions of its axis; mean and (population) std of the values.
    /// This is how the simulated machine's statistics are made, and what a user gets from an
    /// identified error set.
    pub fn from_error_set(set: &ErrorSet, machine: &Machine, samples: usize) -> ErrorStatistics {
        let samples = samples.max(2);
        let mut elements = Vec::new();
        for &axis in &machine.axes {
            let [lo, hi] = machine.travel(axis);
            let mut els: Vec<ErrorElement> = mtec_model::motion_elements(axis).to_vec();
            els.extend(mtec_model::location_elements(axis));
            for el in els {
                let Some(_) = set.get(&el) else { continue };
                let vals: Vec<f64> = (0..samples)
                    .map(|k| set.value(&el, lo + (hi - lo) * k as f64 / (samples - 1) as f64))
                    .collect();
                let mean = vals.iter().sum::<f64>() / samples as f64;
                let constant = vals.iter().all(|v| *v == vals[0]);
                let var = if constant {
                    0.0 // a location error (squareness) is one number, not a distribution
                } else {
                    vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / samples as f64
                };
                elements.push(ElementStat {
                    element: el.name(),
                    mean,
                    std: var.sqrt(),
                    unit: el.unit().to_string(),
                });
            }
        }
        ErrorStatistics { elements }
    }

    /// Statistics of an identified error set, the inputs `sensitivity --stats` reads (what
    /// `identify lines --stats` and a project's `[sensitivity]` stage write): each element's
    /// function over [`IDENTIFIED_SAMPLES`] positions of its travel ([`Self::from_error_set`]),
    /// except that a constant element (a squareness, a location) takes its magnitude |mean| as
    /// its spread (at least 1e-6). It has no spread over the travel, and a spread of zero would
    /// give it no index and allow it a vanishing tolerance (issue 24): the element is as large
    /// as it is, and the sensitivity asks how much that matters.
    pub fn of_identified(set: &ErrorSet, machine: &Machine) -> ErrorStatistics {
        let mut stats = ErrorStatistics::from_error_set(set, machine, IDENTIFIED_SAMPLES);
        for e in &mut stats.elements {
            if e.std == 0.0 {
                e.std = e.mean.abs().max(1e-6);
            }
        }
        stats
    }

    /// The CSV text of [`Self::of_identified`]'s statistics, headed by a comment that says
    /// how they were made.
    pub fn to_identified_csv(&self) -> String {
        self.csv_with(&[format!(
            "statistics of each identified error function over its axis travel (mean, population std of {IDENTIFIED_SAMPLES} evenly spaced positions); a constant element (squareness, location) has no spread over the travel, so its std is its magnitude |value|"
        )])
    }

    /// The CSV text of the statistics.
    pub fn to_csv(&self) -> String {
        self.csv_with(&[])
    }

    fn csv_with(&self, comments: &[String]) -> String {
        let mut w = mtec_io::CsvWriter::commented(comments, ["element", "mean", "std", "unit"]);
        for e in &self.elements {
            w.row([
                e.element.to_string(),
                e.mean.to_string(),
                e.std.to_string(),
                e.unit.to_string(),
            ]);
        }
        w.finish()
    }
}

/// The first-order volumetric error at a set of poses as a [`Model`] of the uncertain elements:
/// outputs [Ex, Ey, Ez, |E|] for each pose in turn (µm).
#[derive(Debug, Clone)]
pub struct VolumetricErrorModel {
    /// Per pose, per input: the Jacobian column [∂Ex, ∂Ey, ∂Ez]/∂e_i.
    coefficients: Vec<Vec<[f64; 3]>>,
    /// Per pose: the error caused by the fixed (std 0) elements at their means.
    offsets: Vec<[f64; 3]>,
}

impl VolumetricErrorModel {
    /// The per-pose Jacobian columns of the inputs.
    pub fn coefficients(&self) -> &[Vec<[f64; 3]>] {
        &self.coefficients
    }
}

impl Model for VolumetricErrorModel {
    fn n_outputs(&self) -> usize {
        4 * self.coefficients.len()
    }
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        for ((cols, off), o) in self
            .coefficients
            .iter()
            .zip(&self.offsets)
            .zip(out.chunks_exact_mut(4))
        {
            // First-order volumetric error E = J·e (linear in the element values).
            let mut e = *off;
            for (c, xi) in cols.iter().zip(x) {
                e[0] += c[0] * xi;
                e[1] += c[1] * xi;
                e[2] += c[2] * xi;
            }
            o[0] = e[0];
            o[1] = e[1];
            o[2] = e[2];
            o[3] = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        }
    }
}

/// The sensitivity problem of a machine: inputs, fixed elements, and the model at the poses.
#[derive(Debug, Clone)]
pub struct ErrorModelProblem {
    pub problem: Problem,
    /// Elements held at their mean (std = 0).
    pub fixed: Vec<String>,
    pub model: VolumetricErrorModel,
    /// Standard deviations of the inputs (element units).
    pub stds: Vec<f64>,
}

impl ErrorModelProblem {
    /// Builds the problem; poses are in the machine's pose order (mm, deg).
    pub fn new(
        machine: &Machine,
        stats: &ErrorStatistics,
        poses: &[Vec<f64>],
    ) -> Result<ErrorModelProblem, SensitivityError> {
        if poses.is_empty() {
            return Err(SensitivityError::Problem("no poses".into()));
        }
        let vm = VolumetricModel::new(machine, &ErrorSet::new("sensitivity"));
        let mut names = Vec::new();
        let mut dists = Vec::new();
        let mut stds = Vec::new();
        let mut fixed = Vec::new();
        let jac: Vec<BTreeMap<String, [f64; 3]>> = poses
            .iter()
            .map(|q| {
                vm.first_order_jacobian(q)
                    .into_iter()
                    .map(|(e, c)| (e.name(), c))
                    .collect()
            })
            .collect();
        for s in &stats.elements {
            if !jac[0].contains_key(&s.element) {
                return Err(SensitivityError::Problem(format!(
                    "element {} is not an error of the machine's chain {}",
                    s.element, machine.chain.text
                )));
            }
            if s.std > 0.0 {
                names.push(s.element.clone());
                dists.push(Distribution::Normal {
                    mean: s.mean,
                    std: s.std,
                });
                stds.push(s.std);
            } else {
                fixed.push(s.element.clone());
            }
        }
        let problem = Problem::new(names, dists)?;
        let coefficients = jac
            .iter()
            .map(|j| problem.names.iter().map(|n| j[n]).collect())
            .collect();
        let offsets = jac
            .iter()
            .map(|j| {
                let mut o = [0.0; 3];
                for s in stats.elements.iter().filter(|s| s.std == 0.0) {
                    let c = j[&s.element];
                    for k in 0..3 {
                        o[k] += c[k] * s.mean;
                    }
                }
                o
            })
            .collect();
        Ok(ErrorModelProblem {
            problem,
            fixed,
            model: VolumetricErrorModel {
                coefficients,
                offsets,
            },
            stds,
        })
    }
}

/// Which method, with its design size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    Efast(EfastSettings),
    /// Sobol with N base points.
    Sobol {
        n: usize,
        bootstrap: Bootstrap,
    },
    Morris(MorrisSettings),
}

impl Method {
    /// Name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Efast(_) => "efast",
            Method::Sobol { .. } => "sobol",
            Method::Morris(_) => "morris",
        }
    }
}

/// Indices of one output channel, aggregated over the poses.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelIndices {
    pub output: String,
    #[serde(rename = "S1", skip_serializing_if = "Option::is_none")]
    pub s1: Option<Vec<f64>>,
    #[serde(rename = "ST", skip_serializing_if = "Option::is_none")]
    pub st: Option<Vec<f64>>,
    #[serde(rename = "S1_conf", skip_serializing_if = "Option::is_none")]
    pub s1_conf: Option<Vec<f64>>,
    #[serde(rename = "ST_conf", skip_serializing_if = "Option::is_none")]
    pub st_conf: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_star: Option<Vec<f64>>,
    /// Bootstrap half width of μ* (Morris).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_star_conf: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<Vec<f64>>,
    /// Mean over the poses of the output's variance, µm².
    pub variance_um2: f64,
}

/// One ranked element.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ranked {
    pub element: String,
    pub value: f64,
}

/// One row of the tolerance-allocation table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Allocation {
    pub element: String,
    pub unit: String,
    pub current_std: f64,
    /// Allowed std, or `None` when the element does not reach Ex, Ey, Ez (no limit).
    pub allowed_std: Option<f64>,
    /// The axis whose budget binds.
    pub binding_output: Option<String>,
    /// current / allowed: > 1 means the element must be held tighter.
    pub ratio: Option<f64>,
}

/// The tolerance-allocation result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToleranceTable {
    pub target_um: f64,
    pub coverage_factor: f64,
    /// Current k·σ of Ex, Ey, Ez (µm), to compare with the target.
    pub current_expanded_um: [f64; 3],
    pub rows: Vec<Allocation>,
}

/// Everything an error-model sensitivity run reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorModelReport {
    pub method: String,
    pub evaluations: usize,
    pub points: usize,
    pub inputs: Vec<String>,
    pub fixed: Vec<String>,
    pub outputs: Vec<ChannelIndices>,
    /// Key errors: by S1 of |E| (μ* for Morris), largest first.
    pub key_errors: Vec<Ranked>,
    /// Coupled errors: ST − S1 of |E| ≥ [`COUPLING_THRESHOLD`] (σ for Morris), largest first.
    pub coupled_errors: Vec<Ranked>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<ToleranceTable>,
}

/// Threshold of ST − S1 above which an element is listed as coupled. EFAST with normal inputs
/// and M = 4 shows ST ≈ 0.01–0.02 for elements that have no effect at all (harmonic leakage, see
/// `efast`), so the threshold sits above that floor.
pub const COUPLING_THRESHOLD: f64 = 0.03;

/// Runs the method on the problem and aggregates, ranks and allocates tolerances.
pub fn analyze(
    emp: &ErrorModelProblem,
    method: &Method,
    seed: u64,
    target_um: f64,
    coverage_factor: f64,
) -> Result<ErrorModelReport, SensitivityError> {
    let names = &emp.problem.names;
    let d = names.len();
    let n_points = emp.model.coefficients.len();
    // Draw the design and evaluate every output column.
    let (columns, evaluations, morris_design) = match method {
        Method::Efast(s) => {
            let x = efast::sample(&emp.problem, s, seed)?;
            (evaluate(&emp.model, &x), x.n_rows, None)
        }
        Method::Sobol { n, .. } => {
            let x = sobol::sample(&emp.problem, *n, seed)?;
            (evaluate(&emp.model, &x), x.n_rows, None)
        }
        Method::Morris(s) => {
            let design = morris::sample(&emp.problem, s, seed)?;
            let cols = evaluate(&emp.model, &design.samples);
            let rows = design.samples.n_rows;
            (cols, rows, Some(design))
        }
    };
    let is_morris = matches!(method, Method::Morris(_));
    let mut outputs = Vec::new();
    for (k, out_name) in OUTPUTS.iter().enumerate() {
        let mut acc = Aggregate::new(d);
        for p in 0..n_points {
            let y = &columns[4 * p + k];
            let mean = y.iter().sum::<f64>() / y.len() as f64;
            let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64;
            if var.is_nan() || var <= 1e-20 * (1.0 + mean * mean) {
                continue; // weight 0: the output does not vary at this pose
            }
            match method {
                Method::Efast(s) => {
                    let ix = efast::analyze(names, y, s.m, s.resamples, s.confidence)?;
                    let reps = ix.replicates.as_ref();
                    acc.add(
                        var,
                        (&ix.s1, reps.map(|r| &r.s1[..])),
                        (&ix.st, reps.map(|r| &r.st[..])),
                    );
                }
                Method::Sobol { bootstrap, .. } => {
                    // every pose resamples the same base points (`Bootstrap::rows`), so the
                    // replicates aggregate like the estimates
                    let ix = sobol::analyze(names, y, bootstrap)?.indices;
                    let reps = ix.replicates.as_ref();
                    acc.add(
                        var,
                        (&ix.s1, reps.map(|r| &r.s1[..])),
                        (&ix.st, reps.map(|r| &r.st[..])),
                    );
                }
                Method::Morris(s) => {
                    let design = morris_design.as_ref().expect("morris design drawn above");
                    let r = morris::analyze(names, design, y, &s.bootstrap)?;
                    acc.add(
                        var,
                        (&r.mu_star, r.mu_star_replicates.as_deref()),
                        (&r.sigma, None),
                    );
                }
            }
        }
        let (a, b, ca, cb, v) = match method {
            Method::Efast(s) => acc.finish(n_points, s.confidence, replicate_half_widths),
            Method::Sobol { bootstrap, .. } => {
                acc.finish(n_points, bootstrap.confidence, bootstrap_half_widths)
            }
            Method::Morris(s) => {
                acc.finish(n_points, s.bootstrap.confidence, bootstrap_half_widths)
            }
        };
        outputs.push(if is_morris {
            ChannelIndices {
                output: out_name.to_string(),
                s1: None,
                st: None,
                s1_conf: None,
                st_conf: None,
                mu_star: Some(a),
                mu_star_conf: ca,
                sigma: Some(b),
                variance_um2: v,
            }
        } else {
            ChannelIndices {
                output: out_name.to_string(),
                s1: Some(a),
                st: Some(b),
                s1_conf: ca,
                st_conf: cb,
                mu_star: None,
                mu_star_conf: None,
                sigma: None,
                variance_um2: v,
            }
        });
    }
    let total = &outputs[3];
    let (key, coupled) = match (&total.s1, &total.st, &total.mu_star, &total.sigma) {
        (Some(s1), Some(st), _, _) => (
            rank(names, s1, f64::NEG_INFINITY),
            rank(
                names,
                &st.iter().zip(s1).map(|(t, s)| t - s).collect::<Vec<_>>(),
                COUPLING_THRESHOLD,
            ),
        ),
        (_, _, Some(mu), Some(sig)) => (
            rank(names, mu, f64::NEG_INFINITY),
            rank(names, sig, f64::NEG_INFINITY),
        ),
        _ => (Vec::new(), Vec::new()),
    };
    let tolerance = if matches!(method, Method::Morris(_)) {
        None
    } else {
        Some(allocate(emp, &outputs, target_um, coverage_factor)?)
    };
    Ok(ErrorModelReport {
        method: method.name().to_string(),
        evaluations,
        points: n_points,
        inputs: names.clone(),
        fixed: emp.fixed.clone(),
        outputs,
        key_errors: key,
        coupled_errors: coupled,
        tolerance,
    })
}

/// Variance-weighted aggregation of per-pose indices (Gamboa et al. 2014) and of their
/// replicate estimates, which give the aggregate's interval (`interval` module docs).
struct Aggregate {
    a: Vec<f64>,
    b: Vec<f64>,
    reps_a: Option<Vec<Vec<f64>>>,
    reps_b: Option<Vec<Vec<f64>>>,
    weight: f64,
}

/// An index vector with its replicate estimates `[k][i]`, if any.
type WithReplicates<'a> = (&'a [f64], Option<&'a [Vec<f64>]>);

fn add_weighted(acc: &mut Option<Vec<Vec<f64>>>, w: f64, reps: Option<&[Vec<f64>]>) {
    let Some(reps) = reps else { return };
    let sums = acc.get_or_insert_with(|| vec![vec![0.0; reps[0].len()]; reps.len()]);
    for (s, r) in sums.iter_mut().zip(reps) {
        for (si, ri) in s.iter_mut().zip(r) {
            *si += w * ri;
        }
    }
}

impl Aggregate {
    fn new(d: usize) -> Self {
        Aggregate {
            a: vec![0.0; d],
            b: vec![0.0; d],
            reps_a: None,
            reps_b: None,
            weight: 0.0,
        }
    }
    fn add(&mut self, var: f64, a: WithReplicates, b: WithReplicates) {
        for i in 0..a.0.len() {
            self.a[i] += var * a.0[i];
            self.b[i] += var * b.0[i];
        }
        add_weighted(&mut self.reps_a, var, a.1);
        add_weighted(&mut self.reps_b, var, b.1);
        self.weight += var;
    }
    /// Variance-weighted indices (or Morris measures), the half widths of their intervals from
    /// the aggregated replicates (`half_width(replicates, confidence)`), and the mean variance
    /// over the poses.
    #[allow(clippy::type_complexity)]
    fn finish(
        self,
        n_points: usize,
        confidence: f64,
        half_width: fn(&[Vec<f64>], f64) -> Vec<f64>,
    ) -> (Vec<f64>, Vec<f64>, Option<Vec<f64>>, Option<Vec<f64>>, f64) {
        let w = if self.weight > 0.0 { self.weight } else { 1.0 };
        let a = self.a.iter().map(|v| v / w).collect();
        let b = self.b.iter().map(|v| v / w).collect();
        let conf = |reps: Option<Vec<Vec<f64>>>| {
            reps.map(|mut r| {
                r.iter_mut().flatten().for_each(|v| *v /= w);
                half_width(&r, confidence)
            })
        };
        let (ca, cb) = (conf(self.reps_a), conf(self.reps_b));
        (a, b, ca, cb, self.weight / n_points as f64)
    }
}

fn rank(names: &[String], v: &[f64], threshold: f64) -> Vec<Ranked> {
    let mut r: Vec<Ranked> = names
        .iter()
        .zip(v)
        .filter(|(_, &x)| x >= threshold)
        .map(|(n, &x)| Ranked {
            element: n.clone(),
            value: x,
        })
        .collect();
    r.sort_by(|a, b| b.value.total_cmp(&a.value));
    r
}

/// Equal-effects tolerance allocation from the indices of Ex, Ey, Ez (see the module docs).
pub fn allocate(
    emp: &ErrorModelProblem,
    outputs: &[ChannelIndices],
    target_um: f64,
    coverage_factor: f64,
) -> Result<ToleranceTable, SensitivityError> {
    // a target of a metre is no machine-tool accuracy (the error bound of the readers), and a
    // coverage factor beyond 10 is no confidence level (k = 2 for 95 %, 3 for 99.7 %)
    if !(target_um > 0.0 && target_um < mtec_io::plausible::MAX_ERROR_UM) {
        return Err(SensitivityError::Settings(format!(
            "target accuracy {target_um:e} µm must be a positive number below {:e} µm",
            mtec_io::plausible::MAX_ERROR_UM
        )));
    }
    if !(coverage_factor > 0.0 && coverage_factor <= 10.0) {
        return Err(SensitivityError::Settings(format!(
            "coverage factor {coverage_factor:e} must be a positive number of at most 10"
        )));
    }
    let sigma_target = target_um / coverage_factor;
    let d = emp.problem.dim();
    let mut allowed: Vec<Option<(f64, usize)>> = vec![None; d];
    let mut expanded = [0.0; 3];
    for (a, out) in outputs.iter().take(3).enumerate() {
        let st = out.st.as_ref().ok_or_else(|| {
            SensitivityError::Settings("tolerance allocation needs total indices".into())
        })?;
        let v = out.variance_um2;
        expanded[a] = coverage_factor * v.sqrt();
        // c_{i,a} = √(ST_{i,a}·V_a)/σ_i
        let c: Vec<f64> = (0..d)
            .map(|i| (st[i].max(0.0) * v).sqrt() / emp.stds[i])
            .collect();
        let c_max = c.iter().cloned().fold(0.0, f64::max);
        // Elements whose share is below 1e-6 of the largest do not reach this output.
        let active: Vec<usize> = (0..d)
            .filter(|&i| c[i] > 1e-3 * c_max && c[i] > 0.0)
            .collect();
        let n = active.len() as f64;
        for &i in &active {
            // σ_i,a = σ_T / (√n_a · c_{i,a})
            let s = sigma_target / (n.sqrt() * c[i]);
            if allowed[i].map_or(true, |(cur, _)| s < cur) {
                allowed[i] = Some((s, a));
            }
        }
    }
    let unit = |name: &str| {
        ErrorElement::parse(name)
            .map(|e| e.unit().to_string())
            .unwrap_or_default()
    };
    let rows = (0..d)
        .map(|i| Allocation {
            element: emp.problem.names[i].clone(),
            unit: unit(&emp.problem.names[i]),
            current_std: emp.stds[i],
            allowed_std: allowed[i].map(|a| a.0),
            binding_output: allowed[i].map(|a| OUTPUTS[a.1].to_string()),
            ratio: allowed[i].map(|a| emp.stds[i] / a.0),
        })
        .collect();
    Ok(ToleranceTable {
        target_um,
        coverage_factor,
        current_expanded_um: expanded,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mtec_model::ErrorFunction;

    /// A squareness is constant over the travel: its spread is its magnitude, not 0 or 1e-6; a
    /// varying element keeps its population std over the travel.
    #[test]
    fn identified_statistics_spread_a_constant_element_by_its_magnitude() {
        let m = Machine::vmc_xyfz(100.0);
        let mut set = ErrorSet::new("test");
        let ec0y = ErrorElement::parse("EC0Y").unwrap();
        let eb0z = ErrorElement::parse("EB0Z").unwrap();
        let exx = ErrorElement::parse("EXX").unwrap();
        set.insert(ec0y, ErrorFunction::constant(-19.88));
        set.insert(eb0z, ErrorFunction::constant(0.0));
        // EXX = 6 q/600 µm over X's travel [0, 600]: 101 values 0, 0.06, ..., 6; mean 3,
        // population variance (6/100)² · Σ(k − 50)² / 101 = 0.0036 · 85850 / 101
        set.insert(exx, ErrorFunction::polynomial(vec![0.0, 0.01]));
        let stats = ErrorStatistics::of_identified(&set, &m);
        let get = |n: &str| {
            stats
                .elements
                .iter()
                .find(|e| e.element == n)
                .unwrap()
                .clone()
        };
        let s = get("EC0Y");
        // the mean of 101 equal values, to the rounding of their sum
        assert!(
            (s.mean + 19.88).abs() < 1e-12 && s.std == s.mean.abs(),
            "{s:?}"
        );
        assert_eq!(s.unit, "urad");
        assert_eq!(get("EB0Z").std, 1e-6);
        let s = get("EXX");
        assert!((s.mean - 3.0).abs() < 1e-12, "{}", s.mean);
        let want = (0.0036 * 85850.0 / 101.0f64).sqrt();
        assert!((s.std - want).abs() < 1e-12, "{} vs {want}", s.std);
        assert_eq!(stats.elements.len(), 3);
        let csv = stats.to_identified_csv();
        assert!(csv.starts_with("# statistics") && csv.contains("\nelement,mean,std,unit\n"));
    }
}
