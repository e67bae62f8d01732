//! `mtec sensitivity`: global sensitivity of the volumetric error to the error elements
//! (EFAST, Sobol or Morris), or of a standard test function.

use crate::error::CliError;
use crate::inputs::{read_machine, read_poses};
use mtec_io::InputError;
use mtec_sensitivity::efast::EfastSettings;
use mtec_sensitivity::error_model::{
    self, ErrorModelProblem, ErrorModelReport, ErrorStatistics, Method,
};
use mtec_sensitivity::morris::MorrisSettings;
use mtec_sensitivity::sobol::Bootstrap;
use mtec_sensitivity::{efast, evaluate, morris, sobol, testfns};
use std::fmt::Write;
use std::path::PathBuf;

const LONG: &str = "\
Which error elements drive the volumetric error: S1 (key errors) and ST (coupling) of every
element for Ex, Ey, Ez and |E|, and how tightly each must be held for a target accuracy.

Inputs are the geometric error elements with normal distributions from an error-statistics CSV
(docs/formats.md, \"Error statistics CSV\"), one row per element, units um (translations,
squareness excluded) or urad (rotations and squareness):

  element,mean,std,unit
  EXX,4.1,3.2,um
  ECX,-2.0,6.5,urad

Elements with std 0 stay fixed at their mean. The model is the machine's first-order
volumetric error at the pose given by --at (machine axis order, mm/deg) or at every point of
--points (columns x_mm, y_mm, z_mm, ...), where indices are aggregated over the points with
variance weights. Methods: efast (the source method: --samples points per search curve,
interference factor --interference), sobol (--samples base points, bootstrap intervals),
morris (--samples trajectories; mu* and sigma instead of S1 and ST).

The report ranks key errors (S1 of |E|), coupled errors (ST - S1 of |E| >= 0.03), and
allocates tolerances: each element's allowed std so that Ex, Ey, Ez stay within --target-um at
coverage factor --coverage (equal-effects rule).

--function ishigami|sobol-g|linear analyses a standard test function instead and prints its
analytic indices beside the estimates.";

const EXAMPLES: &str = crate::help::examples!(
    "  # EFAST on the Ishigami function: the estimates beside the exact indices
  $ mtec sensitivity --function ishigami --method efast --samples 2000
  # a machining centre, and the spread of five of its error elements
  $ mtec simulate vmc-9line --out d
  $ printf '%s\\n' element,mean,std,unit EXX,2,1.5,um EYY,0,2,um EZZ,1,1,um \\
      EBX,0,4,urad EC0Y,10,5,urad > stats.csv
  # which drive the error at X300 Y400 Z150, and their tolerances for 10 um
  $ mtec sensitivity --machine d/machine.toml --stats stats.csv \\
      --at 300,400,150 --target-um 10"
);

/// Arguments of `mtec sensitivity`.
#[derive(clap::Args, Debug)]
#[command(
    about = "Global sensitivity (EFAST, Sobol, Morris) of the volumetric error to the error elements",
    long_about = LONG,
    after_long_help = EXAMPLES
)]
pub struct Args {
    /// Machine description (TOML).
    #[arg(long, requires = "stats", conflicts_with = "function")]
    pub machine: Option<PathBuf>,
    /// Error statistics (CSV: element,mean,std,unit).
    #[arg(long, requires = "machine")]
    pub stats: Option<PathBuf>,
    /// A standard test function instead of a machine: ishigami, sobol-g, linear.
    #[arg(long)]
    pub function: Option<String>,
    /// Method.
    #[arg(long, value_enum, default_value = "efast")]
    pub method: MethodArg,
    /// Design size: EFAST points per curve (default 1200), Sobol base points (1024), Morris
    /// trajectories (100).
    #[arg(long)]
    pub samples: Option<usize>,
    /// EFAST interference factor M.
    #[arg(long, default_value_t = 4)]
    pub interference: usize,
    /// EFAST repetitions of the search curves with new random phases.
    #[arg(long, default_value_t = 1)]
    pub resamples: usize,
    /// Morris grid levels (even).
    #[arg(long, default_value_t = 4)]
    pub levels: usize,
    /// Sobol bootstrap replicates.
    #[arg(long, default_value_t = 100)]
    pub bootstrap: usize,
    /// Random seed of the design.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// One pose: comma-separated axis positions in the machine's axis order (mm, deg).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        conflicts_with = "points"
    )]
    pub at: Option<Vec<f64>>,
    /// Several poses (CSV with x_mm, y_mm, z_mm, ... columns); indices are aggregated.
    #[arg(long)]
    pub points: Option<PathBuf>,
    /// Target accuracy of Ex, Ey, Ez for the tolerance allocation, µm.
    #[arg(long, default_value_t = 25.0)]
    pub target_um: f64,
    /// Coverage factor k: the target bounds k·σ of each axis.
    #[arg(long, default_value_t = 2.0)]
    pub coverage: f64,
    /// Print JSON ("format": "mtec.sensitivity/1").
    #[arg(long)]
    pub json: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum MethodArg {
    Efast,
    Sobol,
    Morris,
}

