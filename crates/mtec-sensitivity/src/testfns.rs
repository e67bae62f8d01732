//! Standard test functions with analytic sensitivity indices, shipped next to the methods (as
//! SALib does) and used by the tests, the benchmarks and `mtec sensitivity --function`.

use crate::error_model::Method;
use crate::problem::{evaluate, Model, Problem};
use crate::{efast, fastmath, morris, sobol, Distribution, SensitivityError};
use serde::Serialize;
use std::f64::consts::PI;

/// A test function: its problem, its model, and its exact indices.
pub trait TestFunction: Model {
    /// The inputs and their distributions.
    fn problem(&self) -> Problem;
    /// Exact first-order indices.
    fn analytic_s1(&self) -> Vec<f64>;
    /// Exact total indices.
    fn analytic_st(&self) -> Vec<f64>;
}

fn names(prefix: &str, d: usize) -> Vec<String> {
    (1..=d).map(|i| format!("{prefix}{i}")).collect()
}

/// Ishigami & Homma (1990): f = sin x1 + a sin² x2 + b x3⁴ sin x1, xᵢ ~ U(−π, π).
#[derive(Debug, Clone, Copy)]
pub struct Ishigami {
    pub a: f64,
    pub b: f64,
}

impl Default for Ishigami {
    /// The usual a = 7, b = 0.1.
    fn default() -> Self {
        Ishigami { a: 7.0, b: 0.1 }
    }
}

impl Ishigami {
    /// Partial variances (Sobol & Levitan 1999): V, V1, V2, V13.
    fn variances(&self) -> (f64, f64, f64, f64) {
        let (a, b) = (self.a, self.b);
        let pi4 = PI.powi(4);
        let pi8 = PI.powi(8);
        let v1 = 0.5 * (1.0 + b * pi4 / 5.0).powi(2);
        let v2 = a * a / 8.0;
        let v13 = b * b * pi8 * (1.0 / 18.0 - 1.0 / 50.0);
        (v1 + v2 + v13, v1, v2, v13)
    }
}

impl Model for Ishigami {
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        let (s1, s2) = (fastmath::sin(x[0]), fastmath::sin(x[1]));
        out[0] = s1 + self.a * s2.powi(2) + self.b * x[2].powi(4) * s1;
    }

    /// The same values as `evaluate`, with the sines of a block of rows computed in one
    /// vectorised loop (`fastmath`).
    fn evaluate_rows(&self, xs: &[f64], dim: usize, out: &mut [f64]) {
        const BLOCK: usize = 64;
        let (mut x1, mut x2) = ([0.0; BLOCK], [0.0; BLOCK]);
        let (mut s1, mut s2) = ([0.0; BLOCK], [0.0; BLOCK]);
        for (xs, out) in xs.chunks(BLOCK * dim).zip(out.chunks_mut(BLOCK)) {
            let b = out.len();
            for (i, x) in xs.chunks_exact(dim).enumerate() {
                x1[i] = x[0];
                x2[i] = x[1];
            }
            fastmath::sin_slice(&x1[..b], &mut s1[..b]);
            fastmath::sin_slice(&x2[..b], &mut s2[..b]);
            for (i, (o, x)) in out.iter_mut().zip(xs.chunks_exact(dim)).enumerate() {
                *o = s1[i] + self.a * s2[i].powi(2) + self.b * x[2].powi(4) * s1[i];
            }
        }
    }
}

impl TestFunction for Ishigami {
    fn problem(&self) -> Problem {
        let u = Distribution::Uniform { low: -PI, high: PI };
        Problem::new(names("x", 3), vec![u; 3]).expect("valid by construction")
    }
    fn analytic_s1(&self) -> Vec<f64> {
        let (v, v1, v2, _) = self.variances();
        vec![v1 / v, v2 / v, 0.0]
    }
    fn analytic_st(&self) -> Vec<f64> {
        let (v, v1, v2, v13) = self.variances();
        vec![(v1 + v13) / v, v2 / v, v13 / v]
    }
}

/// Sobol's G-function: f = Πᵢ (|4xᵢ − 2| + aᵢ)/(1 + aᵢ), xᵢ ~ U(0, 1); small aᵢ = important.
#[derive(Debug, Clone)]
pub struct SobolG {
    pub a: Vec<f64>,
}

impl Default for SobolG {
    /// The 8-input set of Saltelli & Sobol (1995): a = (0, 1, 4.5, 9, 99, 99, 99, 99).
    fn default() -> Self {
        SobolG {
            a: vec![0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0],
        }
    }
}

impl SobolG {
    /// V_i = 1 / (3 (1 + a_i)²).
    fn partial(&self) -> Vec<f64> {
        self.a
            .iter()
            .map(|a| 1.0 / (3.0 * (1.0 + a).powi(2)))
            .collect()
    }
}

impl Model for SobolG {
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        out[0] = x
            .iter()
            .zip(&self.a)
            .map(|(x, a)| ((4.0 * x - 2.0).abs() + a) / (1.0 + a))
            .product();
    }
}

impl TestFunction for SobolG {
    fn problem(&self) -> Problem {
        let u = Distribution::Uniform {
            low: 0.0,
            high: 1.0,
        };
        Problem::new(names("x", self.a.len()), vec![u; self.a.len()])
            .expect("valid by construction")
    }
    fn analytic_s1(&self) -> Vec<f64> {
        let vi = self.partial();
        let v = vi.iter().map(|v| 1.0 + v).product::<f64>() - 1.0;
        vi.iter().map(|x| x / v).collect()
    }
    fn analytic_st(&self) -> Vec<f64> {
        let vi = self.partial();
        let all = vi.iter().map(|v| 1.0 + v).product::<f64>();
        let v = all - 1.0;
        // V_Ti = V_i Π_{j≠i} (1 + V_j)
        vi.iter().map(|x| x * all / (1.0 + x) / v).collect()
    }
}

