//! Global sensitivity of a machine's volumetric error to its error elements (EFAST, Sobol or
//! Morris, `mtec_sensitivity::error_model`), or of a standard test function
//! (`mtec_sensitivity::testfns`). The job of `mtec sensitivity`.

use crate::inputs::{read_machine, read_poses};
use crate::{Error, Observer, Result};
use mtec_io::InputError;
use mtec_sensitivity::efast::EfastSettings;
use mtec_sensitivity::error_model::{self, ErrorModelProblem, ErrorModelReport, ErrorStatistics};
use mtec_sensitivity::morris::MorrisSettings;
use mtec_sensitivity::sobol::Bootstrap;
use mtec_sensitivity::testfns::{self, FunctionIndices};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::PathBuf;

pub use mtec_sensitivity::error_model::Method;

/// The format tag of the outcome.
pub const FORMAT: &str = "mtec.sensitivity/1";

/// The sensitivity method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MethodKind {
    /// Extended FAST (the source method).
    Efast,
    /// Sobol (Saltelli / Jansen estimators) with bootstrap intervals.
    Sobol,
    /// Morris elementary effects (μ*, σ instead of S1, ST).
    Morris,
}

impl crate::Choice for MethodKind {
    const ALL: &'static [Self] = &[MethodKind::Efast, MethodKind::Sobol, MethodKind::Morris];

    fn name(self) -> &'static str {
        match self {
            MethodKind::Efast => "efast",
            MethodKind::Sobol => "sobol",
            MethodKind::Morris => "morris",
        }
    }
}

impl MethodKind {
    /// `efast`, `sobol` or `morris`.
    pub fn from_name(name: &str) -> Option<MethodKind> {
        match name {
            "efast" => Some(MethodKind::Efast),
            "sobol" => Some(MethodKind::Sobol),
            "morris" => Some(MethodKind::Morris),
            _ => None,
        }
    }
}

/// What to analyse and how.
#[derive(Debug, Clone)]
pub struct Options {
    /// Machine description (TOML); with `stats`.
    pub machine: Option<PathBuf>,
    /// Error statistics (CSV `element,mean,std,unit`; µm or µrad).
    pub stats: Option<PathBuf>,
    /// A standard test function instead of a machine: `ishigami`, `sobol-g`, `linear`.
    pub function: Option<String>,
    /// The method.
    pub method: MethodKind,
    /// Design size: EFAST points per curve (`None`: 1200), Sobol base points (1024), Morris
    /// trajectories (100).
    pub samples: Option<usize>,
    /// EFAST interference factor M.
    pub interference: usize,
    /// EFAST repetitions R of the search curves with new random phases (intervals from their
    /// spread when R ≥ 2; default 10).
    pub resamples: usize,
    /// Morris grid levels (even).
    pub levels: usize,
    /// Bootstrap replicates of the Sobol and Morris intervals (SALib's `num_resamples`, 100;
    /// 0: no intervals).
    pub num_resamples: usize,
    /// Confidence level of every interval (SALib's `conf_level`, 0.95).
    pub conf_level: f64,
    /// Random seed of the design.
    pub seed: u64,
    /// One pose in the machine's axis order (mm, deg).
    pub at: Option<Vec<f64>>,
    /// Several poses (CSV with `x_mm`, `y_mm`, `z_mm`, ... columns); indices are aggregated.
    pub points: Option<PathBuf>,
    /// Instead of `at`/`points`: this many poses drawn by Latin hypercube sampling over the
    /// travels (`--sampling lhs[:N]`, [`parse_sampling`]; seed `seed`); indices are aggregated.
    pub lhs_poses: Option<usize>,
    /// Target accuracy of Ex, Ey, Ez for the tolerance allocation (µm).
    pub target_um: f64,
    /// Coverage factor k: the target bounds k·σ of each axis.
    pub coverage: f64,
}

impl Options {
    /// The defaults of `mtec sensitivity` (EFAST, seed 1, 25 µm at k = 2), no subject yet.
    pub fn new() -> Options {
        Options {
            machine: None,
            stats: None,
            function: None,
            method: MethodKind::Efast,
            samples: None,
            interference: 4,
            resamples: 10,
            levels: 4,
            num_resamples: 100,
            conf_level: 0.95,
            seed: 1,
            at: None,
            points: None,
            lhs_poses: None,
            target_um: 25.0,
            coverage: 2.0,
        }
    }