fn method(args: &Args) -> Method {
    match args.method {
        MethodArg::Efast => Method::Efast(EfastSettings {
            n: args.samples.unwrap_or(1200),
            m: args.interference,
            resamples: args.resamples,
        }),
        MethodArg::Sobol => Method::Sobol {
            n: args.samples.unwrap_or(1024),
            bootstrap: Bootstrap {
                resamples: args.bootstrap,
                confidence: 0.95,
                seed: args.seed,
            },
        },
        MethodArg::Morris => Method::Morris(MorrisSettings {
            trajectories: args.samples.unwrap_or(100),
            levels: args.levels,
        }),
    }
}

/// Writes to stdout; a closed pipe (`| head`) ends the output quietly instead of panicking.
fn emit(text: &str) -> Result<(), CliError> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.map_err(CliError::from),
    }
}

fn to_json(v: &serde_json::Value) -> Result<String, CliError> {
    serde_json::to_string_pretty(v).map_err(|e| CliError::Internal(e.into()))
}

pub fn run(args: Args) -> Result<(), CliError> {
    if let Some(name) = args.function.clone() {
        return run_function(&args, &name);
    }
    let (Some(machine_path), Some(stats_path)) = (args.machine.clone(), args.stats.clone()) else {
        return Err(CliError::usage(
            "give --machine M.toml --stats STATS.csv (or --function ishigami|sobol-g|linear)",
        ));
    };
    let machine = read_machine(&machine_path)?;
    let stats = ErrorStatistics::read(&stats_path)?;
    let poses = match (&args.at, &args.points) {
        (Some(at), None) => {
            if at.len() != machine.axes.len() {
                return Err(CliError::usage(format!(
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
                    return Err(CliError::usage(format!(
                        "--at: {a} = {v} is outside the travel [{lo}, {hi}]"
                    )));
                }
            }
            vec![at.clone()]
        }
        (None, Some(p)) => read_poses(p, &machine)?,
        _ => {
            return Err(CliError::usage(
                "give the pose with --at x,y,z or several with --points P.csv",
            ))
        }
    };
    let emp = ErrorModelProblem::new(&machine, &stats, &poses)
        .map_err(|e| InputError::file(&stats_path, e.to_string()))?;
    let report = error_model::analyze(
        &emp,
        &method(&args),
        args.seed,
        args.target_um,
        args.coverage,
    )
    .map_err(|e| CliError::usage(e.to_string()))?;
    if args.json {
        let mut v = serde_json::to_value(&report).map_err(|e| CliError::Internal(e.into()))?;
        let obj = v.as_object_mut().expect("report is an object");
        obj.insert("format".into(), "mtec.sensitivity/1".into());
        obj.insert("machine".into(), machine.name.clone().into());
        if poses.len() == 1 {
            obj.insert("at".into(), serde_json::json!(poses[0]));
            // The linear model itself, so that the numbers can be checked elsewhere.
            let coeffs: serde_json::Map<String, serde_json::Value> = emp
                .problem
                .names
                .iter()
                .zip(&emp.model.coefficients()[0])
                .map(|(n, c)| (n.clone(), serde_json::json!(c)))
                .collect();
            obj.insert("coefficients_um_per_unit".into(), coeffs.into());
        }
        emit(&(to_json(&v)? + "\n"))?;
    } else {
        emit(&text_report(&report))?;
    }
    Ok(())
}

fn text_report(r: &ErrorModelReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} sensitivity of the first-order volumetric error: {} inputs, {} point(s), {} model evaluations",
        r.method.to_uppercase(),
        r.inputs.len(),
        r.points,
        r.evaluations
    );
    if !r.fixed.is_empty() {
        let _ = writeln!(s, "fixed at their mean (std 0): {}", r.fixed.join(" "));
    }
    let morris = r.outputs[0].mu_star.is_some();
    let _ = write!(s, "\n{:<8}", "element");
    for o in &r.outputs {
        if morris {
            let _ = write!(
                s,
                " {:>9} {:>9}",
                format!("mu*_{}", o.output),
                format!("sig_{}", o.output)
            );
        } else {
            let _ = write!(
                s,
                " {:>8} {:>8}",
                format!("S1_{}", o.output),
                format!("ST_{}", o.output)
            );
        }
    }
    s.push('\n');
    for (i, n) in r.inputs.iter().enumerate() {
        let _ = write!(s, "{n:<8}");
        for o in &r.outputs {
            let (a, b) = if morris {
                (o.mu_star.as_ref().unwrap()[i], o.sigma.as_ref().unwrap()[i])
            } else {
                (o.s1.as_ref().unwrap()[i], o.st.as_ref().unwrap()[i])
            };
            if morris {
                let _ = write!(s, " {a:>9.3} {b:>9.3}");
            } else {
                let _ = write!(s, " {a:>8.4} {b:>8.4}");
            }
        }
        s.push('\n');
    }
    let what = if morris { "mu* of |E|" } else { "S1 of |E|" };
    let _ = writeln!(s, "\nkey errors ({what}):");
    for k in r.key_errors.iter().take(8) {
        let _ = writeln!(s, "  {:<6} {:.4}", k.element, k.value);
    }
    let what = if morris {
        "sigma of |E|"
    } else {
        "ST - S1 of |E| >= 0.03"
    };
    let _ = writeln!(s, "coupled errors ({what}):");
    if r.coupled_errors.is_empty() {
        let _ = writeln!(s, "  none");
    }
    for k in r.coupled_errors.iter().take(8) {
        let _ = writeln!(s, "  {:<6} {:.4}", k.element, k.value);
    }
    if let Some(t) = &r.tolerance {
        let _ = writeln!(
            s,
            "\ntolerance allocation: target {} um at k = {} (now k*sigma of Ex, Ey, Ez = {:.2}, {:.2}, {:.2} um)",
            t.target_um, t.coverage_factor, t.current_expanded_um[0], t.current_expanded_um[1], t.current_expanded_um[2]
        );
        let _ = writeln!(
            s,
            "{:<8} {:>5} {:>12} {:>12} {:>8} {:>8}",
            "element", "unit", "std now", "std allowed", "binds", "ratio"
        );
        for row in &t.rows {
            match (row.allowed_std, &row.binding_output, row.ratio) {
                (Some(a), Some(b), Some(q)) => {
                    let _ = writeln!(
                        s,
                        "{:<8} {:>5} {:>12.3} {:>12.3} {:>8} {:>8.3}{}",
                        row.element,
                        row.unit,
                        row.current_std,
                        a,
                        b,
                        q,
                        if q > 1.0 { "  tighten" } else { "" }
                    );
                }
                _ => {
                    let _ = writeln!(
                        s,
                        "{:<8} {:>5} {:>12.3} {:>12} {:>8} {:>8}",
                        row.element, row.unit, row.current_std, "no limit", "-", "-"
                    );
                }
            }
        }
    }
    s
}