/// A linear model y = Σ cᵢ xᵢ with independent inputs: S1ᵢ = STᵢ = cᵢ² Var xᵢ / Σⱼ cⱼ² Var xⱼ.
#[derive(Debug, Clone)]
pub struct Linear {
    pub coefficients: Vec<f64>,
    pub distributions: Vec<Distribution>,
}

impl Default for Linear {
    /// y = x1 + 2 x2 + 3 x3 with x1 ~ U(0, 1), x2 ~ N(0, 0.5), x3 ~ N(1, 0.1).
    fn default() -> Self {
        Linear {
            coefficients: vec![1.0, 2.0, 3.0],
            distributions: vec![
                Distribution::Uniform {
                    low: 0.0,
                    high: 1.0,
                },
                Distribution::Normal {
                    mean: 0.0,
                    std: 0.5,
                },
                Distribution::Normal {
                    mean: 1.0,
                    std: 0.1,
                },
            ],
        }
    }
}

impl Model for Linear {
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        out[0] = x.iter().zip(&self.coefficients).map(|(x, c)| x * c).sum();
    }
}

impl TestFunction for Linear {
    fn problem(&self) -> Problem {
        Problem::new(
            names("x", self.coefficients.len()),
            self.distributions.clone(),
        )
        .expect("valid by construction")
    }
    fn analytic_s1(&self) -> Vec<f64> {
        let parts: Vec<f64> = self
            .coefficients
            .iter()
            .zip(&self.distributions)
            .map(|(c, d)| c * c * d.variance())
            .collect();
        let v: f64 = parts.iter().sum();
        parts.iter().map(|p| p / v).collect()
    }
    fn analytic_st(&self) -> Vec<f64> {
        self.analytic_s1()
    }
}

/// A test function by name: `ishigami`, `sobol-g`, `linear`.
pub fn by_name(name: &str) -> Option<Box<dyn TestFunction>> {
    match name {
        "ishigami" => Some(Box::new(Ishigami::default())),
        "sobol-g" | "g-function" => Some(Box::new(SobolG::default())),
        "linear" => Some(Box::new(Linear::default())),
        _ => None,
    }
}

/// Names accepted by [`by_name`].
pub const NAMES: [&str; 3] = ["ishigami", "sobol-g", "linear"];

/// The indices of a test function estimated by one method (`mtec sensitivity --function`):
/// S1 and ST (with intervals when the method gives them) for EFAST and Sobol, μ, μ* and σ for
/// Morris, one entry per input of the function's problem.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FunctionIndices {
    /// `efast`, `sobol` or `morris`.
    pub method: String,
    /// Model evaluations of the design.
    pub evaluations: usize,
    #[serde(rename = "S1", skip_serializing_if = "Option::is_none")]
    pub s1: Option<Vec<f64>>,
    #[serde(rename = "ST", skip_serializing_if = "Option::is_none")]
    pub st: Option<Vec<f64>>,
    /// Confidence half-widths of S1 and ST: both or neither.
    #[serde(rename = "S1_conf", skip_serializing_if = "Option::is_none")]
    pub s1_conf: Option<Vec<f64>>,
    #[serde(rename = "ST_conf", skip_serializing_if = "Option::is_none")]
    pub st_conf: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_star: Option<Vec<f64>>,
    /// Bootstrap half width of μ* (Morris).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu_star_conf: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<Vec<f64>>,
}

/// Draws the method's design over the function's problem (seed `seed`), evaluates the function
/// and estimates its indices.
pub fn analyze(
    f: &dyn TestFunction,
    method: &Method,
    seed: u64,
) -> Result<FunctionIndices, SensitivityError> {
    let problem = f.problem();
    let mut r = FunctionIndices {
        method: method.name().to_string(),
        evaluations: 0,
        s1: None,
        st: None,
        s1_conf: None,
        st_conf: None,
        mu: None,
        mu_star: None,
        mu_star_conf: None,
        sigma: None,
    };
    let (s1, st, conf) = match method {
        Method::Efast(s) => {
            let x = efast::sample(&problem, s, seed)?;
            let y = evaluate(f, &x).remove(0);
            let ix = efast::analyze(&problem.names, &y, s.m, s.resamples, s.confidence)?;
            r.evaluations = x.n_rows;
            (ix.s1, ix.st, ix.s1_conf.zip(ix.st_conf))
        }
        Method::Sobol { n, bootstrap } => {
            let x = sobol::sample(&problem, *n, seed)?;
            let y = evaluate(f, &x).remove(0);
            let ix = sobol::analyze(&problem.names, &y, bootstrap)?.indices;
            r.evaluations = x.n_rows;
            (ix.s1, ix.st, ix.s1_conf.zip(ix.st_conf))
        }
        Method::Morris(s) => {
            let d = morris::sample(&problem, s, seed)?;
            let y = evaluate(f, &d.samples).remove(0);
            let ix = morris::analyze(&problem.names, &d, &y, &s.bootstrap)?;
            r.evaluations = d.samples.n_rows;
            r.mu = Some(ix.mu);
            r.mu_star = Some(ix.mu_star);
            r.mu_star_conf = ix.mu_star_conf;
            r.sigma = Some(ix.sigma);
            return Ok(r);
        }
    };
    r.s1 = Some(s1);
    r.st = Some(st);
    if let Some((a, b)) = conf {
        r.s1_conf = Some(a);
        r.st_conf = Some(b);
    }
    Ok(r)
}
