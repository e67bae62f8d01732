//! Charts as SVG strings: line charts (with optional ±bands), grouped bar charts, scatter plots.
//! Drawn with plotters' SVG backend; no hand-written SVG.

use crate::legend::{self, Entry, Swatch};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Size (px) of the x–y charts' plot part; the legend strip is added to the width.
const CHART: (u32, u32) = (720, 420);
/// Tick labels and axis titles (px): readable at 100 % zoom in the report and on paper.
const TICK_FONT: u32 = 13;
const AXIS_FONT: u32 = 14;

/// A named series of (x, y) points.
#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
        }
    }
}

/// A shaded band (e.g. mean ± 2s, or an uncertainty band): lower and upper curves on the same x.
#[derive(Debug, Clone)]
pub struct Band {
    pub name: String,
    pub x: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// The colour of series `i`.
pub fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 1.0, hi + 1.0);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// The frame every x–y chart shares: caption, margins, axis labels, a light mesh.
fn xy_frame<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    title: &str,
    x_label: &str,
    y_label: &str,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Option<
    ChartContext<
        'a,
        SVGBackend<'b>,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .ok()?;
    let _ = chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", TICK_FONT))
        .axis_desc_style(("sans-serif", AXIS_FONT))
        .light_line_style(RGBColor(235, 235, 235))
        .draw();
    Some(chart)
}

/// A line chart of several series with optional bands. Returns SVG text.
pub fn line_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    bands: &[Band],
) -> String {
    let mut entries: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(i, s)| Entry::new(s.name.clone(), colour(i), Swatch::Line))
        .collect();
    // as many bands as series: band i belongs to series i and takes its colour (a mean and its
    // ±2s band); otherwise the bands take colours of their own
    let band_colour = |i: usize| {
        if bands.len() == series.len() {
            colour(i)
        } else {
            colour(i + series.len())
        }
    };
    entries.extend(
        bands
            .iter()
            .enumerate()
            .map(|(i, b)| Entry::new(b.name.clone(), band_colour(i).mix(0.3), Swatch::Box)),
    );
    let lw = legend::width(&entries);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (CHART.0 + lw, CHART.1)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let (plot, strip) = root.split_horizontally(CHART.0);
        let xs = series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .chain(bands.iter().flat_map(|b| b.x.iter().copied()));
        let ys = series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(
                bands
                    .iter()
                    .flat_map(|b| b.lower.iter().chain(b.upper.iter()).copied()),
            );
        let (x0, x1) = range(xs);
        let (y0, y1) = range(ys);
        let Some(mut chart) = xy_frame(&plot, title, x_label, y_label, (x0, x1), (y0, y1)) else {
            return svg_error(title);
        };
        for (i, b) in bands.iter().enumerate() {
            let c = band_colour(i).mix(0.18);
            let mut poly: Vec<(f64, f64)> =
                b.x.iter().zip(&b.upper).map(|(x, y)| (*x, *y)).collect();
            poly.extend(b.x.iter().zip(&b.lower).rev().map(|(x, y)| (*x, *y)));
            let _ = chart.draw_series(std::iter::once(Polygon::new(poly, c.filled())));
        }
        for (i, s) in series.iter().enumerate() {
            let _ = chart.draw_series(LineSeries::new(
                s.points.iter().copied(),
                colour(i).stroke_width(2),
            ));
        }
        legend::draw(&strip, &entries, 50);
        let _ = root.present();
    }
    svg
}

/// A scatter chart (e.g. measured vs predicted). Returns SVG text.
pub fn scatter_chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let entries: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(i, s)| Entry::new(s.name.clone(), colour(i), Swatch::Dot))
        .collect();
    let lw = legend::width(&entries);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (CHART.0 + lw, CHART.1)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let (plot, strip) = root.split_horizontally(CHART.0);
        let (x0, x1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
        let (y0, y1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
        let Some(mut chart) = xy_frame(&plot, title, x_label, y_label, (x0, x1), (y0, y1)) else {
            return svg_error(title);
        };
        for (i, s) in series.iter().enumerate() {
            let c = colour(i);
            let _ = chart.draw_series(s.points.iter().map(|p| Circle::new(*p, 2, c.filled())));
        }
        legend::draw(&strip, &entries, 50);
        let _ = root.present();
    }
    svg
}

