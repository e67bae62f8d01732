//! Figures of identified rotary-axis error motions: polar plots against the angle C and line
//! charts of their change with time (ballbar identification, `mtec identify ballbar`).
//!
//! Polar plot convention (as ballbar software draws it): each motion is drawn as a deviation
//! about a reference circle, radius = `R0 + gain·value`, with `R0` equal to the largest |value| of
//! the figure times 1.5 so that no curve crosses the centre; the dashed reference circle is zero
//! and the two light circles mark ±(largest |value|). The scale is in the caption of the figure.

use crate::plot::{colour, line_chart, Series};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One identified sample: experiment, time, angle and the values of the motions (in the order of
/// the `names` given to [`rotary_figures`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MotionSample {
    pub experiment: i64,
    pub time_min: f64,
    pub angle_deg: f64,
    pub values: Vec<f64>,
}

/// A figure: SVG text and a caption.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    pub name: String,
    pub svg: String,
    pub caption: String,
}

/// A polar chart of curves `(angle_deg, value)`, drawn as deviations about a reference circle.
pub fn polar_chart(title: &str, unit: &str, series: &[Series]) -> String {
    let peak = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1.abs()))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let peak = if peak > 0.0 { peak } else { 1.0 };
    let r0 = 1.5 * peak;
    // the angle labels sit 0.3·peak outside the outer circle: clear of the curves they name
    let lim = r0 + peak * 1.45;
    let to_xy = |a_deg: f64, v: f64| {
        let r = r0 + v;
        let a = a_deg.to_radians();
        (r * a.cos(), r * a.sin())
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (700, 520)).into_drawing_area();
        let _ = root.fill(&WHITE);
        // square polar area on the left, legend in the 180 px on the right
        let mut chart = match ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .margin_right(190)
            .build_cartesian_2d(-lim..lim, -lim..lim)
        {
            Ok(c) => c,
            Err(_) => return String::new(),
        };
        let circle = |r: f64| -> Vec<(f64, f64)> {
            (0..=180)
                .map(|i| {
                    let a = (i as f64 * 2.0).to_radians();
                    (r * a.cos(), r * a.sin())
                })
                .collect()
        };
        let grey = RGBColor(200, 200, 200);
        for r in [r0 - peak, r0 + peak] {
            let _ = chart.draw_series(std::iter::once(PathElement::new(circle(r), grey)));
        }
        let _ = chart.draw_series(DashedLineSeries::new(circle(r0), 4, 4, BLACK.into()));
        for a in (0..360).step_by(30) {
            let ar = (a as f64).to_radians();
            let (c, s) = (ar.cos(), ar.sin());
            let _ = chart.draw_series(std::iter::once(PathElement::new(
                vec![
                    ((r0 - peak) * c, (r0 - peak) * s),
                    ((r0 + peak) * c, (r0 + peak) * s),
                ],
                grey,
            )));
            let style = TextStyle::from(("sans-serif", 11).into_font())
                .pos(Pos::new(HPos::Center, VPos::Center));
            let rl = r0 + peak * 1.3;
            let _ = chart.draw_series(std::iter::once(Text::new(
                format!("{a}°"),
                (rl * c, rl * s),
                style,
            )));
        }
        for (i, s) in series.iter().enumerate() {
            let c = colour(i);
            let mut pts: Vec<(f64, f64)> = s.points.iter().map(|p| to_xy(p.0, p.1)).collect();
            if let Some(first) = pts.first().copied() {
                pts.push(first);
            }
            let _ = chart.draw_series(LineSeries::new(pts, c.stroke_width(2)));
        }
        let style = TextStyle::from(("sans-serif", 12).into_font());
        let _ = chart.draw_series(std::iter::once(Text::new(
            format!("circles: 0 (dashed), ±{peak:.3} {unit}"),
            (-lim * 0.97, -lim * 0.93),
            style.clone(),
        )));
        // legend in the free band right of the square polar area (pixel coordinates of the root)
        let x0 = 520;
        for (i, s) in series.iter().enumerate() {
            let y = 50 + 18 * i as i32;
            let c = colour(i);
            let _ = root.draw(&PathElement::new(
                vec![(x0, y), (x0 + 20, y)],
                c.stroke_width(2),
            ));
            let _ = root.draw(&Text::new(
                s.name.clone(),
                (x0 + 26, y),
                style.clone().pos(Pos::new(HPos::Left, VPos::Center)),
            ));
        }
        let _ = root.present();
    }
    svg
}

