//! Polar plot of circular-test (ballbar) traces as SVG, the way ballbar software shows them:
//! the deviation from the least-squares circle is drawn magnified around a reference ring, with
//! grid rings one scale division apart and spokes every 30°.
//!
//! Mapping: a deviation `dev` (µm) at angle θ is drawn at plot radius `ring + dev`, where `ring`
//! (in µm of the plot) is 4 divisions, and a division is chosen from 1-2-5 steps so that the
//! largest |deviation| fits in 3 divisions (or set by [`PolarOptions::um_per_div`]). Inward and
//! outward deviations therefore stay readable and the centre of the plot is not the machine's
//! circle centre but the reference circle's (as on every ballbar plot).

use crate::legend::{self, Entry, Swatch};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One trace to draw: angles (deg) and deviations from the reference circle (µm).
#[derive(Debug, Clone)]
pub struct PolarTrace<'a> {
    pub label: &'a str,
    pub angles_deg: &'a [f64],
    pub deviations_um: &'a [f64],
    pub color: (u8, u8, u8),
}

/// Size, title and scale of the plot.
#[derive(Debug, Clone)]
pub struct PolarOptions {
    pub title: String,
    pub width: u32,
    pub height: u32,
    /// Scale (µm per grid division); chosen automatically when `None`.
    pub um_per_div: Option<f64>,
}

impl Default for PolarOptions {
    fn default() -> Self {
        PolarOptions {
            title: "Circular test".into(),
            width: 640,
            height: 640,
            um_per_div: None,
        }
    }
}

/// Why a plot could not be drawn.
#[derive(Debug, Clone, PartialEq)]
pub enum PlotError {
    /// The data cannot be drawn (no samples, mismatched lengths, non-finite values).
    Empty(String),
    /// The drawing backend failed.
    Backend(String),
}

impl std::fmt::Display for PlotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PlotError::Empty(m) => write!(f, "nothing to plot: {m}"),
            PlotError::Backend(m) => write!(f, "plotting failed: {m}"),
        }
    }
}

impl std::error::Error for PlotError {}

fn backend<E: std::fmt::Debug>(e: E) -> PlotError {
    PlotError::Backend(format!("{e:?}"))
}

/// A 1-2-5 step at least `x`.
pub fn nice_step(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 || !x.is_finite() {
        return 1.0;
    }
    let p = 10f64.powf(x.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if m * p >= x {
            return m * p;
        }
    }
    10.0 * p
}

/// Number of grid divisions from the centre to the reference ring.
pub const RING_DIVS: f64 = 4.0;

/// Plot coordinates (µm of the plot) of a deviation at an angle.
pub fn plot_point(angle_deg: f64, dev_um: f64, um_per_div: f64) -> (f64, f64) {
    let r = RING_DIVS * um_per_div + dev_um;
    let t = angle_deg.to_radians();
    (r * t.cos(), r * t.sin())
}

