//! ISO 230-2:2014 positioning statistics of a linear axis, and the VDI/DGQ 3441 values.
//!
//! Symbols follow ISO 230-2:2014 clause 3: target i (of m), run j (of n), x_ij↑/↓ the
//! positional deviation. Every axis value is computed from its definition, not from a shortcut:
//! in particular E and A take the maximum and minimum over *both* directions together
//! (E ≠ max(E↑, E↓) in general) and R_i is the maximum of three candidates.

use crate::positioning::PositioningData;
use serde::Serialize;

/// Per-target statistics (µm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TargetStats {
    pub target_mm: f64,
    /// x̄_i↑ = (1/n) Σ_j x_ij↑  (ISO 230-2 3.3.1)
    pub mean_up_um: f64,
    pub mean_down_um: f64,
    /// s_i↑ = sqrt(1/(n−1) Σ_j (x_ij↑ − x̄_i↑)²)  (3.3.5)
    pub s_up_um: f64,
    pub s_down_um: f64,
    /// x̄_i↑ ± 2 s_i↑: the band the standard plots.
    pub upper_up_um: f64,
    pub lower_up_um: f64,
    pub upper_down_um: f64,
    pub lower_down_um: f64,
    /// B_i = x̄_i↑ − x̄_i↓  (3.3.2)
    pub reversal_um: f64,
    /// x̄_i = (x̄_i↑ + x̄_i↓)/2  (3.3.4)
    pub mean_bidirectional_um: f64,
    /// R_i↑ = 4 s_i↑  (3.3.6)
    pub r_up_um: f64,
    pub r_down_um: f64,
    /// R_i = max(2s_i↑ + 2s_i↓ + |B_i|; R_i↑; R_i↓)  (3.3.7)
    pub r_um: f64,
}

/// Axis values of ISO 230-2:2014 (µm). JSON keys follow SPEC (`A_um`, `E_up_um`, ...).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisValues {
    /// B = max |B_i|  (3.3.3)
    #[serde(rename = "B_um")]
    pub b_um: f64,
    /// B̄ = (1/m) Σ B_i  (3.3.3)
    #[serde(rename = "mean_B_um")]
    pub mean_b_um: f64,
    /// R↑ = max R_i↑  (3.3.8)
    #[serde(rename = "R_up_um")]
    pub r_up_um: f64,
    #[serde(rename = "R_down_um")]
    pub r_down_um: f64,
    /// R = max R_i  (3.3.8)
    #[serde(rename = "R_um")]
    pub r_um: f64,
    /// E↑ = max x̄_i↑ − min x̄_i↑  (3.3.9)
    #[serde(rename = "E_up_um")]
    pub e_up_um: f64,
    #[serde(rename = "E_down_um")]
    pub e_down_um: f64,
    /// E = max(x̄_i↑; x̄_i↓) − min(x̄_i↑; x̄_i↓)  (3.3.10)
    #[serde(rename = "E_um")]
    pub e_um: f64,
    /// M = max x̄_i − min x̄_i  (3.3.11)
    #[serde(rename = "M_um")]
    pub m_um: f64,
    /// A↑ = max(x̄_i↑ + 2s_i↑) − min(x̄_i↑ − 2s_i↑)  (3.3.12)
    #[serde(rename = "A_up_um")]
    pub a_up_um: f64,
    #[serde(rename = "A_down_um")]
    pub a_down_um: f64,
    /// A = max(x̄_i↑ + 2s_i↑; x̄_i↓ + 2s_i↓) − min(x̄_i↑ − 2s_i↑; x̄_i↓ − 2s_i↓)  (3.3.13)
    #[serde(rename = "A_um")]
    pub a_um: f64,
}

/// The complete ISO 230-2 evaluation of one axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Iso230_2 {
    pub targets: Vec<TargetStats>,
    pub axis: AxisValues,
    pub runs_up: usize,
    pub runs_down: usize,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Sample standard deviation with n − 1 (ISO 230-2 3.3.5). Needs n ≥ 2 (guaranteed by the reader).
fn sample_std(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt()
}

fn max_of(it: impl Iterator<Item = f64>) -> f64 {
    it.fold(f64::NEG_INFINITY, f64::max)
}
fn min_of(it: impl Iterator<Item = f64>) -> f64 {
    it.fold(f64::INFINITY, f64::min)
}