/// For each motion: a polar plot of the first and last time of every experiment, and a line
/// chart of its peak-to-valley over the revolution against time, one line per experiment.
/// `names` are the motion names with their unit suffix (e.g. `EXC_um`, `EAC_urad`).
pub fn rotary_figures(samples: &[MotionSample], names: &[&str]) -> Vec<Figure> {
    let mut experiments: Vec<i64> = samples.iter().map(|s| s.experiment).collect();
    experiments.sort_unstable();
    experiments.dedup();
    let mut figures = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let (motion, unit) = name.split_once('_').unwrap_or((name, ""));
        let mut polar = Vec::new();
        let mut pv = Vec::new();
        for &e in &experiments {
            let mut times: Vec<f64> = samples
                .iter()
                .filter(|s| s.experiment == e)
                .map(|s| s.time_min)
                .collect();
            times.sort_by(f64::total_cmp);
            times.dedup();
            let curve = |t: f64| -> Vec<(f64, f64)> {
                let mut c: Vec<(f64, f64)> = samples
                    .iter()
                    .filter(|s| s.experiment == e && s.time_min == t)
                    .filter_map(|s| s.values.get(k).map(|v| (s.angle_deg, *v)))
                    .collect();
                c.sort_by(|a, b| a.0.total_cmp(&b.0));
                c
            };
            if let (Some(&t0), Some(&t1)) = (times.first(), times.last()) {
                polar.push(Series::new(format!("exp {e}, {t0} min"), curve(t0)));
                if t1 != t0 {
                    polar.push(Series::new(format!("exp {e}, {t1} min"), curve(t1)));
                }
            }
            let points: Vec<(f64, f64)> = times
                .iter()
                .map(|&t| {
                    let c = curve(t);
                    let hi = c.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
                    let lo = c.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
                    (t, hi - lo)
                })
                .collect();
            pv.push(Series::new(format!("experiment {e}"), points));
        }
        figures.push(Figure {
            name: format!("polar_{motion}.svg"),
            svg: polar_chart(&format!("{motion} against C"), unit, &polar),
            caption: format!(
                "{motion} ({unit}) against the angle C, first and last measurement of each experiment \
                 (mean and first harmonic removed with the set-up error)"
            ),
        });
        figures.push(Figure {
            name: format!("time_{motion}.svg"),
            svg: line_chart(
                &format!("{motion}: peak-to-valley over one revolution"),
                "time (min)",
                &format!("{motion} peak-to-valley ({unit})"),
                &pv,
                &[],
            ),
            caption: format!("Change of {motion} with time (thermal), one line per experiment"),
        });
    }
    figures
}

/// One ballbar reading's bar-length change since its experiment's first measurement (same mode
/// and angle, µm, mean and first harmonic removed): measured, and predicted from a thermal
/// model's error motions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReadingSample {
    pub experiment: i64,
    pub time_min: f64,
    pub mode: i64,
    pub angle_deg: f64,
    pub predicted_change_um: f64,
    pub measured_change_um: f64,
}