/// A grouped bar chart: one group per category, one bar per series (e.g. S1 and ST per element).
pub fn bar_chart(
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<f64>)],
) -> String {
    bar_chart_with_errors(title, y_label, categories, series, &[])
}

/// [`bar_chart`] with whiskers: `errors[j]`, when present, holds the half-width of every bar
/// of series j.
pub fn bar_chart_with_errors(
    title: &str,
    y_label: &str,
    categories: &[String],
    series: &[(String, Vec<f64>)],
    errors: &[Option<Vec<f64>>],
) -> String {
    let entries: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(j, (name, _))| Entry::new(name.clone(), colour(j), Swatch::Box))
        .collect();
    let lw = legend::width(&entries);
    let mut svg = String::new();
    {
        let width =
            (120 + 40 * categories.len().max(1) * series.len().max(1)).clamp(480, 1100) as u32;
        let root = SVGBackend::with_string(&mut svg, (width + lw, CHART.1)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let (plot, strip) = root.split_horizontally(width);
        let whisker = |j: usize, i: usize| {
            errors
                .get(j)
                .and_then(|e| e.as_ref())
                .and_then(|e| e.get(i))
                .copied()
                .filter(|e| e.is_finite())
                .unwrap_or(0.0)
        };
        let (mut y0, y1) = range(
            series
                .iter()
                .enumerate()
                .flat_map(|(j, s)| {
                    s.1.iter()
                        .enumerate()
                        .flat_map(move |(i, v)| [*v - whisker(j, i), *v + whisker(j, i)])
                })
                .chain(std::iter::once(0.0)),
        );
        if y0 > 0.0 {
            y0 = 0.0;
        }
        let n = categories.len().max(1) as f64;
        let mut chart = match ChartBuilder::on(&plot)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..n, y0..y1)
        {
            Ok(c) => c,
            Err(_) => return svg_error(title),
        };
        let _ = chart
            .configure_mesh()
            .disable_x_mesh()
            .disable_x_axis()
            .y_desc(y_label)
            .label_style(("sans-serif", TICK_FONT))
            .axis_desc_style(("sans-serif", AXIS_FONT))
            .draw();
        // category names under each group (categorical axis)
        let style = TextStyle::from(("sans-serif", TICK_FONT).into_font())
            .pos(Pos::new(HPos::Center, VPos::Top));
        let _ = chart.draw_series(
            categories
                .iter()
                .enumerate()
                .map(|(i, c)| Text::new(c.clone(), (i as f64 + 0.5, y0), style.clone())),
        );
        let k = series.len().max(1) as f64;
        for (j, (_, vals)) in series.iter().enumerate() {
            let c = colour(j);
            let bars = vals.iter().enumerate().map(move |(i, v)| {
                let x0 = i as f64 + 0.1 + 0.8 * j as f64 / k;
                let x1 = x0 + 0.8 / k;
                Rectangle::new([(x0, 0.0), (x1, *v)], c.filled())
            });
            let _ = chart.draw_series(bars);
            let whiskers = vals.iter().enumerate().filter_map(|(i, v)| {
                let e = whisker(j, i);
                let xm = i as f64 + 0.1 + 0.8 * (j as f64 + 0.5) / k;
                (e > 0.0).then(|| PathElement::new(vec![(xm, v - e), (xm, v + e)], BLACK))
            });
            let _ = chart.draw_series(whiskers);
        }
        legend::draw(&strip, &entries, 50);
        let _ = root.present();
    }
    svg
}

/// One arrow of a [`quiver_chart`]: at (x, y) (axis units), the vector (dx, dy) (vector units).
#[derive(Debug, Clone, Copy)]
pub struct Arrow {
    pub x: f64,
    pub y: f64,
    pub dx: f64,
    pub dy: f64,
}