/// Draws the traces into an SVG document (returned as text).
pub fn polar_svg(traces: &[PolarTrace], opts: &PolarOptions) -> Result<String, PlotError> {
    let mut max_dev: f64 = 0.0;
    for t in traces {
        if t.angles_deg.len() != t.deviations_um.len() {
            return Err(PlotError::Empty(format!(
                "trace `{}` has {} angles but {} deviations",
                t.label,
                t.angles_deg.len(),
                t.deviations_um.len()
            )));
        }
        for v in t.deviations_um.iter().chain(t.angles_deg) {
            if !v.is_finite() {
                return Err(PlotError::Empty(format!(
                    "trace `{}` holds a value that is not finite",
                    t.label
                )));
            }
        }
        max_dev = t.deviations_um.iter().fold(max_dev, |m, v| m.max(v.abs()));
    }
    if traces.iter().all(|t| t.angles_deg.is_empty()) {
        return Err(PlotError::Empty("no samples".into()));
    }
    let div = opts.um_per_div.unwrap_or_else(|| nice_step(max_dev / 3.0));
    let outer = (RING_DIVS + (max_dev / div).ceil().max(1.0)) * div;
    let lim = outer * 1.12;

    let mut svg = String::new();
    {
        let entries: Vec<Entry> = traces
            .iter()
            .map(|t| {
                Entry::new(
                    t.label,
                    RGBColor(t.color.0, t.color.1, t.color.2),
                    Swatch::Line,
                )
            })
            .collect();
        let lw = legend::width(&entries);
        let root =
            SVGBackend::with_string(&mut svg, (opts.width + lw, opts.height)).into_drawing_area();
        root.fill(&WHITE).map_err(backend)?;
        // title on top, scale note at the bottom, a square plot area between (so circles stay round)
        let (title, rest) = root.split_vertically(36);
        let (body, footer) = rest.split_vertically(opts.height.saturating_sub(36 + 30));
        title
            .draw(&Text::new(
                opts.title.clone(),
                (opts.width as i32 / 2, 10),
                TextStyle::from(("sans-serif", 20).into_font())
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            ))
            .map_err(backend)?;
        let (body, strip) = body.split_horizontally(opts.width);
        let (w, h) = body.dim_in_pixel();
        let side = w.min(h);
        let square = body.shrink(((w - side) / 2, (h - side) / 2), (side, side));
        let mut chart = ChartBuilder::on(&square)
            .margin(8)
            .build_cartesian_2d(-lim..lim, -lim..lim)
            .map_err(backend)?;
        let grid = RGBColor(200, 200, 200);
        let circle = |r: f64| -> Vec<(f64, f64)> {
            (0..=360)
                .map(|k| {
                    let t = (k as f64).to_radians();
                    (r * t.cos(), r * t.sin())
                })
                .collect()
        };
        // grid rings one division apart; the reference ring (deviation 0) darker
        let mut k = 1.0;
        while k * div <= outer + 1e-9 {
            let style = if (k - RING_DIVS).abs() < 1e-9 {
                ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(2)
            } else {
                ShapeStyle::from(&grid).stroke_width(1)
            };
            chart
                .draw_series(std::iter::once(PathElement::new(circle(k * div), style)))
                .map_err(backend)?;
            k += 1.0;
        }
        // spokes every 30° with angle labels
        for a in (0..360).step_by(30) {
            let t = (a as f64).to_radians();
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(0.0, 0.0), (outer * t.cos(), outer * t.sin())],
                    ShapeStyle::from(&grid).stroke_width(1),
                )))
                .map_err(backend)?;
            let style = TextStyle::from(("sans-serif", 13).into_font())
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center));
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{a}°"),
                    (1.06 * outer * t.cos(), 1.06 * outer * t.sin()),
                    style,
                )))
                .map_err(backend)?;
        }
        // traces, closed
        for tr in traces {
            let color = RGBColor(tr.color.0, tr.color.1, tr.color.2);
            let mut idx: Vec<usize> = (0..tr.angles_deg.len()).collect();
            idx.sort_by(|&i, &j| tr.angles_deg[i].total_cmp(&tr.angles_deg[j]));
            let mut pts: Vec<(f64, f64)> = idx
                .iter()
                .map(|&i| plot_point(tr.angles_deg[i], tr.deviations_um[i], div))
                .collect();
            if let Some(&first) = pts.first() {
                pts.push(first);
            }
            chart
                .draw_series(LineSeries::new(
                    pts,
                    ShapeStyle::from(&color).stroke_width(2),
                ))
                .map_err(backend)?;
        }
        // the legend beside the square plot, never over the traces
        legend::draw(&strip, &entries, 20);
        footer
            .draw(&Text::new(
                format!("scale {div} um/div; reference circle = least-squares circle"),
                (10, 12),
                ("sans-serif", 14).into_font(),
            ))
            .map_err(backend)?;
        root.present().map_err(backend)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(0.7), 1.0);
        assert_eq!(nice_step(1.3), 2.0);
        assert_eq!(nice_step(3.0), 5.0);
        assert_eq!(nice_step(7.0), 10.0);
        assert_eq!(nice_step(0.013), 0.02);
    }

    #[test]
    fn draws_traces_rings_and_labels() {
        let a: Vec<f64> = (0..360).map(|k| k as f64).collect();
        let cw: Vec<f64> = a
            .iter()
            .map(|t| 2.0 * (2.0 * t.to_radians()).cos())
            .collect();
        let ccw: Vec<f64> = a.iter().map(|t| -(3.0 * t.to_radians()).sin()).collect();
        let svg = polar_svg(
            &[
                PolarTrace {
                    label: "cw",
                    angles_deg: &a,
                    deviations_um: &cw,
                    color: (200, 30, 30),
                },
                PolarTrace {
                    label: "ccw",
                    angles_deg: &a,
                    deviations_um: &ccw,
                    color: (30, 30, 200),
                },
            ],
            &PolarOptions::default(),
        )
        .unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..60]);
        assert!(svg.contains("cw") && svg.contains("ccw"));
        assert!(svg.contains("90°") && svg.contains("330°"));
        assert!(
            svg.contains("scale 1 um/div"),
            "max 2 µm / 3 → 1 µm per division"
        );
        assert!(
            svg.contains("rgb(200,30,30)") || svg.contains("#C81E1E"),
            "trace colour drawn"
        );
        assert!(!svg.contains("NaN"));
        // plot radius of a deviation: ring at 4 divisions + deviation
        let (x, y) = plot_point(90.0, 2.0, 1.0);
        assert!(x.abs() < 1e-12 && (y - 6.0).abs() < 1e-12);
    }

    #[test]
    fn refuses_bad_traces() {
        let a = [0.0, 1.0];
        let d = [0.0];
        let t = PolarTrace {
            label: "x",
            angles_deg: &a,
            deviations_um: &d,
            color: (0, 0, 0),
        };
        assert!(polar_svg(&[t], &PolarOptions::default()).is_err());
        let d = [0.0, f64::NAN];
        let t = PolarTrace {
            label: "x",
            angles_deg: &a,
            deviations_um: &d,
            color: (0, 0, 0),
        };
        assert!(polar_svg(&[t], &PolarOptions::default()).is_err());
    }
}
