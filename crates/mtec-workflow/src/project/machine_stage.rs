//! The `[machine_model]` and `[[replay]]` stages of `mtec run`: the thermal models of the
//! project's [[thermal]] stages become one machine error model (`mtec machine build`), and
//! recorded days are compensated through the real-time path (`mtec machine replay`), reported
//! as the error at the tool tip before and after over time. Both run `crate::ops::machine`
//! in-process.

use super::pipeline::{s, Pipeline};
use super::spec::{MachineModelStage, ReplayStage};
use crate::ops::machine;
use crate::Error;
use mtec_report::{line_chart, Series};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Builds the machine model; returns its file.
pub fn build(
    p: &mut Pipeline,
    m: &MachineModelStage,
    thermal_models: &[(String, PathBuf)],
    map: Option<&Path>,
) -> crate::Result<PathBuf> {
    p.progress_of("machine error model (geometric + thermal, with training envelopes)");
    let out = p.out.join("machine.json");
    let geometric = m
        .geometric
        .as_ref()
        .map(|g| p.path_of(g))
        .or(map.map(Path::to_path_buf));
    let mut rows = Vec::new();
    let mut parts = Vec::new();
    for part in &m.parts {
        // run.rs checked that exactly one [[thermal]] stage has this target
        let Some((_, model)) = thermal_models.iter().find(|(t, _)| *t == part.target) else {
            return Err(Error::usage(format!(
                "[machine_model] part `{}`: no [[thermal]] stage has this target",
                part.target
            )));
        };
        // as `--thermal AXIS=MODEL[,sign=-1]` reads it: the axis x, y or z
        let sign = if part.sign < 0.0 { ",sign=-1" } else { "" };
        parts.push(machine::Part::parse(&format!(
            "{}={}{sign}",
            part.axis,
            s(model)
        ))?);
        rows.push(vec![
            part.axis.to_uppercase(),
            part.target.clone(),
            format!("{:+}", part.sign),
            s(model),
        ]);
    }
    let mut opts = machine::BuildOptions::new(geometric.clone(), parts, &out);
    opts.data = Some(p.path_of(&m.data));
    opts.guard = m.guard.clone();
    if let Some(f) = m.fade_c {
        opts.fade_c = f;
    }
    machine::build(&opts, &mut crate::Collect::default())?;
    p.outputs.push(s(&out));
    let file: Value = mtec_io::read_json(&out)?;
    let sec = p.report.section("Machine error model with a state");
    sec.text(format!(
        "The thermal models below act along their axes in one machine error model ({}), run on line by the real-time library: every new reading advances their filters, and outside the training envelope (the range of each input over the rows the model was fitted on) the thermal part fades to no correction over {} °C (temperatures) or 10 % of the range (other inputs).",
        s(&out),
        m.fade_c.unwrap_or(mtec_comp::machine::FADE_TEMPERATURE_C)
    ));
    if let Some(g) = &geometric {
        sec.text(format!("Geometric part: {}.", s(g)));
    }
    sec.table(&["axis", "target", "sign", "model"], rows);
    if let Some(parts) = file.get("thermal").and_then(Value::as_array) {
        let mut env = Vec::new();
        for part in parts {
            let axis = part.get("axis").and_then(Value::as_str).unwrap_or("");
            for (k, r) in part
                .get("envelope")
                .and_then(Value::as_object)
                .into_iter()
                .flatten()
            {
                let v: Vec<f64> = r
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(Value::as_f64)
                    .collect();
                if let [lo, hi] = v.as_slice() {
                    env.push(vec![
                        axis.to_uppercase(),
                        k.clone(),
                        format!("{lo}"),
                        format!("{hi}"),
                    ]);
                }
            }
        }
        sec.text("Training envelopes:");
        sec.table(&["axis", "input", "min", "max"], env);
    }
    Ok(out)
}

/// One column of the replay CSV as numbers (`time_min`, `ex_um`, …).
fn column(t: &mtec_io::Table, name: &str) -> Vec<f64> {
    t.f64_column(name).unwrap_or_default()
}