fn run_function(args: &Args, name: &str) -> Result<(), CliError> {
    let f = testfns::by_name(name).ok_or_else(|| {
        CliError::usage(format!(
            "unknown test function `{name}`; choose one of: {}",
            testfns::NAMES.join(", ")
        ))
    })?;
    let problem = f.problem();
    let bad = |e: mtec_sensitivity::SensitivityError| CliError::usage(e.to_string());
    let mut out = serde_json::Map::new();
    out.insert("format".into(), "mtec.sensitivity/1".into());
    out.insert("function".into(), name.into());
    out.insert("inputs".into(), serde_json::json!(problem.names));
    match method(args) {
        Method::Efast(s) => {
            let x = efast::sample(&problem, &s, args.seed).map_err(bad)?;
            let y = evaluate(f.as_ref(), &x).remove(0);
            let ix = efast::analyze(&problem.names, &y, s.m, s.resamples).map_err(bad)?;
            out.insert("method".into(), "efast".into());
            out.insert("evaluations".into(), x.n_rows.into());
            out.insert("S1".into(), serde_json::json!(ix.s1));
            out.insert("ST".into(), serde_json::json!(ix.st));
            if let (Some(a), Some(b)) = (ix.s1_conf, ix.st_conf) {
                out.insert("S1_conf".into(), serde_json::json!(a));
                out.insert("ST_conf".into(), serde_json::json!(b));
            }
        }
        Method::Sobol { n, bootstrap } => {
            let x = sobol::sample(&problem, n, args.seed).map_err(bad)?;
            let y = evaluate(f.as_ref(), &x).remove(0);
            let r = sobol::analyze(&problem.names, &y, &bootstrap).map_err(bad)?;
            out.insert("method".into(), "sobol".into());
            out.insert("evaluations".into(), x.n_rows.into());
            out.insert("S1".into(), serde_json::json!(r.indices.s1));
            out.insert("ST".into(), serde_json::json!(r.indices.st));
            if let (Some(a), Some(b)) = (r.indices.s1_conf, r.indices.st_conf) {
                out.insert("S1_conf".into(), serde_json::json!(a));
                out.insert("ST_conf".into(), serde_json::json!(b));
            }
        }
        Method::Morris(s) => {
            let d = morris::sample(&problem, &s, args.seed).map_err(bad)?;
            let y = evaluate(f.as_ref(), &d.samples).remove(0);
            let r = morris::analyze(&problem.names, &d, &y).map_err(bad)?;
            out.insert("method".into(), "morris".into());
            out.insert("evaluations".into(), d.samples.n_rows.into());
            out.insert("mu".into(), serde_json::json!(r.mu));
            out.insert("mu_star".into(), serde_json::json!(r.mu_star));
            out.insert("sigma".into(), serde_json::json!(r.sigma));
        }
    }
    out.insert(
        "analytic".into(),
        serde_json::json!({ "S1": f.analytic_s1(), "ST": f.analytic_st() }),
    );
    if args.json {
        emit(&(to_json(&serde_json::Value::Object(out))? + "\n"))?;
        return Ok(());
    }
    let mut s = format!(
        "{} of the {name} function ({} model evaluations)\n",
        out["method"].as_str().unwrap_or("").to_uppercase(),
        out["evaluations"]
    );
    let cols: Vec<&str> = if out.contains_key("S1") {
        vec!["S1", "ST"]
    } else {
        vec!["mu_star", "sigma"]
    };
    let _ = writeln!(
        s,
        "{:<6} {:>10} {:>10} {:>10} {:>10}",
        "input", cols[0], cols[1], "S1 exact", "ST exact"
    );
    let (a1, at) = (f.analytic_s1(), f.analytic_st());
    for (i, n) in problem.names.iter().enumerate() {
        let _ = writeln!(
            s,
            "{n:<6} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
            out[cols[0]][i].as_f64().unwrap_or(f64::NAN),
            out[cols[1]][i].as_f64().unwrap_or(f64::NAN),
            a1[i],
            at[i]
        );
    }
    emit(&s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn args(extra: &[&str]) -> Args {
        let mut v = vec!["mtec-sensitivity"];
        v.extend_from_slice(extra);
        Cli::try_parse_from(v).expect("valid command line").args
    }

    fn files(stats: &str) -> (tempfile::TempDir, String, String) {
        let dir = tempfile::tempdir().unwrap();
        let m = dir.path().join("m.toml");
        std::fs::write(
            &m,
            "chain = \"WXYFZT\"\ntool_offset_mm = [0, 0, 100]\n[axes.X]\ntravel = [0, 600]\n[axes.Y]\ntravel = [0, 800]\n[axes.Z]\ntravel = [0, 300]\n",
        )
        .unwrap();
        let s = dir.path().join("stats.csv");
        std::fs::write(&s, stats).unwrap();
        let (m, s) = (m.display().to_string(), s.display().to_string());
        (dir, m, s)
    }

    #[test]
    fn bad_inputs_are_usage_or_located_input_errors() {
        let good = "element,mean,std,unit\nEXX,1,2,um\nECX,0,5,urad\n";
        let (_d, m, s) = files(good);
        // wrong number of --at values, and a pose outside the travel: usage errors (exit 2)
        let e = run(args(&["--machine", &m, "--stats", &s, "--at", "1,2"])).unwrap_err();
        assert!(
            matches!(e, CliError::Usage(ref t) if t.contains("3 axes")),
            "{e}"
        );
        let e = run(args(&["--machine", &m, "--stats", &s, "--at", "1,2,400"])).unwrap_err();
        assert!(
            matches!(e, CliError::Usage(ref t) if t.contains("outside the travel")),
            "{e}"
        );
        // no pose at all
        let e = run(args(&["--machine", &m, "--stats", &s])).unwrap_err();
        assert!(matches!(e, CliError::Usage(_)), "{e}");
        // a unit that does not fit the element: located at line 3, column 4
        let (_d2, m2, s2) = files("element,mean,std,unit\nEXX,1,2,um\nECX,0,5,um\n");
        let e = run(args(&["--machine", &m2, "--stats", &s2, "--at", "1,2,3"])).unwrap_err();
        match e {
            CliError::Input(i) => assert_eq!((i.line, i.column), (Some(3), Some(4))),
            other => panic!("{other}"),
        }
        // unknown test function
        let e = run(args(&["--function", "rosenbrock"])).unwrap_err();
        assert!(matches!(e, CliError::Usage(_)));
        // a good run succeeds
        run(args(&[
            "--machine",
            &m,
            "--stats",
            &s,
            "--at",
            "100,200,50",
            "--samples",
            "300",
        ]))
        .unwrap();
    }
}
