//! The stages of a project run: each runs one job of `crate::ops` in-process, saves its
//! result as the command's `--json` prints it, and turns it into a report section; the job's
//! warnings go to the run's observer and are noted in the section.

use super::pipeline::{s, Pipeline};
use super::spec::{
    BallbarStage, CompensationStage, LinesStage, MapStage, SensitivityStage, ThermalStage,
};
use crate::ops;
use crate::Collect;
use crate::Error;
use mtec_comp::kinematic::KinematicFile;
use mtec_io::CsvWriter;
use mtec_measure::circular::Diagnostics;
use mtec_measure::iso230_2::TargetStats;
use mtec_measure::positioning::PositioningData;
use mtec_report::{bar_chart_with_errors, line_chart, scatter_chart, Section, Series};
use mtec_sensitivity::error_model::ErrorStatistics;
use mtec_thermal::model_file::SplitBy;
use mtec_thermal::select::RidgeTrace;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A JSON value as report text (numbers rounded to a readable precision).
pub fn fmt_value(v: &Value) -> String {
    fmt(v)
}

fn fmt(v: &Value) -> String {
    match v {
        Value::Number(n) => match n.as_f64() {
            Some(x) if x.fract() == 0.0 && x.abs() < 1e9 => format!("{x:.0}"),
            Some(x) if x.abs() >= 1e4 || (x != 0.0 && x.abs() < 1e-3) => format!("{x:.4e}"),
            Some(x) => format!("{x:.3}"),
            None => n.to_string(),
        },
        Value::String(s) => s.clone(),
        Value::Bool(b) => b.to_string(),
        Value::Null => "—".into(),
        Value::Array(a) if a.iter().all(|x| !x.is_object() && !x.is_array()) && a.len() <= 12 => {
            a.iter().map(fmt).collect::<Vec<_>>().join(", ")
        }
        // a long list of numbers: its range (the whole list is in the stage's JSON file)
        Value::Array(a) if a.iter().all(Value::is_number) => {
            let xs: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
            let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            format!(
                "{} values from {} to {}",
                a.len(),
                fmt(&serde_json::json!(lo)),
                fmt(&serde_json::json!(hi))
            )
        }
        Value::Array(a) => format!("{} entries (in the JSON file)", a.len()),
        // a small record inline: `label: value; …`
        Value::Object(o) => o
            .iter()
            .map(|(k, x)| format!("{}: {}", super::labels::label(k), fmt(x)))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

/// Puts a command's JSON result into a section: its scalar values as a table, each array of
/// records (≤ 60 rows) as a table, one level of nested objects likewise.
pub fn json_tables(sec: &mut Section, v: &Value, depth: usize) {
    let Some(obj) = v.as_object() else { return };
    let scalars: Vec<Vec<String>> = obj
        .iter()
        .filter(|(k, x)| {
            *k != "format"
                && !x.is_object()
                && !(x.is_array()
                    && x.as_array()
                        .is_some_and(|a| a.iter().any(|e| e.is_object())))
        })
        .map(|(k, x)| vec![super::labels::label(k), fmt(x)])
        .collect();
    if !scalars.is_empty() {
        sec.table(&["quantity", "value"], scalars);
    }
    for (k, x) in obj {
        match x {
            Value::Array(a) if !a.is_empty() && a.iter().all(|e| e.is_object()) => {
                if a.len() > 60 {
                    sec.text(format!(
                        "{}: {} records (in the stage's JSON file).",
                        super::labels::label(k),
                        a.len()
                    ));
                    continue;
                }
                let mut cols: Vec<String> = Vec::new();
                for e in a {
                    for (c, val) in e.as_object().into_iter().flatten() {
                        if !val.is_object() && !cols.contains(c) {
                            cols.push(c.clone());
                        }
                    }
                }
                let rows = a
                    .iter()
                    .map(|e| {
                        cols.iter()
                            .map(|c| e.get(c).map(fmt).unwrap_or_default())
                            .collect()
                    })
                    .collect();
                sec.text(capitalised(&super::labels::label(k)));
                let header: Vec<String> = cols.iter().map(|c| super::labels::label(c)).collect();
                let header: Vec<&str> = header.iter().map(String::as_str).collect();
                sec.table(&header, rows);
            }
            Value::Object(_) if depth < 1 && k != "options" => {
                sec.text(capitalised(&super::labels::label(k)));
                json_tables(sec, x, depth + 1);
            }
            _ => {}
        }
    }
}

/// `text` with its first letter in capitals (a table's caption).
fn capitalised(text: &str) -> String {
    let mut c = text.chars();
    match c.next() {
        Some(f) => f.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

/// Machine summary.
pub fn machine_section(p: &mut Pipeline, machine: Option<&Path>) -> crate::Result<()> {
    let Some(m) = machine else { return Ok(()) };
    let mach = crate::inputs::read_machine(m)?;
    p.summary.machine = Some(format!("{} (chain {})", mach.name, mach.chain.text));
    let sec = p.report.section("Machine");
    let mut rows = vec![
        vec!["name".into(), mach.name.clone()],
        vec!["chain".into(), mach.chain.text.clone()],
        vec![
            "tool offset (mm)".into(),
            format!("{:?}", mach.tool_offset_mm),
        ],
    ];
    for a in &mach.axes {
        let t = mach.travel(*a);
        rows.push(vec![
            format!("travel {a}"),
            format!(
                "{} … {} {}",
                t[0],
                t[1],
                if a.is_rotary() { "deg" } else { "mm" }
            ),
        ]);
    }
    sec.table(&["", ""], rows);
    Ok(())
}

/// ISO 230-2 positioning statistics.
pub fn iso230_2(p: &mut Pipeline, data: &Path) -> crate::Result<()> {
    let f = p.path_of(data);
    p.progress_of(&format!("ISO 230-2 statistics of {}", f.display()));
    let name = format!("iso230-2-{}.json", stem(&f));
    let mut obs = Collect::default();
    let done = ops::iso230_2::run(&ops::iso230_2::Options::new(&f), &mut obs)?;
    let v = p.json_result(&name, &format!("{}\n", done.to_json()?))?;
    let stage = format!("ISO 230-2 {}", stem(&f));
    let tol = p.tolerances.iso230_2.clone();
    let ax = &done.axis;
    p.summary
        .standard("ISO 230-2:2014 (positioning), with VDI/DGQ 3441 alongside");
    for (q, v, t) in [
        ("bidirectional accuracy A", ax.a_um, tol.a_um),
        ("bidirectional systematic error E", ax.e_um, tol.e_um),
        ("bidirectional repeatability R", ax.r_um, tol.r_um),
        ("reversal value B", ax.b_um, tol.b_um),
        ("mean bidirectional error M", ax.m_um, tol.m_um),
    ] {
        p.summary.figure(&stage, q, v, "µm", 2, t);
    }
    let sec = p
        .report
        .section(format!("Positioning (ISO 230-2): {}", stem(&f)));
    sec.source(
        "ISO 230-2:2014 (A, E, R, B, M as it defines them); VDI/DGQ 3441 (P, Ps, Pa, \
         U); mtec docs/methods.md §2",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text("Bidirectional positioning accuracy A, repeatability R, reversal B, systematic deviation E and mean reversal per ISO 230-2:2014, from the laser runs.");
    // mean unidirectional deviations with their ±2s bands, from the statistics themselves
    let col = |f: fn(&TargetStats) -> f64| done.targets.iter().map(f).collect::<Vec<f64>>();
    let x = col(|t| t.target_mm);
    type Column = fn(&TargetStats) -> f64;
    let directions: [(&str, Column, Column, Column); 2] = [
        ("↑", |t| t.mean_up_um, |t| t.lower_up_um, |t| t.upper_up_um),
        (
            "↓",
            |t| t.mean_down_um,
            |t| t.lower_down_um,
            |t| t.upper_down_um,
        ),
    ];
    let mut series = Vec::new();
    let mut bands = Vec::new();
    for (tag, mean, lower, upper) in directions {
        let mean = col(mean);
        series.push(Series::new(
            format!("mean deviation {tag}"),
            x.iter().zip(&mean).map(|(a, b)| (*a, *b)).collect(),
        ));
        bands.push(mtec_report::Band {
            name: format!("±2s {tag}"),
            x: x.clone(),
            lower: col(lower),
            upper: col(upper),
        });
    }
    sec.figure(line_chart("Mean positioning deviation with ±2s bands", "target (mm)", "deviation (µm)", &series, &bands), "ISO 230-2: mean unidirectional positioning deviation per target and direction, with the mean ± 2s band.");
    // every reading of every run, as the file gives it
    let runs = PositioningData::read(&f)?;
    let raw: Vec<(f64, f64)> = runs
        .targets_mm
        .iter()
        .zip(runs.up_um.iter().zip(&runs.down_um))
        .flat_map(|(t, (up, down))| up.iter().chain(down).map(move |d| (*t, *d)))
        .collect();
    sec.figure(
        scatter_chart(
            "All readings",
            "target (mm)",
            "deviation (µm)",
            &[Series::new("readings", raw)],
        ),
        "Every reading of every run: the vertical spread at a target is the repeatability R, \
         the gap between the two clusters of a target the reversal value B.",
    );
    json_tables(sec, &v, 0);
    Ok(())
}

/// A job's warnings: to the run's observer, and in the report section (a report never hides
/// what the job warned about).
fn warnings(sec: &mut Section, obs: &Collect, to: &mut dyn crate::Observer) {
    for w in &obs.warnings {
        to.warning(w);
        sec.note(format!("Warning: {w}"));
    }
}

/// `thermal fit` of a regression or (in the `neural` build) a neural model.
fn fit_thermal(opts: &ops::thermal::FitOptions, obs: &mut Collect) -> crate::Result<()> {
    if ops::thermal::is_neural(&opts.model) {
        return fit_neural(opts, obs);
    }
    ops::thermal::fit(opts, obs).map(|_| ())
}

#[cfg(feature = "neural")]
fn fit_neural(opts: &ops::thermal::FitOptions, obs: &mut Collect) -> crate::Result<()> {
    use mtec_nn::thermal_log::{NnFitOptions, NnKind};
    let (train, test) = match &opts.split {
        SplitBy::All => (Vec::new(), Vec::new()),
        SplitBy::Experiments { train, test } => (train.clone(), test.clone()),
        SplitBy::Until(_) => {
            return Err(Error::usage(
                "a neural [[thermal]] stage splits by `train`/`test` experiments, not `train_until_min`",
            ))
        }
    };
    if opts.fit.lag {
        return Err(Error::usage(
            "`lag` goes with the regression models, not a neural [[thermal]] stage",
        ));
    }
    let kind = NnKind::from_name(&opts.model).ok_or_else(|| Error::usage("not a neural model"))?;
    let nn = ops::thermal::neural::FitOptions {
        data: opts.data.clone(),
        target: opts.target.clone(),
        sensors: opts.fit.sensors.clone(),
        train,
        test,
        output: opts.output.clone(),
        nn: NnFitOptions::new(kind),
    };
    ops::thermal::neural::fit(&nn, obs).map(|_| ())
}

#[cfg(not(feature = "neural"))]
fn fit_neural(opts: &ops::thermal::FitOptions, _obs: &mut Collect) -> crate::Result<()> {
    Err(crate::neural_unavailable(&format!(
        "a [[thermal]] stage with model = \"{}\"",
        opts.model
    )))
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Line-set identification; returns the identified errors file.
pub fn lines(p: &mut Pipeline, machine: &Path, l: &LinesStage) -> crate::Result<PathBuf> {
    let data = p.path_of(&l.data);
    p.progress_of("identification of the error elements from the line measurements");
    let errors = p.out.join("identified-errors.json");
    let mut opts = ops::identify_lines::Options::new(machine, &data);
    opts.output = Some(errors.clone());
    if let Some(d) = l.degree {
        opts.degree = mtec_identify::lines::Degree::Fixed(d);
    }
    let mut obs = Collect::default();
    let done = ops::identify_lines::run(&opts, &mut obs)?;
    let v = p.json_result("identify-lines.json", &format!("{}\n", done.to_json()?))?;
    p.outputs.push(s(&errors));
    let stage = "Line identification";
    p.summary
        .standard("ISO 230-1 error elements, identified from line measurements (9-line method)");
    let r = &done.report;
    p.summary.fact(
        stage,
        "error elements identified",
        format!(
            "{} (rank {} of {} parameters)",
            r.elements.len(),
            r.rank,
            r.parameters
        ),
    );
    p.summary.figure(
        stage,
        "residual RMS of the fit",
        r.residual_rms_um,
        "µm",
        3,
        None,
    );
    p.summary.fact(stage, "validity", r.validity.clone());
    let sec = p
        .report
        .section("Identified geometric errors (line measurements)");
    sec.source(
        "ISO 230-1 error elements; the 9-line method (least squares on Legendre error \
         functions, degree by cross-validation); mtec docs/methods.md §3",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text("Error elements identified by least squares from the laser-interferometer lines; the identifiability report names what the design cannot determine.");
    let mach = crate::inputs::read_machine(machine)?;
    let set = crate::inputs::read_errors(&errors)?;
    {
        for group in [
            ["EXX", "EYY", "EZZ"],
            ["EYX", "EZX", "EXY"],
            ["EZY", "EXZ", "EYZ"],
            ["EAX", "EBX", "ECX"],
            ["EAY", "EBY", "ECY"],
        ] {
            let mut series = Vec::new();
            let mut bands = Vec::new();
            for n in group {
                let Ok(el) = mtec_model::ErrorElement::parse(n) else {
                    continue;
                };
                let Some(f) = set.get(&el) else { continue };
                let [lo, hi] = mach.travel(el.axis);
                let pts: Vec<(f64, f64)> = (0..=60)
                    .map(|k| {
                        let q = lo + (hi - lo) * k as f64 / 60.0;
                        ((q - lo) / (hi - lo), f.value(q))
                    })
                    .collect();
                // ±2σ of the identification (its largest 1σ over the travel)
                if let Some(u) = r
                    .elements
                    .iter()
                    .find(|e| e.element == n)
                    .map(|e| e.uncertainty_1sigma)
                    .filter(|u| u.is_finite() && *u > 0.0)
                {
                    bands.push(mtec_report::Band {
                        name: format!("{n} ± 2σ"),
                        x: pts.iter().map(|p| p.0).collect(),
                        lower: pts.iter().map(|p| p.1 - 2.0 * u).collect(),
                        upper: pts.iter().map(|p| p.1 + 2.0 * u).collect(),
                    });
                }
                series.push(Series::new(format!("{n} ({})", el.unit()), pts));
            }
            if !series.is_empty() {
                sec.figure(
                    line_chart(
                        &format!("{} against position", group.join(", ")),
                        "position (fraction of travel)",
                        "error (µm or µrad)",
                        &series,
                        &bands,
                    ),
                    "Identified error functions over each axis' travel (linear errors in µm, \
                     angular in µrad), each with its ±2σ band (the identification's largest 1σ \
                     over the travel): the largest curve is where compensation gains most; a \
                     band as wide as its curve means the element is not determined.",
                );
            }
        }
        if !set.unidentifiable.is_empty() {
            sec.note(format!(
                "Not identifiable from this design (no numbers given): {}",
                set.unidentifiable.join(", ")
            ));
        }
    }
    json_tables(sec, &v, 0);
    Ok(errors)
}

/// Writes error statistics (element, mean, std over the travel) of an error set for sensitivity
/// (the library's [`ErrorStatistics::of_identified`], as `identify lines --stats` writes them).
fn stats_from_errors(machine: &Path, errors: &Path, out: &Path) -> crate::Result<()> {
    let mach = crate::inputs::read_machine(machine)?;
    let set = crate::inputs::read_errors(errors)?;
    let stats = ErrorStatistics::of_identified(&set, &mach);
    mtec_io::write_output(out, stats.to_identified_csv().as_bytes())?;
    Ok(())
}

/// Global sensitivity of the volumetric error.
pub fn sensitivity(
    p: &mut Pipeline,
    machine: &Path,
    st: &SensitivityStage,
    identified: Option<&Path>,
) -> crate::Result<()> {
    p.progress_of(&format!("global sensitivity ({})", st.method));
    let stats = match (&st.stats, identified) {
        (Some(f), _) => p.path_of(f),
        (None, Some(errors)) => {
            let f = p.out.join("error-statistics.csv");
            stats_from_errors(machine, errors, &f)?;
            p.outputs.push(s(&f));
            f
        }
        (None, None) => return Err(Error::usage("[sensitivity] needs `stats` or a [lines] stage whose identified errors give the statistics")),
    };
    // indices aggregated over a 3 × 3 × 3 grid of the workspace
    let mach = crate::inputs::read_machine(machine)?;
    let mut pts = CsvWriter::new(mach.axes.iter().map(|a| crate::inputs::pose_column(*a)));
    let mut poses: Vec<Vec<f64>> = vec![vec![]];
    for a in &mach.axes {
        let [lo, hi] = mach.travel(*a);
        poses = poses
            .into_iter()
            .flat_map(|p| [0.0, 0.5, 1.0].map(|f| [p.clone(), vec![lo + f * (hi - lo)]].concat()))
            .collect();
    }
    for q in &poses {
        pts.row(q.iter().map(|v| format!("{v}")));
    }
    let points = p.out.join("sensitivity-points.csv");
    mtec_io::write_output(&points, pts.finish().as_bytes())?;
    let method = ops::sensitivity::MethodKind::from_name(&st.method).ok_or_else(|| {
        Error::usage(format!(
            "[sensitivity] method `{}`: expected efast, sobol or morris",
            st.method
        ))
    })?;
    let opts = ops::sensitivity::Options {
        machine: Some(machine.to_path_buf()),
        stats: Some(stats),
        method,
        samples: st.samples,
        points: Some(points),
        ..ops::sensitivity::Options::new()
    };
    let mut obs = Collect::default();
    let done = ops::sensitivity::run(&opts, &mut obs)?;
    let v = p.json_result("sensitivity.json", &format!("{}\n", done.to_json()?))?;
    let sec = p
        .report
        .section("Global sensitivity of the volumetric error");
    sec.source(
        "EFAST (Saltelli, Tarantola & Chan 1999), Sobol indices (Saltelli et al. 2010), \
         Morris elementary effects (Campolongo et al. 2007); mtec docs/methods.md §6",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text("First-order index S1 (key errors) and total index ST (ST − S1: coupling) of each error element for the volumetric error, inputs drawn from the statistics of the error functions.");
    // one chart per output (Ex, Ey, Ez, |E|) with S1 and ST per input; Morris gives μ*, σ
    let mut rest = v.clone();
    if let ops::sensitivity::Outcome::Machine(m) = &done {
        let r = &m.report;
        let names = |l: &[mtec_sensitivity::error_model::Ranked]| {
            l.iter()
                .take(5)
                .map(|k| k.element.clone())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let key = names(&r.key_errors);
        let coupled = names(&r.coupled_errors);
        p.summary.standard(&format!(
            "global sensitivity by {} (Saltelli et al.)",
            r.method
        ));
        p.summary.fact(
            "Sensitivity",
            "key error elements (largest first)",
            if key.is_empty() {
                "—".into()
            } else {
                key.clone()
            },
        );
        p.summary.fact(
            "Sensitivity",
            "coupled error elements",
            if coupled.is_empty() {
                "none".into()
            } else {
                coupled.clone()
            },
        );
        // what the whiskers are: EFAST's come from its random-phase repetitions and do not
        // hold its interference bias (docs/methods.md §6, "Confidence intervals")
        let whisker_note = format!(
            "; whiskers: the {:.0} % confidence interval of each index ({})",
            100.0 * m.conf_level,
            if r.method == "efast" {
                "spread of the random-phase repetitions; EFAST's own bias of a few hundredths is not in it"
            } else {
                "bootstrap over the base samples"
            }
        );
        for idx in &r.outputs {
            if let (Some(s1), Some(st)) = (&idx.s1, &idx.st) {
                let mark = |n: &String| {
                    let k = r.key_errors.iter().take(5).any(|k| &k.element == n);
                    let c = r.coupled_errors.iter().any(|k| &k.element == n);
                    // short marks, so that 17 names fit under their bars
                    format!(
                        "{n}{}{}",
                        if k { "*" } else { "" },
                        if c { "†" } else { "" }
                    )
                };
                let cats: Vec<String> = r.inputs.iter().map(mark).collect();
                let whiskers = [idx.s1_conf.clone(), idx.st_conf.clone()];
                sec.figure(
                    bar_chart_with_errors(
                        &format!("Sensitivity of {}", idx.output),
                        "index (share of the variance)",
                        &cats,
                        &[("S1".into(), s1.clone()), ("ST".into(), st.clone())],
                        &whiskers,
                    ),
                    format!(
                        "First-order (S1) and total (ST) indices for {}: a tall S1 bar is a key \
                         error (it alone drives the output); a gap between ST and S1 is coupling \
                         with other elements{}. * key: {}. † coupled: {}.",
                        idx.output,
                        if whiskers.iter().any(Option::is_some) {
                            whisker_note.as_str()
                        } else {
                            ""
                        },
                        if key.is_empty() { "—" } else { &key },
                        if coupled.is_empty() { "none" } else { &coupled }
                    ),
                );
            }
        }
        // the indices as a table: one row per element, S1 and ST of every output
        let with: Vec<&mtec_sensitivity::error_model::ChannelIndices> = r
            .outputs
            .iter()
            .filter(|o| o.s1.is_some() && o.st.is_some())
            .collect();
        if !with.is_empty() {
            let mut header = vec!["element".to_string()];
            for o in &with {
                header.push(format!("S1 {}", o.output));
                header.push(format!("ST {}", o.output));
            }
            let rows = r
                .inputs
                .iter()
                .enumerate()
                .map(|(i, n)| {
                    let mut row = vec![n.clone()];
                    for o in &with {
                        for (v, c) in [(&o.s1, &o.s1_conf), (&o.st, &o.st_conf)] {
                            let Some(v) = v else { continue };
                            // the estimate ± its half width, at the resolution of the interval
                            row.push(match c {
                                Some(c) => format!("{:.3} ± {:.3}", v[i], c[i]),
                                None => format!("{:.3}", v[i]),
                            });
                        }
                    }
                    row
                })
                .collect();
            let header: Vec<&str> = header.iter().map(String::as_str).collect();
            sec.text(format!(
                "Indices of every error element (± the half width of the {:.0} % confidence interval):",
                100.0 * m.conf_level
            ));
            sec.table(&header, rows);
        }
        if let Some(o) = rest.as_object_mut() {
            o.remove("outputs");
            o.remove("inputs");
        }
    }
    json_tables(sec, &rest, 0);
    Ok(())
}

/// ISO 230-4 circular test.
pub fn circular(p: &mut Pipeline, data: &Path) -> crate::Result<()> {
    let f = p.path_of(data);
    p.progress_of(&format!("circular test {}", f.display()));
    // `circular --out` draws the polar plot the CLI gives; the report shows that same figure
    let dir = p.out.join(format!("circular-{}", stem(&f)));
    let mut opts = ops::circular::Options::new(&f);
    opts.out = Some(dir.clone());
    let mut obs = Collect::default();
    let done = ops::circular::run(&opts, &mut obs)?;
    p.json_result(
        &format!("circular-{}.json", stem(&f)),
        &format!("{}\n", done.to_json()?),
    )?;
    let stage = format!("ISO 230-4 {}", stem(&f));
    let tol = p.tolerances.circular.clone();
    p.summary
        .standard("ISO 230-4 (circular test), ballbar diagnostics");
    let iso = &done.iso230_4;
    p.summary.figure(
        &stage,
        "bidirectional circular deviation G(b)",
        iso.g_bidirectional_um,
        "µm",
        2,
        tol.g_um,
    );
    p.summary
        .figure(&stage, "circular hysteresis H", iso.h_um, "µm", 2, tol.h_um);
    if let Some(top) = done
        .diagnostics
        .faults
        .iter()
        .filter(|f| f.present)
        .max_by(|a, b| a.contribution_um.total_cmp(&b.contribution_um))
    {
        p.summary.fact(
            &stage,
            "largest diagnosed fault",
            format!(
                "{} ({:.2} µm of the circularity)",
                top.label, top.contribution_um
            ),
        );
    }
    let sec = p
        .report
        .section(format!("Circular test (ISO 230-4): {}", stem(&f)));
    sec.source(
        "ISO 230-4:2005 (circular deviation G, hysteresis H); ballbar diagnostics by \
         least squares on the faults' signatures; mtec docs/methods.md §5",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text(format!(
        "Circular deviation G and circular hysteresis H per ISO 230-4 ({:?} plane, R = {} mm, \
         F = {} mm/min), then the ballbar diagnostics fitted from the trace, ranked by their \
         contribution to the circularity (as `mtec circular` prints them).",
        done.plane,
        fmt(&serde_json::json!(done.radius_mm)),
        fmt(&serde_json::json!(done.feed_mm_min))
    ));
    let polar = std::fs::read_to_string(dir.join(ops::circular::PLOT_FILE))?;
    sec.figure(
        polar,
        "Polar plot of the radial deviation about the least-squares centre, ccw (blue) and \
         cw (red), the mean radius deviation removed.",
    );
    sec.table(&["quantity", "value"], circular_rows(&done));
    sec.table(
        &[
            "fault",
            "present",
            "value",
            "unit",
            "± s.e.",
            "contribution (µm)",
            "%",
        ],
        fault_rows(&done.diagnostics),
    );
    Ok(())
}

/// ISO 230-4 numbers as `mtec circular` prints them.
fn circular_rows(done: &ops::circular::Outcome) -> Vec<Vec<String>> {
    let iso = &done.iso230_4;
    let um = |x: f64| format!("{x:.3} µm");
    let c = &iso.circle_bidirectional;
    vec![
        vec!["circular deviation G(ccw)".into(), um(iso.g_ccw_um)],
        vec!["circular deviation G(cw)".into(), um(iso.g_cw_um)],
        vec![
            "bidirectional circular deviation G(b)".into(),
            um(iso.g_bidirectional_um),
        ],
        vec!["circular hysteresis H".into(), um(iso.h_um)],
        vec![
            "least-squares centre (X, Y)".into(),
            format!("({:.3}, {:.3}) µm", c.centre_um[0], c.centre_um[1]),
        ],
        vec![
            "radius deviation (least-squares circle)".into(),
            um(c.radius_deviation_um),
        ],
        vec![
            "residual RMS after the diagnostics fit".into(),
            um(done.diagnostics.residual_rms_um),
        ],
    ]
}

/// The diagnostics table of `mtec circular`, in its order (by contribution).
fn fault_rows(d: &Diagnostics) -> Vec<Vec<String>> {
    // a value that is not a number (a fault that could not be fitted) shows as `-`
    let n = |x: f64, d: usize| {
        if x.is_finite() {
            format!("{x:.d$}")
        } else {
            "-".into()
        }
    };
    d.faults
        .iter()
        .map(|f| {
            vec![
                f.label.clone(),
                if f.present { "yes" } else { "no" }.into(),
                // a fault a partial arc does not determine has no value: `-`
                n(f.value.unwrap_or(f64::NAN), 3),
                f.unit.clone(),
                n(f.std_error.unwrap_or(f64::NAN), 3),
                n(f.contribution_um, 3),
                n(f.contribution_percent, 1),
            ]
        })
        .collect()
}

/// Ballbar identification of rotary-axis error motions.
pub fn ballbar(p: &mut Pipeline, b: &BallbarStage) -> crate::Result<()> {
    p.progress_of("ballbar identification of the rotary axis");
    let dir = p.out.join("ballbar");
    let opts = ops::identify_ballbar::Options {
        setup: p.path_of(&b.setup),
        data: p.path_of(&b.data),
        temps: b.temps.as_ref().map(|t| p.path_of(t)),
        out: Some(dir.clone()),
    };
    let mut obs = Collect::default();
    let done = ops::identify_ballbar::run(&opts, &mut obs)?;
    p.json_result("ballbar.json", &format!("{}\n", done.to_json()?))?;
    p.summary
        .standard("rotary-axis error motions from five ballbar installation modes");
    let peak = |f: fn(&mtec_identify::ballbar::motions_file::MotionRecord) -> f64| {
        done.motions
            .iter()
            .map(f)
            .fold(0.0_f64, |m, v| m.max(v.abs()))
    };
    let stage = "Rotary axis (ballbar)";
    p.summary.figure(
        stage,
        "largest radial/axial error motion |EXC|, |EYC|, |EZC|",
        peak(|m| m.exc_um)
            .max(peak(|m| m.eyc_um))
            .max(peak(|m| m.ezc_um)),
        "µm",
        2,
        None,
    );
    p.summary.figure(
        stage,
        "largest tilt error motion |EAC|, |EBC|",
        peak(|m| m.eac_urad).max(peak(|m| m.ebc_urad)),
        "µrad",
        1,
        None,
    );
    let sec = p
        .report
        .section("Rotary axis: ballbar identification (5 installation modes)");
    sec.source(
        "the five-mode ballbar identification of a rotary axis' error motions (ISO \
         230-7 names); mtec docs/methods.md §4",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text("Error motions EXC, EYC, EZC (µm), EAC, EBC (µrad) identified per angle and time from five installation modes, after removal of each mode's mean and first harmonic (set-up errors). ECC is not observable by a ballbar.");
    // the polar and time plots `identify ballbar --out` drew, in name order
    let mut svgs = Vec::new();
    for e in std::fs::read_dir(&dir)? {
        let f = e?.path();
        if f.extension().is_some_and(|x| x == "svg") {
            svgs.push(f);
        }
    }
    svgs.sort();
    for f in svgs {
        let svg = std::fs::read_to_string(&f)?;
        sec.figure(svg, rotary_caption(&stem(&f)));
    }
    let c = &done.conditioning;
    sec.text("Conditioning of the five-mode identification (the worst angle):");
    sec.table(
        &["quantity", "value"],
        vec![
            vec!["unknowns".into(), c.unknowns.join(", ")],
            vec!["smallest rank over the angles".into(), c.rank.to_string()],
            vec![
                "worst angle (deg)".into(),
                fmt(&serde_json::json!(c.worst_angle_deg)),
            ],
            vec![
                "worst condition number".into(),
                fmt(&serde_json::json!(c.worst_condition_number)),
            ],
            vec![
                "worst noise gain (per µm of reading)".into(),
                fmt(&serde_json::json!(c.worst_noise_gain)),
            ],
            vec![
                "largest ECC coefficient (µm/µrad)".into(),
                fmt(&serde_json::json!(c.ecc_coefficient_max)),
            ],
        ],
    );
    sec.text("revolution");
    json_tables(sec, &serde_json::to_value(&c.revolution)?, 1);
    match &b.model {
        Some(m) => predicted_readings(p, b, &p.path_of(m), &dir),
        None => Ok(()),
    }
}

/// The predicted ballbar readings of the `[ballbar] model` on the identified motions
/// (`thermal predict --setup --dbb --readings`), and their report section.
fn predicted_readings(
    p: &mut Pipeline,
    b: &BallbarStage,
    model: &Path,
    dir: &Path,
) -> crate::Result<()> {
    let out = dir.join("readings.csv");
    let opts = ops::thermal::PredictOptions {
        model: model.to_path_buf(),
        data: dir.join("motions.csv"),
        history: None,
        output: None,
        readings: Some(ops::thermal::ReadingsOptions {
            setup: p.path_of(&b.setup),
            dbb: p.path_of(&b.data),
            out: Some(out.clone()),
        }),
    };
    let mut obs = Collect::default();
    let done = ops::thermal::predict(&opts, &mut obs)?;
    p.outputs.push(s(&out));
    let sec = p
        .report
        .section("Rotary axis: predicted ballbar readings (thermal model)");
    warnings(sec, &obs, &mut *p.obs);
    #[cfg(feature = "neural")]
    if let ops::thermal::PredictOutcome::Neural(n) = &done {
        if let Some(r) = &n.readings {
            super::readings_section::section(sec, &stem(model), r);
        }
    }
    #[cfg(not(feature = "neural"))]
    let _ = done;
    Ok(())
}

/// What a figure of `identify ballbar --out` shows and what to look at, from its file name
/// (`polar_EXC`, `time_EAC`).
fn rotary_caption(name: &str) -> String {
    let (kind, motion) = name.split_once('_').unwrap_or(("", name));
    match kind {
        "polar" => format!(
            "{motion} over one revolution of the table, drawn about the dashed reference circle, \
             at the first and the last measurement of every experiment: the gap between them is \
             what warming up changed."
        ),
        "time" => format!(
            "Peak-to-valley of {motion} over the revolution against time, one line per \
             experiment: how the error motion grows as the axis warms and settles."
        ),
        _ => format!("{motion}: identified rotary-axis error motion."),
    }
}

/// A thermal model: sensor selection, fit, prediction; returns the model file.
pub fn thermal(p: &mut Pipeline, t: &ThermalStage) -> crate::Result<PathBuf> {
    let data = p.path_of(&t.data);
    p.progress_of(&format!("thermal model of {} ({})", t.target, t.model));
    let tag = format!("{}-{}", stem(&data), t.target);
    let model = p.out.join(format!("thermal-model-{tag}.json"));
    let list = |l: &Option<String>| -> Vec<String> {
        l.iter()
            .flat_map(|x| x.split(','))
            .map(|x| x.trim().to_string())
            .collect()
    };
    let split = match (&t.train, &t.test, t.train_until_min) {
        (Some(_), Some(_), _) => SplitBy::Experiments {
            train: list(&t.train),
            test: list(&t.test),
        },
        (_, _, Some(u)) => SplitBy::Until(u),
        _ => SplitBy::All,
    };
    let mut fit = mtec_thermal::FitOptions {
        sensors: t.sensors.clone().unwrap_or_default(),
        lag: t.lag,
        ..Default::default()
    };
    if let Some(input) = &t.input {
        fit.input = input.clone();
    }
    let fit = ops::thermal::FitOptions {
        data: data.clone(),
        target: t.target.clone(),
        model: t.model.clone(),
        fit,
        split,
        output: model.clone(),
    };
    let mut obs = Collect::default();
    fit_thermal(&fit, &mut obs)?;
    p.outputs.push(s(&model));
    let predict = ops::thermal::PredictOptions {
        model: model.clone(),
        data: data.clone(),
        history: None,
        output: None,
        readings: None,
    };
    let done = ops::thermal::predict(&predict, &mut obs)?;
    p.json_result(
        &format!("thermal-predict-{tag}.json"),
        &format!(
            "{}\n",
            serde_json::to_string(&serde_json::to_value(&done)?)?
        ),
    )?;
    let model_json: Value = mtec_io::read_json(&model)?;
    let table = mtec_io::Table::read(&data)?;
    thermal_figures(
        p,
        t,
        &model_json,
        &table,
        done.predictions_of(&t.target).as_deref(),
    );
    let sec = p
        .report
        .section(format!("Thermal model: {} from {}", t.target, stem(&data)));
    sec.source(
        "the model kind's method in mtec docs/methods.md §7 (ridge trace: Hoerl & \
         Kennard 1970; forward validation: rolling origin, Tashman 2000)",
    );
    warnings(sec, &obs, &mut *p.obs);
    let ridge_trace = super::thermal_section::section(
        sec,
        &model_json,
        Some(&table),
        &t.target,
        done.predictions_of(&t.target).as_deref(),
    );
    {
        let tab = &table;
        let (xs, x_label) = super::thermal_section::time_axis(tab, tab.rows.len());
        let temps: Vec<Series> = tab
            .columns_with_suffix("_c")
            .iter()
            .take(8)
            .map(|c| {
                let v = tab.f64_column(c)?;
                Ok(Series::new(
                    c.clone(),
                    xs.iter().zip(&v).map(|(x, t)| (*x, *t)).collect(),
                ))
            })
            .collect::<crate::Result<_>>()?;
        if !temps.is_empty() {
            sec.figure(
                line_chart("Temperatures", x_label, "temperature (°C)", &temps, &[]),
                "The temperature sensors (up to 8 shown): compare their rise and lag with the \
                 drift above; a sensor that moves with the drift is a candidate input.",
            );
        }
    }
    if ridge_trace {
        // the model is the ridge-trace selection's: show how the sensors were chosen
        let opts = ops::thermal::SelectOptions {
            data: data.clone(),
            target: t.target.clone(),
            sensors: Vec::new(),
            out: None,
        };
        let done = ops::thermal::select(&opts, &mut Collect::default())?;
        let sel = p.json_result(
            &format!("thermal-select-{tag}.json"),
            &format!(
                "{}\n",
                serde_json::to_string_pretty(&serde_json::to_value(&done)?)?
            ),
        )?;
        let sec = p.report.section(format!(
            "Sensor selection for {}: the ridge trace",
            t.target
        ));
        sec.text(
            "The ridge-trace selection the model was fitted with: variance inflation factors, \
             the elimination steps and the chosen k, on all rows of the data.",
        );
        if let Some(fig) = ridge_trace_figure(&done.selection.trace) {
            sec.figure(
                fig,
                "Ridge trace: each sensor's standardised coefficient against the ridge parameter k.",
            );
        }
        let mut sel_small = sel.clone();
        if let Some(o) = sel_small.as_object_mut() {
            o.remove("trace");
        }
        json_tables(sec, &sel_small, 0);
    }
    Ok(model)
}

/// The thermal stage's key figures: the measured drift, what the model leaves of it, and the
/// out-of-sample error the tolerance is judged on (test rows, else the forward validation; the
/// in-sample residual only when neither exists).
fn thermal_figures(
    p: &mut Pipeline,
    t: &ThermalStage,
    model: &Value,
    table: &mtec_io::Table,
    predictions: Option<&[f64]>,
) {
    let stage = format!("Thermal {}", t.target);
    p.summary
        .standard("thermal drift models validated forward in time (rolling origin)");
    let column = mtec_thermal::data::target_column(&t.target);
    let (Ok(y), Some(pred)) = (table.f64_column(&column), predictions) else {
        return;
    };
    if y.len() != pred.len() || y.is_empty() {
        return;
    }
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x * x, n + 1));
        (s / n.max(1) as f64).sqrt()
    };
    let before = rms(&mut y.iter().copied());
    let after = rms(&mut y.iter().zip(pred).map(|(a, b)| a - b));
    let tol = p.tolerances.thermal_residual_rms_um;
    p.summary.figure(
        &stage,
        "measured drift RMS (all rows)",
        before,
        "µm",
        2,
        None,
    );
    let test = model
        .pointer("/test_metrics/rmse_um")
        .and_then(Value::as_f64);
    let forward = model
        .pointer("/validation/pooled_rmse_um")
        .and_then(Value::as_f64);
    match (test, forward) {
        (Some(e), _) => {
            p.summary
                .figure(&stage, "residual RMS on the test rows", e, "µm", 2, tol);
            p.summary
                .figure(&stage, "residual RMS (all rows)", after, "µm", 2, None);
        }
        (None, Some(e)) => {
            p.summary
                .figure(&stage, "residual RMS, forward-validated", e, "µm", 2, tol);
            p.summary.figure(
                &stage,
                "residual RMS in-sample (all rows)",
                after,
                "µm",
                2,
                None,
            );
        }
        (None, None) => p.summary.figure(
            &stage,
            "residual RMS in-sample (all rows)",
            after,
            "µm",
            2,
            tol,
        ),
    }
}

/// The ridge trace of the selection: one line per sensor over log10 k (k > 0).
fn ridge_trace_figure(trace: &RidgeTrace) -> Option<String> {
    let series = ridge_trace_series(trace);
    (!series.is_empty()).then(|| {
        line_chart(
            "Ridge trace",
            "log10 k",
            "standardised coefficient",
            &series,
            &[],
        )
    })
}

/// `coefficients[i][j]` is sensor j at k[i]: one series per sensor, over every k > 0 (k = 0
/// has no logarithm).
fn ridge_trace_series(trace: &RidgeTrace) -> Vec<Series> {
    trace
        .sensors
        .iter()
        .enumerate()
        .map(|(j, name)| {
            Series::new(
                name.clone(),
                trace
                    .k
                    .iter()
                    .zip(&trace.coefficients)
                    .filter(|(k, row)| **k > 0.0 && j < row.len())
                    .map(|(k, row)| (k.log10(), row[j]))
                    .collect(),
            )
        })
        .collect()
}

/// A volumetric map from a grid; returns the map file.
pub fn map(p: &mut Pipeline, m: &MapStage) -> crate::Result<PathBuf> {
    let grid = p.path_of(&m.grid);
    p.progress_of("volumetric map (trilinear)");
    p.summary
        .standard("volumetric error map, trilinear interpolation");
    let map = p.out.join("map.json");
    let mut obs = Collect::default();
    ops::map::fit(&ops::map::FitOptions::trilinear(&grid, &map), &mut obs)?;
    p.outputs.push(s(&map));
    let mut figures = Vec::new();
    let mut notes = Vec::new();
    if let Some(check) = &m.check {
        let pts = p.path_of(check);
        let out = p.out.join("map-check.csv");
        let opts = ops::map::EvalOptions {
            model: map.clone(),
            points: pts.clone(),
            out: Some(out.clone()),
        };
        ops::map::eval(&opts, &mut obs)?;
        p.outputs.push(s(&out));
        let (meas, pred) = (mtec_io::Table::read(&pts)?, mtec_io::Table::read(&out)?);
        for (c, name) in ["ex_um", "ey_um", "ez_um"].iter().zip(["Ex", "Ey", "Ez"]) {
            if !meas.has(c) {
                notes.push(format!(
                    "{}: no `{c}` column, so {name} of the map is not compared with a measurement.",
                    pts.display()
                ));
                continue;
            }
            let (a, b) = (meas.f64_column(c)?, pred.f64_column(c)?);
            let rms = (a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>()
                / a.len() as f64)
                .sqrt();
            let tol = p.tolerances.map_check_rms_um;
            p.summary.figure(
                "Volumetric map",
                &format!("{name}: map against the check measurements, RMS"),
                rms,
                "µm",
                2,
                tol,
            );
            let xs = 0..a.len();
            figures.push((
                line_chart(
                    &format!("{name} along the check points"),
                    "point",
                    "µm",
                    &[
                        Series::new("measured", xs.clone().map(|i| (i as f64, a[i])).collect()),
                        Series::new("map", xs.map(|i| (i as f64, b[i])).collect()),
                    ],
                    &[],
                ),
                format!(
                    "{name}: map against measurement off the grid, RMS difference {rms:.2} µm."
                ),
            ));
        }
    }
    let sec = p.report.section("Volumetric error map");
    sec.source(
        "a regular grid of measured volumetric errors, trilinear interpolation; mtec \
         docs/methods.md §8",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text("A regular grid of measured volumetric errors, interpolated trilinearly (the controller-style compensation baseline).");
    for (svg, cap) in figures {
        sec.figure(svg, cap);
    }
    for n in notes {
        sec.note(n);
    }
    Ok(map)
}

/// Compensation outputs: corrected programs and controller tables.
pub fn compensation(
    p: &mut Pipeline,
    c: &CompensationStage,
    map: Option<&Path>,
    machine: Option<&Path>,
    identified: Option<&Path>,
) -> crate::Result<()> {
    p.progress_of("compensation outputs");
    let elements: ops::selective::Elements = c
        .elements
        .as_deref()
        .unwrap_or("all")
        .parse()
        .map_err(|m| Error::usage(format!("[compensation] elements: {m}")))?;
    // the model: the map if there is one, else the identified kinematic model
    let model = match (map, machine, identified) {
        (Some(_), _, _) if elements != ops::selective::Elements::All => {
            return Err(Error::usage(format!(
                "[compensation] elements = \"{}\" selects elements of the identified kinematic \
                 model, but this project compensates with the [map] stage's map (remove one)",
                c.elements.as_deref().unwrap_or_default()
            )))
        }
        (Some(m), _, _) => m.to_path_buf(),
        (None, Some(mach), Some(errors)) => {
            let machine = crate::inputs::read_machine(mach)?;
            let set = crate::inputs::read_errors(errors)?;
            let f = p.out.join("kinematic-model.json");
            // the same file `identify lines --kinematic-model` writes
            let doc = KinematicFile::new(&machine, &set)
                .map_err(|m| Error::Input(mtec_io::InputError::file(mach, m)))?;
            let text = doc.to_json().map_err(|e| Error::Internal(e.into()))?;
            mtec_io::write_output(&f, text.as_bytes())?;
            p.outputs.push(s(&f));
            f
        }
        _ => {
            return Err(Error::usage(
                "[compensation] needs a [map] stage or a machine with a [lines] stage",
            ))
        }
    };
    let mut obs = Collect::default();
    let mut rows = Vec::new();
    for g in &c.gcode {
        let input = p.path_of(g);
        let out = p.out.join(format!("{}-compensated.ngc", stem(&input)));
        let mut opts = ops::compensate_gcode::Options::new(&model, &input, &out);
        opts.elements = elements.clone();
        let said = ops::compensate_gcode::run(&opts, &mut obs)?.to_string();
        p.outputs.push(s(&out));
        let lines_in = std::fs::read_to_string(&input)
            .map(|t| t.lines().count())
            .unwrap_or(0);
        let lines_out = std::fs::read_to_string(&out)
            .map(|t| t.lines().count())
            .unwrap_or(0);
        rows.push(vec![
            stem(&input),
            format!("{lines_in}"),
            format!("{lines_out}"),
            said.lines().last().unwrap_or("").to_string(),
        ]);
    }
    let mut tables = Vec::new();
    for f in &c.tables {
        let out = p.out.join(format!("comp-{f}.txt"));
        let format = ops::compensate_table::Format::from_name(f).ok_or_else(|| {
            let names: Vec<&str> = ops::compensate_table::Format::ALL
                .iter()
                .map(|f| f.name())
                .collect();
            Error::usage(format!(
                "[compensation] tables: no format `{f}`; the formats are {}",
                names.join(", ")
            ))
        })?;
        let mut opts = ops::compensate_table::Options::new(&model, format, Some(out.clone()));
        opts.elements = elements.clone();
        ops::compensate_table::run(&opts, &mut obs)?;
        p.outputs.push(s(&out));
        let head: String = std::fs::read_to_string(&out)
            .unwrap_or_default()
            .lines()
            .take(6)
            .collect::<Vec<_>>()
            .join(" | ");
        tables.push(vec![f.clone(), s(&out), head]);
    }
    p.summary.fact(
        "Compensation",
        "outputs written",
        format!(
            "{} NC program(s), {} controller table(s)",
            rows.len(),
            tables.len()
        ),
    );
    let sec = p.report.section("Compensation outputs");
    sec.source(
        "the correction solve and the G-code rewriter, mtec docs/methods.md §8–9; table \
         formats from the controllers' manuals (docs/formats.md)",
    );
    warnings(sec, &obs, &mut *p.obs);
    sec.text(format!("Model used: {}. NC programs are rewritten so that every commanded point is corrected (long moves split where the correction changes); controller tables carry the negative of the predicted error.", model.display()));
    if !rows.is_empty() {
        sec.table(
            &["program", "lines in", "lines out", "rewriter summary"],
            rows,
        );
    }
    if !tables.is_empty() {
        sec.table(&["format", "file", "first lines"], tables);
    }
    if map.is_none() {
        super::selective_section::section(p, &model, &elements)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `coefficients` is one row per k: the trace has one line per sensor, over every k (the
    /// report drew it transposed, one line per k).
    #[test]
    fn the_ridge_trace_has_one_line_per_sensor() {
        let trace = RidgeTrace {
            k: vec![0.001, 0.01, 0.1],
            sensors: vec!["s1_c".into(), "s2_c".into()],
            coefficients: vec![vec![1.0, -1.0], vec![0.8, -0.5], vec![0.3, -0.1]],
        };
        let s = ridge_trace_series(&trace);
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].name, "s1_c");
        assert_eq!(s[0].points, vec![(-3.0, 1.0), (-2.0, 0.8), (-1.0, 0.3)]);
        assert_eq!(s[1].points[2], (-1.0, -0.1));
    }
}