/// Compensates a recorded day and reports it.
pub fn replay(p: &mut Pipeline, r: &ReplayStage, built: Option<&Path>) -> crate::Result<()> {
    let name = if r.name.is_empty() {
        stem(&r.state)
    } else {
        r.name.clone()
    };
    p.progress_of(&format!("compensation replay: {name}"));
    let model = match (&r.model, built) {
        (Some(m), _) => p.path_of(m),
        (None, Some(b)) => b.to_path_buf(),
        (None, None) => {
            return Err(Error::usage(
                "[[replay]] needs `model` or a [machine_model] stage",
            ))
        }
    };
    let tag = stem(&r.probes);
    let csv = p.out.join(format!("replay-{tag}.csv"));
    let opts = machine::ReplayOptions {
        model,
        state: p.path_of(&r.state),
        probes: p.path_of(&r.probes),
        output: Some(csv.clone()),
    };
    let done = machine::replay(&opts, &mut crate::Collect::default())?;
    let doc = serde_json::to_value(&done)?;
    let v = p.json_result(
        &format!("replay-{tag}.json"),
        &format!("{}\n", serde_json::to_string_pretty(&doc)?),
    )?;
    p.outputs.push(s(&csv));
    let sec = p.report.section(format!("Compensation replay: {name}"));
    sec.text("The recorded day compensated exactly as the real-time library would have done it: at each probe reading the model has received every state reading up to that moment (update_state), then gives the correction for the probe point (correction_um). The error after compensation is the measured error plus the correction.");
    let get = |k: &str, f: &str| v.get(k).and_then(|x| x.get(f)).and_then(Value::as_f64);
    let mut rows = Vec::new();
    for (k, label) in [("x", "X"), ("y", "Y"), ("z", "Z"), ("vector", "vector")] {
        let f = |x: Option<f64>| x.map(|v| format!("{v:.3}")).unwrap_or_default();
        let pc = |x: Option<f64>| x.map(|v| format!("{:.1} %", 100.0 * v)).unwrap_or_default();
        rows.push(vec![
            label.to_string(),
            f(get(k, "rms_before_um")),
            f(get(k, "rms_after_um")),
            f(get(k, "max_before_um")),
            f(get(k, "max_after_um")),
            pc(get(k, "compensation_rate")),
            pc(get(k, "worst_reduction")),
        ]);
    }
    sec.table(
        &[
            "",
            "RMS before (µm)",
            "RMS after (µm)",
            "max before (µm)",
            "max after (µm)",
            "compensation rate",
            "worst moment reduced by",
        ],
        rows,
    );
    let n = |k: &str| v.get(k).map(super::stages::fmt_value).unwrap_or_default();
    sec.text(format!(
        "{} probe readings; {} made worse by the compensation (largest increase of |e| {} µm); {} taken with the thermal part faded (smallest weight {}).",
        n("readings"),
        n("worse"),
        n("largest_worsening_um"),
        n("faded"),
        n("min_thermal_weight")
    ));
    if let Ok(t) = mtec_io::Table::read(&csv) {
        let time_h: Vec<f64> = column(&t, "time_min").iter().map(|m| m / 60.0).collect();
        let probes = t.str_column("probe").unwrap_or_default();
        let first = probes.first().cloned().unwrap_or_default();
        // the worst probe at each moment: |e| before and after
        let (bx, by, bz) = (
            column(&t, "ex_um"),
            column(&t, "ey_um"),
            column(&t, "ez_um"),
        );
        let (ax, ay, az) = (
            column(&t, "ex_after_um"),
            column(&t, "ey_after_um"),
            column(&t, "ez_after_um"),
        );
        let norm = |x: f64, y: f64, z: f64| (x * x + y * y + z * z).sqrt();
        let before = bx
            .iter()
            .zip(&by)
            .zip(&bz)
            .map(|((x, y), z)| norm(*x, *y, *z));
        let after = ax
            .iter()
            .zip(&ay)
            .zip(&az)
            .map(|((x, y), z)| norm(*x, *y, *z));
        let mut worst_b: Vec<(f64, f64)> = Vec::new();
        let mut worst_a: Vec<(f64, f64)> = Vec::new();
        for ((&h, nb), na) in time_h.iter().zip(before).zip(after) {
            match (worst_b.last_mut(), worst_a.last_mut()) {
                (Some(b), Some(a)) if b.0 == h => {
                    b.1 = b.1.max(nb);
                    a.1 = a.1.max(na);
                }
                _ => {
                    worst_b.push((h, nb));
                    worst_a.push((h, na));
                }
            }
        }
        sec.figure(
            line_chart(
                "Error at the tool tip, worst probe point",
                "time (h)",
                "|e| (µm)",
                &[
                    Series::new("without compensation", worst_b),
                    Series::new("compensated", worst_a),
                ],
                &[],
            ),
            "The largest error vector over the probe points at each moment, before and after compensation.",
        );
        for (label, b, a) in [("X", &bx, &ax), ("Y", &by, &ay), ("Z", &bz, &az)] {
            let pick = |v: &[f64]| -> Vec<(f64, f64)> {
                (0..time_h.len().min(v.len()))
                    .filter(|&i| probes.get(i) == Some(&first))
                    .map(|i| (time_h[i], v[i]))
                    .collect()
            };
            sec.figure(
                line_chart(
                    &format!("{label} error at probe point `{first}`"),
                    "time (h)",
                    &format!("e{} (µm)", label.to_lowercase()),
                    &[
                        Series::new("without compensation", pick(b)),
                        Series::new("compensated", pick(a)),
                    ],
                    &[],
                ),
                format!("{label} component of the error at the first probe point over the day."),
            );
        }
        let w = column(&t, "thermal_weight");
        if w.iter().any(|&x| x < 1.0) {
            let pts: Vec<(f64, f64)> = (0..time_h.len().min(w.len()))
                .filter(|&i| probes.get(i) == Some(&first))
                .map(|i| (time_h[i], w[i]))
                .collect();
            sec.figure(
                line_chart(
                    "Thermal weight (envelope rule)",
                    "time (h)",
                    "weight",
                    &[Series::new("thermal weight", pts)],
                    &[],
                ),
                "1 inside the training envelope; fading to 0 (no thermal correction) outside it.",
            );
        }
    }
    Ok(())
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
