//! Human labels for the fields of the jobs' JSON results, as the report's tables show them
//! (issue 23: "no table shows raw field names"): the standard's symbol and name where there is
//! one, otherwise the field's words with its unit suffix written as a unit.

/// The label of a JSON field name, e.g. `A_up_um` → "positioning accuracy A↑ (µm)".
pub fn label(key: &str) -> String {
    if let Some(l) = known(key) {
        return l.to_string();
    }
    let (words, unit) = split_unit(key);
    let words: Vec<String> = words
        .split('_')
        .filter(|w| !w.is_empty())
        .map(word)
        .collect();
    let mut text = words.join(" ");
    if let Some(u) = unit {
        text.push_str(&format!(" ({u})"));
    }
    text
}

/// The fields the standards name (ISO 230-2:2014 §2–3, VDI/DGQ 3441) and those whose words
/// alone would mislead.
fn known(key: &str) -> Option<&'static str> {
    Some(match key {
        "A_um" => "bidirectional accuracy of positioning A (µm)",
        "A_up_um" => "unidirectional accuracy of positioning A↑ (µm)",
        "A_down_um" => "unidirectional accuracy of positioning A↓ (µm)",
        "E_um" => "bidirectional systematic positioning error E (µm)",
        "E_up_um" => "unidirectional systematic positioning error E↑ (µm)",
        "E_down_um" => "unidirectional systematic positioning error E↓ (µm)",
        "R_um" => "bidirectional repeatability of positioning R (µm)",
        "R_up_um" => "unidirectional repeatability R↑ (µm)",
        "R_down_um" => "unidirectional repeatability R↓ (µm)",
        "B_um" => "reversal value B (µm)",
        "mean_B_um" => "mean reversal value B̄ (µm)",
        "M_um" => "mean bidirectional positioning error M (µm)",
        "P_um" => "position uncertainty P (VDI/DGQ 3441) (µm)",
        "Pa_um" => "position deviation Pa (VDI/DGQ 3441) (µm)",
        "Ps_um" | "ps_um" => "position scatter Ps (VDI/DGQ 3441) (µm)",
        "U_um" | "u_um" => "reversal span U (VDI/DGQ 3441) (µm)",
        "s_mean_um" => "mean scatter s̄ (µm)",
        "mean_um" => "mean deviation x̄ (µm)",
        "target_mm" => "target position (mm)",
        "mean_up_um" => "mean deviation x̄↑ (µm)",
        "mean_down_um" => "mean deviation x̄↓ (µm)",
        "s_up_um" => "standard uncertainty s↑ (µm)",
        "s_down_um" => "standard uncertainty s↓ (µm)",
        "upper_up_um" => "x̄↑ + 2s↑ (µm)",
        "lower_up_um" => "x̄↑ − 2s↑ (µm)",
        "upper_down_um" => "x̄↓ + 2s↓ (µm)",
        "lower_down_um" => "x̄↓ − 2s↓ (µm)",
        "reversal_um" => "reversal value Bᵢ (µm)",
        "mean_bidirectional_um" => "mean bidirectional deviation x̄ᵢ (µm)",
        "r_up_um" => "repeatability R↑ᵢ (µm)",
        "r_down_um" => "repeatability R↓ᵢ (µm)",
        "r_um" => "bidirectional repeatability Rᵢ (µm)",
        "runs_up" => "runs in the positive direction",
        "runs_down" => "runs in the negative direction",
        "rmse_um" => "RMS error (µm)",
        "dof" => "degrees of freedom",
        "vif" => "variance inflation factor",
        "S1" => "first-order index S1",
        "ST" => "total index ST",
        "binding_output" => "output that sets the tolerance",
        "allowed_std" => "allowed standard deviation",
        "current_std" => "current standard deviation",
        "u_1sigma" | "uncertainty_1sigma" => "uncertainty (1σ)",
        "coefficient_at_k" => "coefficient at the chosen k",
        "k" => "ridge parameter k",
        "n" => "count",
        "tool_offset_mm" => "tool offset (mm)",
        "moving_axes" => "moving axes",
        "with_alignment" => "with alignment terms",
        "confounded_with" => "confounded with",
        "rank_deficiency" => "rank deficiency",
        "singular_values" => "singular values",
        "max_harmonic" => "highest harmonic",
        _ => return None,
    })
}

/// A field's unit suffix as a unit: `_um` → µm and so on.
fn split_unit(key: &str) -> (&str, Option<&'static str>) {
    const UNITS: [(&str, &str); 12] = [
        ("_um2", "µm²"),
        ("_um", "µm"),
        ("_urad", "µrad"),
        ("_mm", "mm"),
        ("_deg", "°"),
        ("_c", "°C"),
        ("_min", "min"),
        ("_s", "s"),
        ("_pct", "%"),
        ("_rpm", "rpm"),
        ("_mm_min", "mm/min"),
        ("_um_per_m_k", "µm/(m·K)"),
    ];
    // the longest suffix that fits (`_mm_min` before `_min`)
    UNITS
        .iter()
        .filter(|(s, _)| key.len() > s.len() && key.ends_with(s))
        .max_by_key(|(s, _)| s.len())
        .map(|(s, u)| (&key[..key.len() - s.len()], Some(*u)))
        .unwrap_or((key, None))
}

/// One word of a field name: abbreviations in capitals.
fn word(w: &str) -> String {
    match w {
        "rms" => "RMS".into(),
        "rmse" => "RMSE".into(),
        "mae" => "MAE".into(),
        "vif" => "VIF".into(),
        "std" => "standard deviation".into(),
        "r2" => "R²".into(),
        _ => w.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_read_as_words_with_units() {
        assert_eq!(
            label("A_up_um"),
            "unidirectional accuracy of positioning A↑ (µm)"
        );
        assert_eq!(
            label("channel_residual_rms_um"),
            "channel residual RMS (µm)"
        );
        assert_eq!(label("feed_mm_min"), "feed (mm/min)");
        assert_eq!(label("condition_number"), "condition number");
        assert_eq!(label("sigma_urad"), "sigma (µrad)");
        assert_eq!(label("variance_um2"), "variance (µm²)");
        for k in [
            "A_um",
            "mean_B_um",
            "end_mm",
            "x_y_z",
            "ps_um",
            "binding_output",
        ] {
            assert!(!label(k).contains('_'), "{k} → {}", label(k));
        }
    }
}