/// Arrows over a plane (e.g. the volumetric error in XY over the workspace), drawn at equal
/// scale in x and y on the page whatever the axes' ranges: an arrow of `full_scale` vector
/// units is 0.8 of the smaller grid step long, so two charts drawn with the same `full_scale`
/// compare by eye; a reference arrow of `reference` units with its label sits beside the plot.
/// Returns SVG text.
pub fn quiver_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    arrows: &[Arrow],
    full_scale: f64,
    (reference, reference_label): (f64, &str),
) -> String {
    // the smallest spacing of the arrows' positions along each axis
    let step = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.windows(2)
            .map(|w| w[1] - w[0])
            .filter(|d| *d > 1e-9)
            .fold(f64::INFINITY, f64::min)
    };
    let (sx, sy) = (
        step(&mut arrows.iter().map(|a| a.x).collect()),
        step(&mut arrows.iter().map(|a| a.y).collect()),
    );
    let (sx, sy) = (
        if sx.is_finite() { sx } else { 1.0 },
        if sy.is_finite() { sy } else { 1.0 },
    );
    // the strip beside the plot holds the scale: a reference arrow and its length
    let lw = 150;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (CHART.0 + lw, CHART.1)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let (plot, strip) = root.split_horizontally(CHART.0);
        // one grid step of margin round the positions: room for the arrows
        let (x0, x1) = range(arrows.iter().flat_map(|a| [a.x - sx, a.x + sx]));
        let (y0, y1) = range(arrows.iter().flat_map(|a| [a.y - sy, a.y + sy]));
        let Some(mut chart) = xy_frame(&plot, title, x_label, y_label, (x0, x1), (y0, y1)) else {
            return svg_error(title);
        };
        // pixels per axis unit, each way
        let (ax, ay) = chart.backend_coord(&(x0, y0));
        let (bx, by) = chart.backend_coord(&(x1, y1));
        let kx = (bx - ax).abs() as f64 / (x1 - x0);
        let ky = (by - ay).abs() as f64 / (y1 - y0);
        // pixels per vector unit, the same in both directions
        let g = 0.8 * (sx * kx).min(sy * ky) / full_scale.max(1e-12);
        let c = colour(0);
        for a in arrows {
            let end = (a.x + a.dx * g / kx, a.y + a.dy * g / ky);
            let _ = chart.draw_series(std::iter::once(PathElement::new(
                vec![(a.x, a.y), end],
                c.stroke_width(2),
            )));
            let _ = chart.draw_series(std::iter::once(Circle::new(end, 2, c.filled())));
            let _ = chart.draw_series(std::iter::once(Circle::new((a.x, a.y), 1, BLACK.filled())));
        }
        let len = ((reference * g).round() as i32).clamp(2, lw as i32 - 20);
        let text = TextStyle::from(("sans-serif", 13).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        let _ = strip.draw(&Text::new("scale", (8, 50), text.clone()));
        let _ = strip.draw(&PathElement::new(
            vec![(8, 72), (8 + len, 72)],
            c.stroke_width(2),
        ));
        let _ = strip.draw(&Circle::new((8 + len, 72), 2, c.filled()));
        let _ = strip.draw(&Text::new(reference_label.to_string(), (8, 94), text));
        let _ = root.present();
    }
    svg
}

fn svg_error(title: &str) -> String {
    format!("<svg xmlns='http://www.w3.org/2000/svg' width='400' height='40'><text x='5' y='25'>{}: no data to plot</text></svg>", crate::html::escape(title))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charts_draw_their_data() {
        let s = Series::new(
            "sin",
            (0..50)
                .map(|i| (i as f64, (i as f64 / 5.0).sin()))
                .collect(),
        );
        let svg = line_chart(
            "t",
            "x",
            "y",
            &[s],
            &[Band {
                name: "band".into(),
                x: vec![0.0, 49.0],
                lower: vec![-1.0, -1.0],
                upper: vec![1.0, 1.0],
            }],
        );
        assert!(
            svg.starts_with("<svg") && svg.contains("polyline") || svg.contains("path"),
            "{}",
            &svg[..200.min(svg.len())]
        );
        let b = bar_chart(
            "b",
            "S",
            &["EXX".into(), "EYY".into()],
            &[("S1".into(), vec![0.5, 0.2]), ("ST".into(), vec![0.6, 0.3])],
        );
        assert!(b.contains("EXX") && b.matches("<rect").count() >= 4);
    }
}
