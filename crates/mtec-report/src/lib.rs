//! mtec-report: Plots (SVG) and the self-contained HTML report.
