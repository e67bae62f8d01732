//! The legend of a chart, drawn in its own strip beside the plot area, so that it can never
//! cover data (issue 23: "a legend that does not cover data"). plotters' own series labels are
//! drawn inside the plot area, on top of whatever lies there.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// How an entry's sample is drawn: the mark its series uses.
#[derive(Debug, Clone, Copy)]
pub enum Swatch {
    Line,
    Box,
    Dot,
}

/// One legend entry.
#[derive(Debug, Clone)]
pub struct Entry {
    pub name: String,
    pub colour: RGBAColor,
    pub swatch: Swatch,
}

impl Entry {
    pub fn new(name: impl Into<String>, colour: impl Color, swatch: Swatch) -> Self {
        Entry {
            name: name.into(),
            colour: colour.to_rgba(),
            swatch,
        }
    }
}

/// Font size of the entries (px).
const FONT: u32 = 13;
/// Longest entry shown whole; longer names end in `…`.
const MAX_CHARS: usize = 34;
/// Vertical distance between entries (px).
const STEP: i32 = 20;

fn shown(name: &str) -> String {
    if name.chars().count() <= MAX_CHARS {
        name.to_string()
    } else {
        let mut s: String = name.chars().take(MAX_CHARS - 1).collect();
        s.push('…');
        s
    }
}

/// The width (px) of the strip the legend needs; 0 when one entry or none needs no legend
/// (the chart's title names the single series).
pub fn width(entries: &[Entry]) -> u32 {
    if entries.len() <= 1 {
        return 0;
    }
    let chars = entries
        .iter()
        .map(|e| shown(&e.name).chars().count())
        .max()
        .unwrap_or(0);
    // about 0.6 em per character of a sans-serif font, plus the swatch and the margins
    (chars as u32 * FONT * 6 / 10 + 50).clamp(100, 300)
}

/// Draws the entries top-down in `area` (the strip right of the plot), starting at `top` px.
pub fn draw<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, entries: &[Entry], top: i32) {
    if entries.len() <= 1 {
        return;
    }
    let style = TextStyle::from(("sans-serif", FONT).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (i, e) in entries.iter().enumerate() {
        let y = top + STEP * i as i32;
        let (x0, x1) = (8, 28);
        let c = e.colour;
        let _ = match e.swatch {
            Swatch::Line => area.draw(&PathElement::new(vec![(x0, y), (x1, y)], c.stroke_width(2))),
            Swatch::Box => area.draw(&Rectangle::new([(x0, y - 6), (x1, y + 6)], c.filled())),
            Swatch::Dot => area.draw(&Circle::new((x0 + 10, y), 4, c.filled())),
        };
        let _ = area.draw(&Text::new(shown(&e.name), (x1 + 8, y), style.clone()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_names_are_cut_and_the_strip_fits_the_longest() {
        let e = |n: &str| Entry::new(n, BLACK, Swatch::Line);
        assert_eq!(width(&[e("only one")]), 0);
        let short = width(&[e("a"), e("b")]);
        let long = width(&[e("a"), e(&"x".repeat(80))]);
        assert_eq!(short, 100);
        assert!(long > short && long <= 300);
        assert_eq!(shown(&"x".repeat(80)).chars().count(), MAX_CHARS);
    }
}
