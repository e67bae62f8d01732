//! mtec-report: plots (SVG, drawn with plotters) and the self-contained HTML report.
//!
//! What it is for: turning results into figures and one HTML file that opens anywhere with no
//! network (inline SVG, inline CSS, no scripts from elsewhere).
//! What it is not for: computing results; every number it shows is handed to it.

pub mod html;
pub mod legend;
pub mod plot;
pub mod ridge_trace;
pub mod rotary;

pub use html::{KeyFigure, Report, Section, Verdict};
pub use plot::{
    bar_chart, bar_chart_with_errors, line_chart, quiver_chart, scatter_chart, Arrow, Band, Series,
};

pub mod polar;
