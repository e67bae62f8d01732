//! mtec-report: Plots (SVG) and the self-contained HTML report.

pub mod polar;