/// Evaluates validated positioning data.
pub fn evaluate(data: &PositioningData) -> Iso230_2 {
    let targets: Vec<TargetStats> = (0..data.targets_mm.len())
        .map(|i| {
            let mu = mean(&data.up_um[i]);
            let md = mean(&data.down_um[i]);
            let su = sample_std(&data.up_um[i]);
            let sd = sample_std(&data.down_um[i]);
            let b = mu - md; // 3.3.2
            let ru = 4.0 * su; // 3.3.6
            let rd = 4.0 * sd;
            TargetStats {
                target_mm: data.targets_mm[i],
                mean_up_um: mu,
                mean_down_um: md,
                s_up_um: su,
                s_down_um: sd,
                upper_up_um: mu + 2.0 * su,
                lower_up_um: mu - 2.0 * su,
                upper_down_um: md + 2.0 * sd,
                lower_down_um: md - 2.0 * sd,
                reversal_um: b,
                mean_bidirectional_um: 0.5 * (mu + md),
                r_up_um: ru,
                r_down_um: rd,
                r_um: (2.0 * su + 2.0 * sd + b.abs()).max(ru).max(rd), // 3.3.7
            }
        })
        .collect();
    let t = &targets;
    let m = t.len() as f64;
    let all_means = || t.iter().flat_map(|s| [s.mean_up_um, s.mean_down_um]);
    let axis = AxisValues {
        b_um: max_of(t.iter().map(|s| s.reversal_um.abs())),
        mean_b_um: t.iter().map(|s| s.reversal_um).sum::<f64>() / m,
        r_up_um: max_of(t.iter().map(|s| s.r_up_um)),
        r_down_um: max_of(t.iter().map(|s| s.r_down_um)),
        r_um: max_of(t.iter().map(|s| s.r_um)),
        e_up_um: max_of(t.iter().map(|s| s.mean_up_um)) - min_of(t.iter().map(|s| s.mean_up_um)),
        e_down_um: max_of(t.iter().map(|s| s.mean_down_um))
            - min_of(t.iter().map(|s| s.mean_down_um)),
        e_um: max_of(all_means()) - min_of(all_means()),
        m_um: max_of(t.iter().map(|s| s.mean_bidirectional_um))
            - min_of(t.iter().map(|s| s.mean_bidirectional_um)),
        a_up_um: max_of(t.iter().map(|s| s.upper_up_um)) - min_of(t.iter().map(|s| s.lower_up_um)),
        a_down_um: max_of(t.iter().map(|s| s.upper_down_um))
            - min_of(t.iter().map(|s| s.lower_down_um)),
        a_um: max_of(t.iter().flat_map(|s| [s.upper_up_um, s.upper_down_um]))
            - min_of(t.iter().flat_map(|s| [s.lower_up_um, s.lower_down_um])),
    };
    Iso230_2 {
        targets,
        axis,
        runs_up: data.up_um.first().map_or(0, Vec::len),
        runs_down: data.down_um.first().map_or(0, Vec::len),
    }
}

/// Per-target values of VDI/DGQ 3441 (µm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VdiTarget {
    pub target_mm: f64,
    /// s̄_j = (s_j↑ + s_j↓)/2: VDI 3441 averages the two directions' standard deviations.
    pub s_mean_um: f64,
    /// Ps_j = 6 s̄_j  (positional scatter)
    pub ps_um: f64,
    /// U_j = |x̄_j↑ − x̄_j↓|  (reversal span)
    pub u_um: f64,
    /// x̄_j = (x̄_j↑ + x̄_j↓)/2
    pub mean_um: f64,
}

/// VDI/DGQ 3441 axis values (µm): Ps, U, Pa, P.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Vdi3441 {
    pub targets: Vec<VdiTarget>,
    /// Ps = max Ps_j
    #[serde(rename = "Ps_um")]
    pub ps_um: f64,
    /// U = max U_j
    #[serde(rename = "U_um")]
    pub u_um: f64,
    /// Pa = max x̄_j − min x̄_j
    #[serde(rename = "Pa_um")]
    pub pa_um: f64,
    /// P = max(x̄_j + (U_j + Ps_j)/2) − min(x̄_j − (U_j + Ps_j)/2)
    #[serde(rename = "P_um")]
    pub p_um: f64,
}