    /// A machine's error elements from their statistics.
    pub fn machine(machine: impl Into<PathBuf>, stats: impl Into<PathBuf>) -> Options {
        Options {
            machine: Some(machine.into()),
            stats: Some(stats.into()),
            ..Options::new()
        }
    }

    /// A standard test function by name.
    pub fn function(name: impl Into<String>) -> Options {
        Options {
            function: Some(name.into()),
            ..Options::new()
        }
    }

    /// Refuses a method setting given another value than its default to a method that does
    /// not read it (`--levels 6` with EFAST used to run EFAST and say nothing).
    pub fn refuse_unused(&self) -> Result<()> {
        use crate::unused::{refuse_unused, Given};
        let (d, m) = (Options::new(), self.method);
        let o = Given::new;
        let options = [
            o(
                "--interference",
                self.interference != d.interference,
                m == MethodKind::Efast,
                "--method efast",
            ),
            o(
                "--resamples",
                self.resamples != d.resamples,
                m == MethodKind::Efast,
                "--method efast",
            ),
            o(
                "--levels",
                self.levels != d.levels,
                m == MethodKind::Morris,
                "--method morris",
            ),
            o(
                "--num-resamples",
                self.num_resamples != d.num_resamples,
                m != MethodKind::Efast,
                "--method sobol and morris",
            ),
        ];
        refuse_unused(&format!("--method {}", crate::Choice::name(m)), &options)?;
        // a test function has no machine: no pose, no tolerance allocation
        let machine = "a machine (--machine, --stats)";
        let function = self.function.is_none();
        let options = [
            o("--at", self.at.is_some(), function, machine),
            o("--points", self.points.is_some(), function, machine),
            o("--sampling", self.lhs_poses.is_some(), function, machine),
            o(
                "--target-um",
                self.target_um != d.target_um,
                function,
                machine,
            ),
            o("--coverage", self.coverage != d.coverage, function, machine),
        ];
        refuse_unused("--function", &options)
    }

    /// The method with its design settings.
    pub fn method(&self) -> Method {
        let bootstrap = Bootstrap {
            resamples: self.num_resamples,
            confidence: self.conf_level,
            seed: self.seed,
        };
        match self.method {
            MethodKind::Efast => Method::Efast(EfastSettings {
                n: self.samples.unwrap_or(1200),
                m: self.interference,
                resamples: self.resamples,
                confidence: self.conf_level,
            }),
            MethodKind::Sobol => Method::Sobol {
                n: self.samples.unwrap_or(1024),
                bootstrap,
            },
            MethodKind::Morris => Method::Morris(MorrisSettings {
                trajectories: self.samples.unwrap_or(100),
                levels: self.levels,
                bootstrap,
            }),
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options::new()
    }
}

/// The sensitivity of a machine's volumetric error (`mtec.sensitivity/1`).
#[derive(Debug, Clone, Serialize)]
pub struct MachineOutcome {
    /// `mtec.sensitivity/1`.
    pub format: String,
    /// The machine's name.
    pub machine: String,
    /// Confidence level of the `*_conf` half widths (EFAST: R ≥ 2 replicates; Sobol, Morris:
    /// bootstrap).
    pub conf_level: f64,
    /// Indices, key and coupled errors, tolerance allocation.
    #[serde(flatten)]
    pub report: ErrorModelReport,
    /// The pose, when there is one (mm, deg).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<Vec<f64>>,
    /// At one pose, the linear model itself: [∂Ex, ∂Ey, ∂Ez] per input (µm per µm or per µrad),
    /// so that the numbers can be checked elsewhere.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coefficients_um_per_unit: Option<BTreeMap<String, [f64; 3]>>,
}

/// The exact indices of a test function.
#[derive(Debug, Clone, Serialize)]
pub struct Analytic {
    #[serde(rename = "S1")]
    pub s1: Vec<f64>,
    #[serde(rename = "ST")]
    pub st: Vec<f64>,
}

/// The indices of a test function beside its exact ones (`mtec.sensitivity/1`).
#[derive(Debug, Clone, Serialize)]
pub struct FunctionOutcome {
    /// `mtec.sensitivity/1`.
    pub format: String,
    /// The function's name as given.
    pub function: String,
    /// Confidence level of the `*_conf` half widths.
    pub conf_level: f64,
    /// Its inputs.
    pub inputs: Vec<String>,
    /// The estimates.
    #[serde(flatten)]
    pub indices: FunctionIndices,
    /// The exact indices.
    pub analytic: Analytic,
}

/// The result: a machine's or a test function's sensitivity.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Outcome {
    Machine(MachineOutcome),
    Function(FunctionOutcome),
}

