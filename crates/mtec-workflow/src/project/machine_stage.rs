//! The `[machine_model]` and `[[replay]]` stages of `mtec run`: the thermal models of the
//! project's [[thermal]] stages become one machine error model (`mtec machine build`), and
//! recorded days are compensated through the real-time path (`mtec machine replay`), reported
//! as the error at the tool tip before and after over time. Both run `crate::ops::machine`
//! in-process.

use super::pipeline::{s, Pipeline};
use super::spec::{MachineModelStage, ReplayStage};
use crate::ops::machine;
use crate::Error;
use mtec_comp::replay::ReplaySample;
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
    p.json_result(
        &format!("replay-{tag}.json"),
        &format!(
            "{}\n",
            serde_json::to_string_pretty(&serde_json::to_value(&done)?)?
        ),
    )?;
    p.outputs.push(s(&csv));
    let sec = p.report.section(format!("Compensation replay: {name}"));
    sec.text("The recorded day compensated exactly as the real-time library would have done it: at each probe reading the model has received every state reading up to that moment (update_state), then gives the correction for the probe point (correction_um). The error after compensation is the measured error plus the correction.");
    let sum = &done.summary;
    let rows = [
        ("X", &sum.x),
        ("Y", &sum.y),
        ("Z", &sum.z),
        ("vector", &sum.vector),
    ]
    .into_iter()
    .map(|(label, r)| {
        vec![
            label.to_string(),
            format!("{:.3}", r.rms_before_um),
            format!("{:.3}", r.rms_after_um),
            format!("{:.3}", r.max_before_um),
            format!("{:.3}", r.max_after_um),
            format!("{:.1} %", 100.0 * r.compensation_rate),
            format!("{:.1} %", 100.0 * r.worst_reduction),
        ]
    })
    .collect();
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
    let n = |x: f64| super::stages::fmt_value(&serde_json::json!(x));
    sec.text(format!(
        "{} probe readings; {} made worse by the compensation (largest increase of |e| {} µm); {} taken with the thermal part faded (smallest weight {}).",
        sum.readings,
        sum.worse,
        n(sum.largest_worsening_um),
        sum.faded,
        n(sum.min_thermal_weight)
    ));
    replay_figures(sec, &done.samples);
    Ok(())
}

/// The error at the tool tip over the day, before and after, from the compensated readings.
fn replay_figures(sec: &mut mtec_report::Section, samples: &[ReplaySample]) {
    let Some(first) = samples.first().map(|r| r.probe.clone()) else {
        return;
    };
    let norm = |e: &[f64; 3]| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    // the worst probe at each moment: |e| before and after
    let mut worst_b: Vec<(f64, f64)> = Vec::new();
    let mut worst_a: Vec<(f64, f64)> = Vec::new();
    for r in samples {
        let (h, nb, na) = (r.time_min / 60.0, norm(&r.before_um), norm(&r.after_um));
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
    let at_first = || samples.iter().filter(|r| r.probe == first);
    for (i, label) in ["X", "Y", "Z"].into_iter().enumerate() {
        let pick = |e: fn(&ReplaySample) -> [f64; 3]| -> Vec<(f64, f64)> {
            at_first().map(|r| (r.time_min / 60.0, e(r)[i])).collect()
        };
        sec.figure(
            line_chart(
                &format!("{label} error at probe point `{first}`"),
                "time (h)",
                &format!("e{} (µm)", label.to_lowercase()),
                &[
                    Series::new("without compensation", pick(|r| r.before_um)),
                    Series::new("compensated", pick(|r| r.after_um)),
                ],
                &[],
            ),
            format!("{label} component of the error at the first probe point over the day."),
        );
    }
    if samples.iter().any(|r| r.thermal_weight < 1.0) {
        let pts: Vec<(f64, f64)> = at_first()
            .map(|r| (r.time_min / 60.0, r.thermal_weight))
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

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
