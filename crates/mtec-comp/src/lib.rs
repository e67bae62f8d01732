//! mtec-comp: Compensation: volumetric maps, correction values, G-code rewriting, controller tables, real-time API.
