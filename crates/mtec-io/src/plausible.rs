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

/// Largest correction a compensation may be told to allow (`--max-correction-um`, µm): a
/// geometric or thermal error of 10 mm is a broken model or a unit mistake, and the option is
/// the last stop before a controller, so it cannot be switched off with a huge number.
pub const MAX_CORRECTION_LIMIT_UM: f64 = 1e4;

/// An option that is a machine position (mm): finite and below [`MAX_POSITION_MM`] in
/// magnitude, else the message naming the option.
pub fn position_option(flag: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v.abs() < MAX_POSITION_MM {
        Ok(v)
    } else {
        Err(format!(
            "{flag} {v:e} mm is not a machine position (finite, below {MAX_POSITION_MM:e} mm in magnitude)"
        ))
    }
}

/// A positive option with an upper bound: finite and 0 < v ≤ `max`, else the message naming
/// the option, its range and the value.
pub fn positive_option(flag: &str, v: f64, max: f64, unit: &str) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(v)
    } else {
        Err(format!(
            "{flag} must be a positive number of at most {max} {unit}, not {v:e}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_bounded_and_named() {
        assert_eq!(position_option("--at-mm", -250.5), Ok(-250.5));
        for bad in [f64::NAN, f64::INFINITY, 1e5, -1e308] {
            let e = position_option("--at-mm", bad).unwrap_err();
            assert!(e.starts_with("--at-mm "), "{e}");
        }
        assert_eq!(
            positive_option("--max-correction-um", 500.0, 1e4, "um"),
            Ok(500.0)
        );
        assert_eq!(
            positive_option("--max-correction-um", 1e4, 1e4, "um"),
            Ok(1e4)
        );
        for bad in [0.0, -1.0, f64::NAN, 1.0001e4, 1e308] {
            let e = positive_option("--max-correction-um", bad, 1e4, "um").unwrap_err();
            assert!(
                e.starts_with("--max-correction-um must be a positive number of at most 10000 um"),
                "{e}"
            );
        }
    }

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