/// The VDI/DGQ 3441 report from the same per-target statistics.
///
/// Decision: s̄_j is the arithmetic mean of the two directions' standard deviations (as in the
/// guideline), and P is evaluated target by target from its max/min definition (not from the
/// approximation Pa + (U + Ps)/2, which over-estimates when the extremes sit at different targets).
pub fn vdi3441(iso: &Iso230_2) -> Vdi3441 {
    let targets: Vec<VdiTarget> = iso
        .targets
        .iter()
        .map(|s| {
            let s_mean = 0.5 * (s.s_up_um + s.s_down_um);
            VdiTarget {
                target_mm: s.target_mm,
                s_mean_um: s_mean,
                ps_um: 6.0 * s_mean,
                u_um: s.reversal_um.abs(),
                mean_um: s.mean_bidirectional_um,
            }
        })
        .collect();
    let half = |t: &VdiTarget| 0.5 * (t.u_um + t.ps_um);
    Vdi3441 {
        ps_um: max_of(targets.iter().map(|t| t.ps_um)),
        u_um: max_of(targets.iter().map(|t| t.u_um)),
        pa_um: max_of(targets.iter().map(|t| t.mean_um))
            - min_of(targets.iter().map(|t| t.mean_um)),
        p_um: max_of(targets.iter().map(|t| t.mean_um + half(t)))
            - min_of(targets.iter().map(|t| t.mean_um - half(t))),
        targets,
    }
}

/// An evaluation standard `mtec iso230-2 --standard` reports (docs/methods.md §2.2).
///
/// Only standards whose definitions were established from a citable source are here; the
/// others a customer's contract may name are in [`NOT_ESTABLISHED`], with what is unknown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Standard {
    /// ISO 230-2:2014, clause 3 ([`evaluate`]).
    Iso230_2_2014,
    /// VDI/DGQ 3441 ([`vdi3441`]).
    Vdi3441,
}

impl Standard {
    /// Every implemented standard, in the order `--standard all` reports them.
    pub const ALL: [Standard; 2] = [Standard::Iso230_2_2014, Standard::Vdi3441];

    /// The `--standard` value.
    pub fn name(self) -> &'static str {
        match self {
            Standard::Iso230_2_2014 => "iso230-2:2014",
            Standard::Vdi3441 => "vdi-3441",
        }
    }

    /// Parses a `--standard` value: one implemented standard or `all`. A standard named in
    /// [`NOT_ESTABLISHED`] is refused with what is unknown about it.
    pub fn parse(value: &str) -> Result<Vec<Standard>, String> {
        let v = value.trim().to_ascii_lowercase();
        if v == "all" {
            return Ok(Standard::ALL.to_vec());
        }
        if let Some(s) = Standard::ALL.iter().find(|s| s.name() == v) {
            return Ok(vec![*s]);
        }
        let known = Standard::ALL.map(Standard::name).join(", ");
        match NOT_ESTABLISHED.iter().find(|(n, _)| *n == v) {
            Some((n, why)) => Err(format!(
                "--standard {n} is not implemented: {why} (docs/methods.md §2.2); implemented: {known}, all"
            )),
            None => Err(format!(
                "--standard `{value}` is not a standard mtec knows: expected {known} or all"
            )),
        }
    }
}

/// Standards asked for in acceptance contracts whose definitions could not be established from
/// a citable source, with what is unknown (docs/methods.md §2.2). Reporting them would mean
/// guessing their definitions, so `--standard` refuses them.
pub const NOT_ESTABLISHED: [(&str, &str); 5] = [
    (
        "iso230-2:1997",
        "only its coverage factor is established (2 standard uncertainties, replacing the 1988 \
         edition's 3 standard deviations); the text of its A, E, R, B and M definitions was not \
         found",
    ),
    (
        "iso230-2:2006",
        "its scope is established (uncertainty by ISO/TR 230-9 Annex C, step cycle in Annex B), \
         the text of its A, E, R, B and M definitions was not found",
    ),
    (
        "gb-t-17421.2",
        "neither edition's degree of equivalence to ISO 230-2 (IDT or MOD, and of which \
         edition) nor its definitions were found",
    ),
    (
        "jis-b-6190-2",
        "what it modifies from ISO 230-2 was not found",
    ),
    (
        "asme-b5.54",
        "its positioning accuracy and repeatability definitions were not found",
    ),
];

