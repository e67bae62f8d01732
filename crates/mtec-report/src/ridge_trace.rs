//! The ridge-trace plot (SVG, drawn with plotters): standardised coefficient of each sensor
//! against k on a log axis, with the chosen k marked (Hoerl & Kennard 1970, the trace of
//! `mtec_thermal::select::RidgeTrace`).

use crate::legend::{self, Entry, Swatch};
use plotters::prelude::*;

/// A ridge trace as plain numbers: `coefficients[i][j]` is sensor j's standardised coefficient
/// at `k[i]`.
pub struct RidgeTrace<'a> {
    pub sensors: &'a [String],
    pub k: &'a [f64],
    pub coefficients: &'a [Vec<f64>],
}

/// Renders the trace (k > 0 only; k = 0 cannot sit on a log axis) as SVG text.
pub fn ridge_trace_svg(trace: &RidgeTrace, chosen_k: f64) -> Result<String, String> {
    let mut svg = String::new();
    {
        let mut entries: Vec<Entry> = trace
            .sensors
            .iter()
            .enumerate()
            .map(|(j, name)| Entry::new(name.clone(), Palette99::pick(j), Swatch::Line))
            .collect();
        entries.push(Entry::new(
            format!("chosen k = {chosen_k:.4}"),
            BLACK,
            Swatch::Line,
        ));
        let lw = legend::width(&entries);
        let root = SVGBackend::with_string(&mut svg, (900 + lw, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (plot, strip) = root.split_horizontally(900);
        let pts: Vec<(usize, f64)> = trace
            .k
            .iter()
            .enumerate()
            .filter(|(_, k)| **k > 0.0)
            .map(|(i, k)| (i, *k))
            .collect();
        let (kmin, kmax) = (
            pts.first().map(|p| p.1).unwrap_or(1e-4),
            pts.last().map(|p| p.1).unwrap_or(1.0),
        );
        let (lo, hi) = pts
            .iter()
            .flat_map(|(i, _)| trace.coefficients[*i].iter())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        let pad = 0.05 * (hi - lo).max(1e-9);
        let mut chart = ChartBuilder::on(&plot)
            .caption(
                "Ridge trace (standardised coefficients)",
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .right_y_label_area_size(10)
            .build_cartesian_2d((kmin..kmax).log_scale(), (lo - pad)..(hi + pad))
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("ridge parameter k")
            .y_desc("standardised coefficient")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .draw()
            .map_err(|e| e.to_string())?;
        for j in 0..trace.sensors.len() {
            let color = Palette99::pick(j).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|(i, k)| (*k, trace.coefficients[*i][j])),
                    color.stroke_width(2),
                ))
                .map_err(|e| e.to_string())?;
        }
        chart
            .draw_series(LineSeries::new(
                vec![(chosen_k, lo - pad), (chosen_k, hi + pad)],
                BLACK.stroke_width(1),
            ))
            .map_err(|e| e.to_string())?;
        legend::draw(&strip, &entries, 50);
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}
