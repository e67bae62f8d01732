//! The bar-length model of a C axis: exact (rigid-body transform) and first order.

use super::setup::{Mode, Setup};
use mtec_model::Htm;
use nalgebra::{Matrix5, Vector3};

/// ISO 230-1 names of the five observable error motions, in the order of every vector here.
pub const OBSERVABLE_NAMES: [&str; 5] = ["EXC", "EYC", "EZC", "EAC", "EBC"];

/// The error motions of the C axis at one angle: translations in µm, rotations in µrad.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorMotions {
    pub exc_um: f64,
    pub eyc_um: f64,
    pub ezc_um: f64,
    pub eac_urad: f64,
    pub ebc_urad: f64,
    /// Angular positioning error about the axis; not observable with bars in axial planes.
    #[serde(default)]
    pub ecc_urad: f64,
}

impl ErrorMotions {
    /// The five observable motions `[EXC, EYC, EZC, EAC, EBC]`.
    pub fn observable(&self) -> [f64; 5] {
        [
            self.exc_um,
            self.eyc_um,
            self.ezc_um,
            self.eac_urad,
            self.ebc_urad,
        ]
    }
    /// From `[EXC, EYC, EZC, EAC, EBC]` (ECC = 0).
    pub fn from_observable(v: [f64; 5]) -> Self {
        ErrorMotions {
            exc_um: v[0],
            eyc_um: v[1],
            ezc_um: v[2],
            eac_urad: v[3],
            ebc_urad: v[4],
            ecc_urad: 0.0,
        }
    }

    /// The table's exact error transform `E = Trans(δ)·Rz(εz)·Ry(εy)·Rx(εx)` (mm, rad), the
    /// ISO 230-1 small-error transform of `mtec-model`.
    pub fn transform(&self) -> Htm {
        Htm::error_exact(
            Vector3::new(self.exc_um, self.eyc_um, self.ezc_um) * 1e-3,
            Vector3::new(self.eac_urad, self.ebc_urad, self.ecc_urad) * 1e-6,
        )
    }
}

/// The ideal pose of the table at angle C: `Rz(C)`.
pub fn ideal_table(angle_deg: f64) -> Htm {
    Htm::rotation(Vector3::z(), angle_deg.to_radians())
}

/// Ideal position of the workpiece ball at table angle `angle_deg` (mm): `Rz(C)·p`.
pub fn ideal_workpiece_mm(mode: &Mode, angle_deg: f64) -> Vector3<f64> {
    ideal_table(angle_deg).point(&mode.workpiece())
}

/// Exact bar-length change (µm): `|E(C)·Rz(C)·p_w − p_t| − |Rz(C)·p_w − p_t|`.
pub fn exact_dl_um(mode: &Mode, angle_deg: f64, e: &ErrorMotions) -> f64 {
    let ideal = ideal_workpiece_mm(mode, angle_deg);
    let actual = (e.transform() * ideal_table(angle_deg)).point(&mode.workpiece());
    let l0 = (ideal - mode.tool()).norm();
    let l = (actual - mode.tool()).norm();
    (l - l0) * 1e3
}

/// Coefficients of `[EXC, EYC, EZC (µm), EAC, EBC, ECC (µrad)]` in the bar-length change (µm)
/// of one mode at one angle.
///
/// First-order model `L0·ΔL = (r_w − r_t)·Δr`, `Δr = δ + ε × r_w` (small rotations about the
/// origin), hence `ΔL = n·δ + ε·(r_w × n)` with `n = (r_w − r_t)/L0`; `1e-3` turns µrad·mm
/// into µm.
pub fn first_order_row(mode: &Mode, angle_deg: f64) -> [f64; 6] {
    let r = ideal_workpiece_mm(mode, angle_deg);
    let d = r - mode.tool();
    let n = d / d.norm();
    let m = r.cross(&n) * 1e-3;
    [n.x, n.y, n.z, m.x, m.y, m.z]
}

/// The 5×5 identification matrix at one angle: row i = mode i, columns EXC..EBC.
pub fn identification_matrix(setup: &Setup, angle_deg: f64) -> Matrix5<f64> {
    let mut a = Matrix5::zeros();
    for (i, mode) in setup.modes.iter().enumerate() {
        let row = first_order_row(mode, angle_deg);
        for j in 0..5 {
            a[(i, j)] = row[j];
        }
    }
    a
}