/// The source's figure of predicted against measured ballbar readings, per experiment against
/// time: the bar-length change of the reading that changed most (its mode and angle named),
/// measured and predicted, and the largest |predicted − measured| over every mode and angle at
/// that time (what a compensation from the model would leave at worst).
pub fn readings_figure(samples: &[ReadingSample]) -> Figure {
    let mut experiments: Vec<i64> = samples.iter().map(|s| s.experiment).collect();
    experiments.sort_unstable();
    experiments.dedup();
    let mut series = Vec::new();
    for &e in &experiments {
        let of_e: Vec<&ReadingSample> = samples.iter().filter(|s| s.experiment == e).collect();
        let Some(peak) = of_e.iter().max_by(|a, b| {
            a.measured_change_um
                .abs()
                .total_cmp(&b.measured_change_um.abs())
        }) else {
            continue;
        };
        let mut at_peak: Vec<(f64, f64, f64)> = of_e
            .iter()
            .filter(|s| s.mode == peak.mode && s.angle_deg == peak.angle_deg)
            .map(|s| (s.time_min, s.measured_change_um, s.predicted_change_um))
            .collect();
        at_peak.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut times: Vec<f64> = of_e.iter().map(|s| s.time_min).collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let worst: Vec<(f64, f64)> = times
            .iter()
            .map(|&t| {
                let r = of_e
                    .iter()
                    .filter(|s| s.time_min == t)
                    .map(|s| (s.predicted_change_um - s.measured_change_um).abs())
                    .fold(0.0, f64::max);
                (t, r)
            })
            .collect();
        let at = format!("mode {}, C = {}°", peak.mode, peak.angle_deg);
        series.push(Series::new(
            format!("exp {e} measured ({at})"),
            at_peak.iter().map(|p| (p.0, p.1)).collect(),
        ));
        series.push(Series::new(
            format!("exp {e} predicted ({at})"),
            at_peak.iter().map(|p| (p.0, p.2)).collect(),
        ));
        series.push(Series::new(
            format!("exp {e} max |residual|, all readings"),
            worst,
        ));
    }
    Figure {
        name: "readings_predicted_vs_measured.svg".into(),
        svg: line_chart(
            "Ballbar readings: predicted against measured change",
            "time (min)",
            "bar-length change (µm)",
            &series,
            &[],
        ),
        caption: "Bar-length change since the first measurement of the reading that changed \
                  most, measured and predicted, and the largest |residual| over all modes and \
                  angles, against time"
            .into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polar_and_time_figures_carry_the_data() {
        let mut samples = Vec::new();
        for e in 1..=2 {
            for t in [0.0, 20.0, 40.0] {
                for i in 0..36 {
                    let a = i as f64 * 10.0;
                    let v = (1.0 + t / 40.0 * e as f64) * (2.0 * a.to_radians()).cos();
                    samples.push(MotionSample {
                        experiment: e,
                        time_min: t,
                        angle_deg: a,
                        values: vec![v, -v],
                    });
                }
            }
        }
        let f = rotary_figures(&samples, &["EXC_um", "EAC_urad"]);
        assert_eq!(f.len(), 4);
        assert_eq!(f[0].name, "polar_EXC.svg");
        // 4 curves of 37 points (closed) on the polar plot, legend names present
        assert!(f[0].svg.contains("exp 2, 40 min"), "legend");
        assert!(
            f[0].svg.contains("±3.000 um"),
            "peak of exp 2 at 40 min is 3"
        );
        assert!(f[1].svg.contains("experiment 1") && f[1].svg.contains("polyline"));
        assert!(f[3].svg.contains("EAC peak-to-valley (urad)"));
    }

    /// The reading that changed most is followed; the residual line is the worst over all
    /// readings at each time.
    #[test]
    fn readings_figure_follows_the_largest_change() {
        let mut samples = Vec::new();
        for (k, t) in [0.0, 20.0, 40.0].into_iter().enumerate() {
            for (mode, angle, gain) in [(1, 0.0, 1.0), (3, 90.0, 4.0)] {
                let m = gain * k as f64;
                // mode 3 at 40 min is predicted 2 µm short
                let p = if mode == 3 && k == 2 {
                    m - 2.0
                } else {
                    m + 0.5 * (k == 1) as i64 as f64
                };
                samples.push(ReadingSample {
                    experiment: 3,
                    time_min: t,
                    mode,
                    angle_deg: angle,
                    predicted_change_um: p,
                    measured_change_um: m,
                });
            }
        }
        let f = readings_figure(&samples);
        assert_eq!(f.name, "readings_predicted_vs_measured.svg");
        assert!(
            f.svg.contains("exp 3 measured (mode 3, C = 90°)"),
            "{}",
            f.svg
        );
        assert!(f.svg.contains("max |residual|") && f.svg.contains("polyline"));
        assert!(readings_figure(&[]).svg.contains("svg"));
    }
}