impl Outcome {
    /// The outcome as the pretty JSON text `mtec sensitivity --json` prints (keys sorted).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(&serde_json::to_value(self)?)?)
    }
}

/// Analyses the machine (`machine` and `stats`) or the test function (`function`).
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    opts.refuse_unused()?;
    if let Some(name) = &opts.function {
        return function(opts, name).map(Outcome::Function);
    }
    let (Some(machine_path), Some(stats_path)) = (&opts.machine, &opts.stats) else {
        return Err(Error::usage(
            "give --machine M.toml --stats STATS.csv (or --function ishigami|sobol-g|linear)",
        ));
    };
    let machine = read_machine(machine_path)?;
    let stats = ErrorStatistics::read(stats_path)?;
    let poses = match (&opts.at, &opts.points) {
        _ if opts.lhs_poses.is_some() && (opts.at.is_some() || opts.points.is_some()) => {
            return Err(Error::usage(
                "--sampling lhs draws the poses: give it without --at and --points",
            ))
        }
        (None, None) if opts.lhs_poses.is_some() => {
            lhs_poses(&machine, opts.lhs_poses.unwrap_or(LHS_POSES), opts.seed)
        }
        (Some(at), None) => {
            if at.len() != machine.axes.len() {
                return Err(Error::usage(format!(
                    "--at has {} values but the machine has {} axes ({})",
                    at.len(),
                    machine.axes.len(),
                    machine
                        .axes
                        .iter()
                        .map(|a| a.letter().to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            for (v, a) in at.iter().zip(&machine.axes) {
                let [lo, hi] = machine.travel(*a);
                if !(v.is_finite() && *v >= lo && *v <= hi) {
                    return Err(Error::usage(format!(
                        "--at: {a} = {v} is outside the travel [{lo}, {hi}]"
                    )));
                }
            }
            vec![at.clone()]
        }
        (None, Some(p)) => read_poses(p, &machine)?,
        _ => {
            return Err(Error::usage(
                "give the pose with --at x,y,z, several with --points P.csv, or draw them with --sampling lhs",
            ))
        }
    };
    let emp = ErrorModelProblem::new(&machine, &stats, &poses)
        .map_err(|e| InputError::file(stats_path, e.to_string()))?;
    let report = error_model::analyze(
        &emp,
        &opts.method(),
        opts.seed,
        opts.target_um,
        opts.coverage,
    )
    .map_err(|e| Error::usage(e.to_string()))?;
    let one = poses.len() == 1;
    Ok(Outcome::Machine(MachineOutcome {
        format: FORMAT.into(),
        machine: machine.name.clone(),
        conf_level: opts.conf_level,
        report,
        at: one.then(|| poses[0].clone()),
        coefficients_um_per_unit: one.then(|| {
            emp.problem
                .names
                .iter()
                .cloned()
                .zip(emp.model.coefficients()[0].iter().copied())
                .collect()
        }),
    }))
}

/// Poses `--sampling lhs` draws when it gives no count.
pub const LHS_POSES: usize = 64;

/// Most poses `--sampling lhs:N` draws (each is a whole analysis at that pose).
pub const MAX_LHS_POSES: usize = 10_000;

/// The number of poses of `--sampling lhs[:N]` (`lhs` alone: [`LHS_POSES`]).
pub fn parse_sampling(s: &str) -> Result<usize> {
    let bad = || {
        Error::usage(format!(
            "--sampling: `{s}` is not lhs or lhs:N (N poses, 2 to {MAX_LHS_POSES})"
        ))
    };
    match s.split_once(':') {
        None if s == "lhs" => Ok(LHS_POSES),
        Some(("lhs", n)) => n
            .parse()
            .ok()
            .filter(|n| (2..=MAX_LHS_POSES).contains(n))
            .ok_or_else(bad),
        _ => Err(bad()),
    }
}

/// n poses by Latin hypercube sampling over the travels of the machine's axes
/// ([`mtec_sensitivity::lhs`]): each axis has exactly one pose in each of n equal slices of
/// its travel.
pub fn lhs_poses(machine: &mtec_model::Machine, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let travels: Vec<[f64; 2]> = machine.axes.iter().map(|a| machine.travel(*a)).collect();
    mtec_sensitivity::lhs::unit(n, travels.len(), seed)
        .into_iter()
        .map(|u| {
            u.iter()
                .zip(&travels)
                .map(|(u, [lo, hi])| lo + u * (hi - lo))
                .collect()
        })
        .collect()
}

fn function(opts: &Options, name: &str) -> Result<FunctionOutcome> {
    let f = testfns::by_name(name).ok_or_else(|| {
        Error::usage(format!(
            "unknown test function `{name}`; choose one of: {}",
            testfns::NAMES.join(", ")
        ))
    })?;
    let indices = testfns::analyze(f.as_ref(), &opts.method(), opts.seed)
        .map_err(|e| Error::usage(e.to_string()))?;
    Ok(FunctionOutcome {
        format: FORMAT.into(),
        function: name.into(),
        conf_level: opts.conf_level,
        inputs: f.problem().names,
        indices,
        analytic: Analytic {
            s1: f.analytic_s1(),
            st: f.analytic_st(),
        },
    })
}

impl fmt::Display for Outcome {
    fn fmt(&self, o: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Machine(m) => m.fmt(o),
            Outcome::Function(f) => f.fmt(o),
        }
    }
}

impl fmt::Display for MachineOutcome {
    fn fmt(&self, s: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        writeln!(
            s,
            "{} sensitivity of the first-order volumetric error: {} inputs, {} point(s), {} model evaluations",
            r.method.to_uppercase(),
            r.inputs.len(),
            r.points,
            r.evaluations
        )?;
        if !r.fixed.is_empty() {
            writeln!(s, "fixed at their mean (std 0): {}", r.fixed.join(" "))?;
        }
        let morris = r.outputs.first().is_some_and(|o| o.mu_star.is_some());
        write!(s, "\n{:<8}", "element")?;
        for o in &r.outputs {
            if morris {
                write!(
                    s,
                    " {:>9} {:>9}",
                    format!("mu*_{}", o.output),
                    format!("sig_{}", o.output)
                )?;
            } else {
                write!(
                    s,
                    " {:>8} {:>8}",
                    format!("S1_{}", o.output),
                    format!("ST_{}", o.output)
                )?;
            }
        }
        writeln!(s)?;
        let at = |v: &Option<Vec<f64>>, i: usize| v.as_ref().map_or(f64::NAN, |v| v[i]);
        for (i, n) in r.inputs.iter().enumerate() {
            write!(s, "{n:<8}")?;
            for o in &r.outputs {
                if morris {
                    write!(s, " {:>9.3} {:>9.3}", at(&o.mu_star, i), at(&o.sigma, i))?;
                } else {
                    write!(s, " {:>8.4} {:>8.4}", at(&o.s1, i), at(&o.st, i))?;
                }
            }
            writeln!(s)?;
        }
        if let Some(o) = r.outputs.last() {
            let c = o.s1_conf.as_ref().or(o.mu_star_conf.as_ref());
            if let Some(c) = c {
                let max = c.iter().cloned().fold(0.0, f64::max);
                writeln!(
                    s,
                    "{:.0} % confidence half widths up to {max:.4} for {}{} (all in --json: *_conf)",
                    100.0 * self.conf_level,
                    o.output,
                    if r.method == "efast" {
                        ", random-phase spread only"
                    } else {
                        ""
                    }
                )?;
            }
        }
        let what = if morris { "mu* of |E|" } else { "S1 of |E|" };
        writeln!(s, "\nkey errors ({what}):")?;
        for k in r.key_errors.iter().take(8) {
            writeln!(s, "  {:<6} {:.4}", k.element, k.value)?;
        }
        let what = if morris {
            "sigma of |E|"
        } else {
            "ST - S1 of |E| >= 0.03"
        };
        writeln!(s, "coupled errors ({what}):")?;
        if r.coupled_errors.is_empty() {
            writeln!(s, "  none")?;
        }
        for k in r.coupled_errors.iter().take(8) {
            writeln!(s, "  {:<6} {:.4}", k.element, k.value)?;
        }
        if let Some(t) = &r.tolerance {
            writeln!(
                s,
                "\ntolerance allocation: target {} um at k = {} (now k*sigma of Ex, Ey, Ez = {:.2}, {:.2}, {:.2} um)",
                t.target_um, t.coverage_factor, t.current_expanded_um[0], t.current_expanded_um[1], t.current_expanded_um[2]
            )?;
            writeln!(
                s,
                "{:<8} {:>5} {:>12} {:>12} {:>8} {:>8}",
                "element", "unit", "std now", "std allowed", "binds", "ratio"
            )?;
            for row in &t.rows {
                match (row.allowed_std, &row.binding_output, row.ratio) {
                    (Some(a), Some(b), Some(q)) => writeln!(
                        s,
                        "{:<8} {:>5} {:>12.3} {:>12.3} {:>8} {:>8.3}{}",
                        row.element,
                        row.unit,
                        row.current_std,
                        a,
                        b,
                        q,
                        if q > 1.0 { "  tighten" } else { "" }
                    )?,
                    _ => writeln!(
                        s,
                        "{:<8} {:>5} {:>12.3} {:>12} {:>8} {:>8}",
                        row.element, row.unit, row.current_std, "no limit", "-", "-"
                    )?,
                }
            }
        }
        Ok(())
    }
}

impl fmt::Display for FunctionOutcome {
    fn fmt(&self, s: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ix = &self.indices;
        writeln!(
            s,
            "{} of the {} function ({} model evaluations)",
            ix.method.to_uppercase(),
            self.function,
            ix.evaluations
        )?;
        let none = Vec::new();
        let (names, a, b, ca, cb) = if ix.s1.is_some() {
            (["S1", "ST"], &ix.s1, &ix.st, &ix.s1_conf, &ix.st_conf)
        } else {
            (
                ["mu_star", "sigma"],
                &ix.mu_star,
                &ix.sigma,
                &ix.mu_star_conf,
                &None,
            )
        };
        let (a, b) = (a.as_ref().unwrap_or(&none), b.as_ref().unwrap_or(&none));
        let value = |v: &Vec<f64>, i: usize| v.get(i).copied().unwrap_or(f64::NAN);
        // "± half width" after an estimate that has an interval
        let pm = |c: &Option<Vec<f64>>, i: usize| {
            c.as_ref()
                .map_or(String::new(), |c| format!(" ±{:.4}", value(c, i)))
        };
        let w = |c: &Option<Vec<f64>>| if c.is_some() { 18 } else { 10 };
        writeln!(
            s,
            "{:<6} {:>wa$} {:>wb$} {:>10} {:>10}",
            "input",
            names[0],
            names[1],
            "S1 exact",
            "ST exact",
            wa = w(ca),
            wb = w(cb)
        )?;
        for (i, n) in self.inputs.iter().enumerate() {
            writeln!(
                s,
                "{n:<6} {:>wa$} {:>wb$} {:>10.4} {:>10.4}",
                format!("{:.4}{}", value(a, i), pm(ca, i)),
                format!("{:.4}{}", value(b, i), pm(cb, i)),
                value(&self.analytic.s1, i),
                value(&self.analytic.st, i),
                wa = w(ca),
                wb = w(cb)
            )?;
        }
        if ca.is_some() {
            writeln!(
                s,
                "±: {:.0} % confidence half widths{}",
                100.0 * self.conf_level,
                if ix.method == "efast" {
                    " of the random-phase repetitions (EFAST's interference bias is not in them)"
                } else {
                    ""
                }
            )?;
        }
        Ok(())
    }
}
