//! The one interface every compensable error model offers.

/// A model of the volumetric error of the tool tip relative to the workpiece, as a function of
/// the commanded position. Grids, identified kinematic error models and fitted models (BPNN)
/// implement it; compensation only ever sees this trait.
pub trait ErrorModel: Send + Sync {
    /// Volumetric error [Ex, Ey, Ez] in µm at the commanded position `p_mm` [x, y, z] in mm.
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3];
    /// One line saying what the model is and where it came from (written into outputs as provenance).
    fn describe(&self) -> String;
}
