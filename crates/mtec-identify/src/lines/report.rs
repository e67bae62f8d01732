//! The identification report (`"format": "mtec.identify-lines/1"`) and its text form.

use super::data::{ChannelKind, LineData};
use super::identifiability::{drop_priority, Analysis};
use super::model::Layout;
use super::solve::Fit;
use super::validity;
use mtec_model::Machine;
use serde::Serialize;
use std::fmt::Write;

/// Format tag of the report JSON.
pub const REPORT_FORMAT: &str = "mtec.identify-lines/1";

#[derive(Debug, Clone, Serialize)]
pub struct ChannelSummary {
    pub name: String,
    /// Repeat run (1 when the file has no `run` column).
    pub run: i64,
    pub kind: ChannelKind,
    pub u: [f64; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct LineSummary {
    pub name: String,
    pub start_mm: [f64; 3],
    pub end_mm: [f64; 3],
    pub points: usize,
    /// Axes moving along the line, e.g. "XY".
    pub moving_axes: String,
    pub channels: Vec<ChannelSummary>,
}

#[derive(Debug, Clone, Serialize)]
pub struct UnidentifiableReport {
    pub element: String,
    pub description: String,
    pub confounded_with: Vec<String>,
    pub with_alignment: bool,
    pub reason: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct ElementReport {
    pub element: String,
    pub description: String,
    pub unit: String,
    /// max |f(q)| over the travel.
    pub max_abs_value: f64,
    /// max over the travel of the 1σ uncertainty of f(q).
    pub uncertainty_1sigma: f64,
    /// Unidentifiable elements whose effect this one absorbs at the measured poses.
    pub absorbs: Vec<String>,
    /// Polynomial degree of its function (0 for a squareness constant).
    pub degree: usize,
    /// Period (mm) of its pitch-error pair, when it has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pitch_period_mm: Option<f64>,
    /// Interior knots (mm) of a cubic-spline function (`degree` is then 3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spline_knots_mm: Option<Vec<f64>>,
}

#[derive(Debug, Clone, Serialize)]
pub struct SlopeReport {
    pub channel: String,
    pub slope_urad: f64,
    pub sigma_urad: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct LinesReport {
    pub format: String,
    pub data: String,
    pub machine: String,
    pub tool_offset_mm: [f64; 3],
    pub degree: usize,
    pub lines: Vec<LineSummary>,
    pub readings: usize,
    /// Parameters of the full model (coefficients, squareness, alignment slopes).
    pub parameters: usize,
    /// Numerical rank of the full, column-scaled design.
    pub rank: usize,
    pub rank_deficiency: usize,
    /// Singular values of the full column-scaled design, descending.
    pub singular_values: Vec<f64>,
    /// Condition number of the kept (identifiable) design, column-scaled.
    pub condition_number: f64,
    pub unidentifiable: Vec<UnidentifiableReport>,
    pub elements: Vec<ElementReport>,
    pub alignment: Vec<SlopeReport>,
    pub residual_rms_um: f64,
    /// √(RSS/dof): the reading noise the fit implies.
    pub sigma_um: f64,
    pub dof: usize,
    pub channel_residual_rms_um: Vec<(String, f64)>,
    pub validity: String,
    /// False when a check of [`super::validity`] says the result cannot be trusted.
    pub valid: bool,
    /// Why not (one line each).
    pub warnings: Vec<String>,
    /// Pure error of the repeat runs, µm (None with one run).
    pub repeatability_um: Option<f64>,
    /// σ̂ / repeatability.
    pub residual_to_repeatability: Option<f64>,
    /// Largest amplification Λ of a function's fit between the measured positions.
    pub amplification: f64,
    /// The cross-validated choice of the degrees (`--degree auto`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub selection: Option<super::select::Selection>,
}

/// Builds the report.
pub fn build(
    machine: &Machine,
    data: &LineData,
    degree: usize,
    layout: &Layout,
    an: &Analysis,
    fit: &Fit,
) -> LinesReport {
    let mut lines: Vec<LineSummary> = Vec::new();
    for c in &data.channels {
        let summary = ChannelSummary {
            name: c.name.clone(),
            run: c.run,
            kind: c.kind,
            u: c.u,
        };
        match lines.iter_mut().find(|l| l.name == c.line) {
            Some(l) => l.channels.push(summary),
            None => lines.push(LineSummary {
                name: c.line.clone(),
                start_mm: c.points_mm[0],
                end_mm: *c.points_mm.last().expect("≥ 3 points"),
                points: c.points_mm.len(),
                moving_axes: c.moving_axes.iter().map(|a| a.letter()).collect(),
                channels: vec![summary],
            }),
        }
    }
    let unidentifiable: Vec<UnidentifiableReport> = an
        .dropped
        .iter()
        .map(|d| {
            let partners: Vec<String> = d.confounded_with.iter().map(|e| e.name()).collect();
            let reason = if d.zero_sensitivity {
                "reaches no reading: at this tool offset it does not move the tool tip relative to the workpiece at any measured pose".to_string()
            } else {
                let mut r = format!(
                    "confounded at the measured poses with {}{}",
                    if partners.is_empty() {
                        "nothing else identifiable".to_string()
                    } else {
                        partners.join(", ")
                    },
                    if d.with_alignment {
                        " and the straightness alignment slopes"
                    } else {
                        ""
                    }
                );
                let b = layout.block(&d.element).expect("block");
                if drop_priority(b) == 4 {
                    r.push_str("; a tool-side angular error acts through the fixed tool offset only");
                }
                r
            };
            UnidentifiableReport {
                element: d.element.name(),
                description: d.element.describe(),
                confounded_with: partners,
                with_alignment: d.with_alignment,
                reason,
            }
        })
        .collect();
    let elements: Vec<ElementReport> = layout
        .blocks
        .iter()
        .filter(|b| !an.dropped.iter().any(|d| d.element == b.element))
        .map(|b| {
            let (max_abs_value, uncertainty_1sigma) = fit.envelope(an, b);
            ElementReport {
                element: b.element.name(),
                description: b.element.describe(),
                unit: b.element.unit().into(),
                max_abs_value,
                uncertainty_1sigma,
                absorbs: an
                    .dropped
                    .iter()
                    .filter(|d| d.confounded_with.contains(&b.element))
                    .map(|d| d.element.name())
                    .collect(),
                degree: b.degree(),
                pitch_period_mm: b.period_mm,
                spline_knots_mm: b.spline.as_ref().map(|s| s.interior.clone()),
            }
        })
        .collect();
    let m = fit.residual_um.len();
    let condition_number = an.condition_number();
    let rep = validity::repeatability(data, &fit.residual_um);
    let ratio = rep.map(|(r, _)| fit.sigma_um / r);
    let worst = validity::worst_amplification(layout, data);
    let mut warnings = Vec::new();
    if condition_number > validity::COND_LIMIT {
        warnings.push(format!(
            "the design's condition number {condition_number:.2e} exceeds {:.0e}: the parameters are not determined to the readings' precision",
            validity::COND_LIMIT
        ));
    }
    if let Some((el, d, l)) = &worst {
        if *l > validity::LAMBDA_LIMIT {
            warnings.push(format!(
                "degree {d} is more than the measured positions support: between them {el} may amplify a reading error {l:.1}x (limit {}); lower the degree or measure more points",
                validity::LAMBDA_LIMIT
            ));
        }
    }
    if let (Some(r), Some((rep_um, _))) = (ratio, rep) {
        if r > validity::RATIO_LIMIT {
            warnings.push(format!(
                "the fit's residual ({:.3} um) is {r:.1}x the repeatability of the runs ({rep_um:.3} um): the error functions do not follow the machine's shape; raise the degree or use --degree auto",
                fit.sigma_um
            ));
        }
    }
    LinesReport {
        format: REPORT_FORMAT.into(),
        data: data.source.clone(),
        machine: format!("{} ({})", machine.name, machine.chain.text),
        tool_offset_mm: machine.tool_offset_mm,
        degree,
        lines,
        readings: m,
        parameters: layout.n_cols,
        rank: an.rank,
        rank_deficiency: layout.n_cols - an.rank,
        singular_values: an.singular_values.clone(),
        condition_number,
        unidentifiable,
        elements,
        alignment: fit
            .slopes(an, layout, data)
            .into_iter()
            .map(|(channel, slope_urad, sigma_urad)| SlopeReport {
                channel,
                slope_urad,
                sigma_urad,
            })
            .collect(),
        residual_rms_um: (fit.residual_um.norm_squared() / m as f64).sqrt(),
        sigma_um: fit.sigma_um,
        dof: fit.dof,
        channel_residual_rms_um: fit.channel_rms(data),
        validity: format!(
            "predictions are valid for the measured tool offset {:?} mm; unidentifiable elements are absorbed by their partners there",
            machine.tool_offset_mm
        ),
        valid: warnings.is_empty(),
        warnings,
        repeatability_um: rep.map(|r| r.0),
        residual_to_repeatability: ratio,
        amplification: worst.map_or(0.0, |w| w.2),
        selection: None,
    }
}

impl LinesReport {
    /// The human-readable report.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "Line identification: {}", self.data);
        let _ = writeln!(
            s,
            "Machine: {}, tool offset {:?} mm",
            self.machine, self.tool_offset_mm
        );
        let _ = writeln!(
            s,
            "Design: {} lines, {} readings; polynomial degree {}; {} parameters",
            self.lines.len(),
            self.readings,
            self.degree,
            self.parameters
        );
        for l in &self.lines {
            let mut ch: Vec<&str> = Vec::new();
            for c in &l.channels {
                if !ch.contains(&c.name.as_str()) {
                    ch.push(c.name.as_str());
                }
            }
            let runs = l.channels.iter().map(|c| c.run).max().unwrap_or(1);
            let runs = if runs > 1 {
                format!(" ({runs} runs)")
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "  {:<6} {:<3} {:>3} points  ({:.1}, {:.1}, {:.1}) -> ({:.1}, {:.1}, {:.1})  channels {}{}",
                l.name,
                l.moving_axes,
                l.points,
                l.start_mm[0],
                l.start_mm[1],
                l.start_mm[2],
                l.end_mm[0],
                l.end_mm[1],
                l.end_mm[2],
                ch.join(" "),
                runs
            );
        }
        let _ = writeln!(
            s,
            "\nIdentifiability: rank {} of {} (deficiency {}); singular values (column-scaled) {:.3e} .. {:.3e}",
            self.rank,
            self.parameters,
            self.rank_deficiency,
            self.singular_values.first().copied().unwrap_or(0.0),
            self.singular_values.last().copied().unwrap_or(0.0)
        );
        let _ = writeln!(
            s,
            "Condition number of the identifiable part: {:.3e}",
            self.condition_number
        );
        if self.unidentifiable.is_empty() {
            let _ = writeln!(s, "Every element is identifiable.");
        } else {
            let _ = writeln!(s, "Not identifiable (no numbers are given for these):");
            for u in &self.unidentifiable {
                let _ = writeln!(s, "  {:<5} {}: {}", u.element, u.description, u.reason);
            }
        }
        let _ = writeln!(
            s,
            "\nFit: residual RMS {:.3} um, noise estimate {:.3} um ({} degrees of freedom)",
            self.residual_rms_um, self.sigma_um, self.dof
        );
        if let (Some(r), Some(q)) = (self.repeatability_um, self.residual_to_repeatability) {
            let _ = writeln!(
                s,
                "Repeatability of the runs {r:.3} um: residual/repeatability {q:.2}"
            );
        }
        if let Some(sel) = &self.selection {
            let d = sel.chosen;
            let _ = writeln!(
                s,
                "Degrees chosen by cross-validation over the points ({} choices scored): positioning {}, straightness {}, angular {}; held-out RMS {:.3} um",
                sel.trials.len(),
                d.positioning,
                d.straightness,
                d.angular,
                sel.cv_rms_um
            );
        }
        let _ = writeln!(
            s,
            "Largest amplification between measured positions: {:.2}",
            self.amplification
        );
        let _ = writeln!(
            s,
            "\n{:<6} {:>12} {:>12}  {:<6} description",
            "element", "max |value|", "1 sigma", "unit"
        );
        for e in &self.elements {
            let _ = writeln!(
                s,
                "{:<6} {:>12.3} {:>12.3}  {:<6} {}{}",
                e.element,
                e.max_abs_value,
                e.uncertainty_1sigma,
                e.unit,
                e.description,
                if e.absorbs.is_empty() {
                    String::new()
                } else {
                    format!(" (absorbs {})", e.absorbs.join(", "))
                }
            );
        }
        if !self.alignment.is_empty() {
            let _ = writeln!(s, "\nStraightness alignment slopes (nuisance, urad):");
            for a in &self.alignment {
                let _ = writeln!(
                    s,
                    "  {:<8} {:>9.3} +- {:.3}",
                    a.channel, a.slope_urad, a.sigma_urad
                );
            }
        }
        let _ = writeln!(s, "\nNote: {}", self.validity);
        if !self.valid {
            let _ = writeln!(s, "NOT VALID:");
            for w in &self.warnings {
                let _ = writeln!(s, "  warning: {w}");
            }
        }
        s
    }
}
