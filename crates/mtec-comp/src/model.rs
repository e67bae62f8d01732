//! The one interface every compensable error model offers.

/// A model of the volumetric error of the tool tip relative to the workpiece, as a function of
/// the commanded position. Grids, identified kinematic error models and fitted models (BPNN)
/// implement it; compensation only ever sees this trait.
pub trait ErrorModel: Send + Sync {
    /// Volumetric error [Ex, Ey, Ez] in µm at the commanded position `p_mm` [x, y, z] in mm.
    fn error_um(&self, p_mm: [f64; 3]) -> [f64; 3];
    /// One line saying what the model is and where it came from (written into outputs as provenance).
    fn describe(&self) -> String;
    /// The model as a trilinear grid map, when it is one: G-code rewriting then bounds the
    /// path error exactly from the grid's cells instead of sampling (see `gcode::bound`).
    fn as_grid(&self) -> Option<&crate::GridMap> {
        None
    }
}
