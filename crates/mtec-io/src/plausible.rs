//! Bounds on measured values: a reading far beyond anything a machine tool can show is a unit or
//! export mistake (nm or raw counts written as µm, a logger's error code), refused at its line
//! and column before it reaches a fit, a model file or a controller.

/// An error reading (positioning, straightness, volumetric) of a metre or more is not an error of
/// a machine tool (µm). The ISO 230-2 reader's bound too.
pub const MAX_ERROR_UM: f64 = 1e6;

/// A measured position of 100 m or more lies beyond any machine tool's travel (mm).
pub const MAX_POSITION_MM: f64 = 1e5;

/// `v` when |v| < `limit`, else the message to locate: the value, the bound and what to check.
pub fn within(name: &str, v: f64, limit: f64, unit: &str) -> Result<f64, String> {
    if v.abs() < limit {
        Ok(v)
    } else {
        Err(format!(
            "`{name}` is {v:e} {unit}: implausible (|{name}| must be below {limit:e} {unit}): check the unit or the export"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_is_strict_and_the_message_names_column_and_unit() {
        assert_eq!(
            within("ex_um", -999_999.0, MAX_ERROR_UM, "um"),
            Ok(-999_999.0)
        );
        let e = within("ex_um", 1e6, MAX_ERROR_UM, "um").unwrap_err();
        assert!(
            e.contains("`ex_um` is 1e6 um") && e.contains("below 1e6 um"),
            "{e}"
        );
        assert!(within("x_mm", -1e300, MAX_POSITION_MM, "mm").is_err());
    }
}
