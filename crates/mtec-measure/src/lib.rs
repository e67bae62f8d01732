//! mtec-measure: Measurement files and their standard statistics: ISO 230-2 positioning, ISO 230-4 circular tests and ballbar diagnostics.