/// One standard's axis values from one run, for the side-by-side report (µm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StandardValues {
    /// The `--standard` name.
    pub standard: String,
    /// Positioning accuracy: A (ISO 230-2) or P (VDI 3441).
    pub accuracy_um: f64,
    /// Repeatability: R (ISO 230-2, bidirectional) or Ps (VDI 3441, positional scatter).
    pub repeatability_um: f64,
    /// Reversal: B = max |B_i| (ISO 230-2) or U (VDI 3441).
    pub reversal_um: f64,
    /// Systematic deviation E (ISO 230-2); VDI 3441 defines none.
    pub systematic_um: Option<f64>,
    /// Range of the mean bidirectional deviations: M (ISO 230-2) or Pa (VDI 3441).
    pub mean_range_um: f64,
}

/// The values of `standard` from the one evaluation `iso` (VDI 3441 from its statistics).
pub fn values_of(standard: Standard, iso: &Iso230_2) -> StandardValues {
    match standard {
        Standard::Iso230_2_2014 => StandardValues {
            standard: standard.name().into(),
            accuracy_um: iso.axis.a_um,
            repeatability_um: iso.axis.r_um,
            reversal_um: iso.axis.b_um,
            systematic_um: Some(iso.axis.e_um),
            mean_range_um: iso.axis.m_um,
        },
        Standard::Vdi3441 => {
            let v = vdi3441(iso);
            StandardValues {
                standard: standard.name().into(),
                accuracy_um: v.p_um,
                repeatability_um: v.ps_um,
                reversal_um: v.u_um,
                systematic_um: None,
                mean_range_um: v.pa_um,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mtec_io::Table;
    use std::path::Path;

    /// A fixture worked by hand from the definitions of ISO 230-2:2014 and VDI/DGQ 3441.
    /// Three targets, three runs per direction (deliberately too few: the reader must warn).
    const FIXTURE: &str = "# worked by hand in the test below\n\
        target_mm,run,direction,deviation_um\n\
        0,1,+,0\n100,1,+,3\n200,1,+,-2\n200,1,-,-6\n100,1,-,3\n0,1,-,-7\n\
        0,2,+,1\n100,2,+,5\n200,2,+,-2\n200,2,-,-4\n100,2,-,4\n0,2,-,-7\n\
        0,3,+,2\n100,3,+,7\n200,3,+,-2\n200,3,-,-2\n100,3,-,5\n0,3,-,-7\n";

    fn close(a: f64, b: f64) {
        assert!((a - b).abs() < 1e-12, "{a} != {b}");
    }

    #[test]
    fn hand_worked_fixture() {
        let data = PositioningData::from_table(&Table::parse(Path::new("f.csv"), FIXTURE).unwrap())
            .unwrap();
        assert_eq!(data.warnings.len(), 3); // 3 runs up, 3 runs down, 3 targets: all below 5
        let r = evaluate(&data);
        let t = &r.targets;

        // --- per target ---------------------------------------------------------------
        // P1 = 0 mm:   ↑ 0, 1, 2     x̄↑ = 1,  s↑ = sqrt(((−1)²+0²+1²)/2) = 1
        //              ↓ −7, −7, −7  x̄↓ = −7, s↓ = 0
        //              B = 1 − (−7) = 8; x̄ = (1 − 7)/2 = −3
        //              R↑ = 4, R↓ = 0, 2s↑+2s↓+|B| = 2 + 0 + 8 = 10  → R_1 = 10
        // P2 = 100 mm: ↑ 3, 5, 7     x̄↑ = 5,  s↑ = sqrt((4+0+4)/2) = 2
        //              ↓ 3, 4, 5     x̄↓ = 4,  s↓ = sqrt((1+0+1)/2) = 1
        //              B = 1; x̄ = 4.5
        //              R↑ = 8, R↓ = 4, 2s↑+2s↓+|B| = 4 + 2 + 1 = 7   → R_2 = 8 (R↑ wins)
        // P3 = 200 mm: ↑ −2, −2, −2  x̄↑ = −2, s↑ = 0
        //              ↓ −6, −4, −2  x̄↓ = −4, s↓ = sqrt((4+0+4)/2) = 2
        //              B = 2; x̄ = −3
        //              R↑ = 0, R↓ = 8, 2s↑+2s↓+|B| = 0 + 4 + 2 = 6   → R_3 = 8 (R↓ wins)
        let expect = [
            // target, x̄↑, x̄↓, s↑, s↓, B, x̄, R↑, R↓, R
            (0.0, 1.0, -7.0, 1.0, 0.0, 8.0, -3.0, 4.0, 0.0, 10.0),
            (100.0, 5.0, 4.0, 2.0, 1.0, 1.0, 4.5, 8.0, 4.0, 8.0),
            (200.0, -2.0, -4.0, 0.0, 2.0, 2.0, -3.0, 0.0, 8.0, 8.0),
        ];
        for (s, e) in t.iter().zip(expect) {
            close(s.target_mm, e.0);
            close(s.mean_up_um, e.1);
            close(s.mean_down_um, e.2);
            close(s.s_up_um, e.3);
            close(s.s_down_um, e.4);
            close(s.reversal_um, e.5);
            close(s.mean_bidirectional_um, e.6);
            close(s.r_up_um, e.7);
            close(s.r_down_um, e.8);
            close(s.r_um, e.9);
        }

        // --- axis values ---------------------------------------------------------------
        let a = &r.axis;
        // B = max|B_i| = max(8, 1, 2) = 8;  B̄ = (8 + 1 + 2)/3 = 11/3
        close(a.b_um, 8.0);
        close(a.mean_b_um, 11.0 / 3.0);
        // R↑ = max(4, 8, 0) = 8; R↓ = max(0, 4, 8) = 8; R = max(10, 8, 8) = 10 (> max(R↑, R↓))
        close(a.r_up_um, 8.0);
        close(a.r_down_um, 8.0);
        close(a.r_um, 10.0);
        // E↑ = 5 − (−2) = 7;  E↓ = 4 − (−7) = 11
        // E = max(1, 5, −2, −7, 4, −4) − min(same) = 5 − (−7) = 12   (≠ max(E↑, E↓) = 11)
        close(a.e_up_um, 7.0);
        close(a.e_down_um, 11.0);
        close(a.e_um, 12.0);
        // M = max(−3, 4.5, −3) − min(...) = 7.5
        close(a.m_um, 7.5);
        // x̄↑ + 2s↑ = (3, 9, −2), x̄↑ − 2s↑ = (−1, 1, −2)  → A↑ = 9 − (−2) = 11
        // x̄↓ + 2s↓ = (−7, 6, 0), x̄↓ − 2s↓ = (−7, 2, −8)  → A↓ = 6 − (−8) = 14
        // A = max(9, 6) − min(−2, −8) = 17                 (≠ max(A↑, A↓) = 14)
        close(a.a_up_um, 11.0);
        close(a.a_down_um, 14.0);
        close(a.a_um, 17.0);

        // --- VDI/DGQ 3441 ----------------------------------------------------------------
        // s̄ = ((1+0)/2, (2+1)/2, (0+2)/2) = (0.5, 1.5, 1);  Ps_j = 6 s̄ = (3, 9, 6) → Ps = 9
        // U_j = |B_j| = (8, 1, 2) → U = 8;  x̄_j = (−3, 4.5, −3) → Pa = 7.5
        // (U_j + Ps_j)/2 = (5.5, 5, 4)
        // max(x̄_j + ...) = max(2.5, 9.5, 1) = 9.5;  min(x̄_j − ...) = min(−8.5, −0.5, −7) = −8.5
        // P = 9.5 − (−8.5) = 18
        let v = vdi3441(&r);
        close(v.ps_um, 9.0);
        close(v.u_um, 8.0);
        close(v.pa_um, 7.5);
        close(v.p_um, 18.0);

        // JSON keys the SPEC promises
        let j = serde_json::to_value(&r.axis).unwrap();
        for k in [
            "A_um",
            "E_um",
            "R_um",
            "B_um",
            "M_um",
            "mean_B_um",
            "A_up_um",
            "A_down_um",
            "E_up_um",
            "E_down_um",
            "R_up_um",
            "R_down_um",
        ] {
            assert!(j.get(k).is_some(), "missing {k}");
        }
    }

    #[test]
    fn standard_values_parse_and_refuse() {
        assert_eq!(
            Standard::parse("iso230-2:2014").unwrap(),
            [Standard::Iso230_2_2014]
        );
        assert_eq!(Standard::parse("ALL").unwrap(), Standard::ALL);
        let e = Standard::parse("asme-b5.54").unwrap_err();
        assert!(e.contains("not implemented") && e.contains("§2.2"), "{e}");
        let e = Standard::parse("iso230-2:1988").unwrap_err();
        assert!(
            e.contains("not a standard") && e.contains("vdi-3441"),
            "{e}"
        );
        for (n, _) in NOT_ESTABLISHED {
            assert!(Standard::parse(n).is_err(), "{n}");
        }
    }
}