/// Predicted bar-length changes (µm) of the five modes, in setup order, for given error motions
/// at one angle: the first-order model (ECC included, it contributes only to off-plane bars).
///
/// This is the map from predicted error motions back to predicted ballbar readings (e.g. for a
/// neural model's output). It has no set-up error: compare it with readings after
/// [`super::harmonics::remove_mean_and_first_harmonic`], or with the model of the cleaned
/// motions.
pub fn predicted_dl_um(setup: &Setup, angle_deg: f64, motions: &ErrorMotions) -> [f64; 5] {
    let e = [
        motions.exc_um,
        motions.eyc_um,
        motions.ezc_um,
        motions.eac_urad,
        motions.ebc_urad,
        motions.ecc_urad,
    ];
    let mut out = [0.0; 5];
    for (i, mode) in setup.modes.iter().enumerate() {
        let row = first_order_row(mode, angle_deg);
        out[i] = row.iter().zip(&e).map(|(a, b)| a * b).sum();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn radial(id: i64, h: f64, b: f64) -> Mode {
        Mode {
            id,
            workpiece_ball_mm: [0.0, 0.0, h],
            tool_ball_mm: [b, 0.0, h],
        }
    }

    /// Hand-worked: a pure EXC = 1 µm moves the centre ball towards a tool cup on +X, so the
    /// bar shortens by 1 µm; a tool cup on −X sees it lengthen by 1 µm.
    #[test]
    fn pure_exc_on_radial_bar_is_plus_minus_one_um() {
        let e = ErrorMotions {
            exc_um: 1.0,
            ..Default::default()
        };
        let plus_x = radial(1, 100.0, 150.0);
        let minus_x = Mode {
            tool_ball_mm: [-150.0, 0.0, 100.0],
            ..plus_x.clone()
        };
        assert!((exact_dl_um(&plus_x, 0.0, &e) + 1.0).abs() < 1e-6);
        assert!((exact_dl_um(&minus_x, 0.0, &e) - 1.0).abs() < 1e-6);
        assert!((predicted_row(&plus_x, 0.0, &e) + 1.0).abs() < 1e-12);
    }

    /// Hand-worked: a tilt EBC = 10 µrad about Y moves a ball at height h = 100 mm on the axis
    /// by +h·ε = +1 µm in X (right-hand rule: Ry turns +Z towards +X), so the +X bar shortens
    /// by 1 µm; the same tilt moves a ball at (90, 0, 100) down by 90 mm·10 µrad = 0.9 µm.
    #[test]
    fn tilt_about_y_worked_by_hand() {
        let e = ErrorMotions {
            ebc_urad: 10.0,
            ..Default::default()
        };
        let m = radial(1, 100.0, 150.0);
        assert!((exact_dl_um(&m, 0.0, &e) + 1.0).abs() < 1e-5);
        // inclined bar: ball (90, 0, 100), tool (0, 0, 220): n = (90, 0, −120)/150.
        // Δr = ε × r = (0, 10e-6, 0) × (90, 0, 100) mm = (1.0, 0, −0.9) µm
        // ΔL = (90·1.0 + 120·0.9)/150 = 1.32 µm
        let inc = Mode {
            id: 3,
            workpiece_ball_mm: [90.0, 0.0, 100.0],
            tool_ball_mm: [0.0, 0.0, 220.0],
        };
        assert!((exact_dl_um(&inc, 0.0, &e) - 1.32).abs() < 1e-5);
        assert!((predicted_row(&inc, 0.0, &e) - 1.32).abs() < 1e-12);
        // after C = 180° the ball is at (−90, 0, 100): Δr = (1.0, 0, 0.9), n = (−90, 0, −120)/150
        // ΔL = (−90·1.0 − 120·0.9)/150 = −1.32 µm
        assert!((exact_dl_um(&inc, 180.0, &e) + 1.32).abs() < 1e-5);
    }

    /// ECC leaves bars in axial planes unchanged (first order), but not a tangential bar.
    #[test]
    fn ecc_invisible_in_axial_planes() {
        let s = Setup::preset(Setup::default_dims()).unwrap();
        for m in &s.modes {
            for c in [0.0, 37.0, 211.0] {
                assert!(first_order_row(m, c)[5].abs() < 1e-15);
            }
        }
        let tangential = Mode {
            id: 9,
            workpiece_ball_mm: [100.0, 0.0, 0.0],
            tool_ball_mm: [100.0, 150.0, 0.0],
        };
        assert!(first_order_row(&tangential, 0.0)[5].abs() > 0.05);
    }

    /// First order minus exact shrinks quadratically with the size of the motions.
    #[test]
    fn first_order_error_is_second_order() {
        let s = Setup::preset(Setup::default_dims()).unwrap();
        let e = |f: f64| ErrorMotions {
            exc_um: 3.0 * f,
            eyc_um: -2.0 * f,
            ezc_um: 1.5 * f,
            eac_urad: 40.0 * f,
            ebc_urad: -25.0 * f,
            ecc_urad: 30.0 * f,
        };
        let gap = |f: f64| {
            let mut g: f64 = 0.0;
            for c in [0.0, 50.0, 130.0, 275.0] {
                let p = predicted_dl_um(&s, c, &e(f));
                for (i, m) in s.modes.iter().enumerate() {
                    g = g.max((exact_dl_um(m, c, &e(f)) - p[i]).abs());
                }
            }
            g
        };
        let (g1, g2) = (gap(100.0), gap(10.0));
        assert!(
            g1 > 1e-4,
            "the scaled-up case must show a nonlinearity: {g1}"
        );
        let ratio = g1 / g2;
        assert!((ratio - 100.0).abs() < 5.0, "ratio {ratio}");
    }

    fn predicted_row(m: &Mode, c: f64, e: &ErrorMotions) -> f64 {
        let r = first_order_row(m, c);
        r[0] * e.exc_um
            + r[1] * e.eyc_um
            + r[2] * e.ezc_um
            + r[3] * e.eac_urad
            + r[4] * e.ebc_urad
            + r[5] * e.ecc_urad
    }
}
