//! Arc geometry of G2/G3 (RS274/NGC, LinuxCNC semantics): centre from I/J/K or from R, sweep,
//! helical axis, and points along the arc for linearisation.
//!
//! Planes (NIST RS274/NGC v3 §3.5.3): G17 works in (X, Y) about Z, G18 in (Z, X) about Y, G19 in
//! (Y, Z) about X; G3 is counter-clockwise seen from the positive end of the normal axis, which
//! is a positive angle in the (first, second) plane coordinates listed here. When the end radius
//! differs a little from the start radius (rounded programs) the radius is interpolated linearly
//! with the angle, as LinuxCNC does.

use std::f64::consts::PI;

/// A working plane: (first, second) in-plane axis indices and the normal axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Plane {
    pub first: usize,
    pub second: usize,
    pub normal: usize,
}

/// G17: X-Y about Z.
pub const XY: Plane = Plane {
    first: 0,
    second: 1,
    normal: 2,
};
/// G18: Z-X about Y.
pub const ZX: Plane = Plane {
    first: 2,
    second: 0,
    normal: 1,
};
/// G19: Y-Z about X.
pub const YZ: Plane = Plane {
    first: 1,
    second: 2,
    normal: 0,
};

/// A circular (or helical) arc in machine coordinates (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct Arc {
    pub plane: Plane,
    pub start: [f64; 3],
    pub end: [f64; 3],
    /// Centre in the plane: (first, second) coordinates.
    pub center: [f64; 2],
    pub r_start: f64,
    pub r_end: f64,
    pub theta_start: f64,
    /// Signed sweep in radians: positive counter-clockwise (G3).
    pub sweep: f64,
}

/// The largest difference (mm) between the end and the start radius of a centre-format arc
/// that LinuxCNC's interpreter runs (as a spiral): √2 · 0.02 mm in a G21 block, √2 · 0.002 in
/// in a G20 block, or 0.1 % of the larger radius when that is more ("Radius to end of arc
/// differs from radius to start"), but never more than 100 times the absolute part (2.83 mm,
/// 0.283 in: on radii above 2.8 m the 0.1 % would allow more). Measured with rs274
/// (linuxcnc-uspace 2.9.0~pre1) by bisection at r = 2, 20, 200 mm and 0.05, 1, 10 in,
/// 2026-11-28; until then mtec used 0.02 mm in both units, which refused inch arcs LinuxCNC
/// runs. The cap: r = 3000 mm runs 2.82 mm and stops at 2.835 mm, r = 300 in runs 0.282 in and
/// stops at 0.2835 in (2026-11-29; found by LinuxCNC's own tests/interp/bad/bad-arc.big.*,
/// which mtec had linearised into a program that runs where the original stops).
pub fn center_arc_limit_mm(r_start: f64, r_end: f64, inch: bool) -> f64 {
    let abs = std::f64::consts::SQRT_2 * if inch { 0.002 * 25.4 } else { 0.02 };
    abs.max(0.001 * r_start.max(r_end)).min(100.0 * abs)
}

/// LinuxCNC stops at a centre-format arc whose radius to the start or to the end is below this
/// ("Zero-radius arc"; mm, 0.00005 in, in both units: rs274 2.9.0~pre1 runs r = 0.00127 mm and
/// stops at 0.00126 mm in G21, runs 0.00005 in and stops at 0.000049 in in G20; its
/// `arc_data_ijk` takes a tenth of the radius tolerance). An R-format arc has no such limit, so
/// an R arc mtec writes with its centre must have its radii above it (found 2026-11-30 by a
/// dxf2gcode program's R0.0011 arc, which rs274 ran and mtec's IJK rewrite made it refuse).
pub const CENTER_ARC_MIN_RADIUS_MM: f64 = 0.00005 * 25.4;

/// Radii this close to [`CENTER_ARC_MIN_RADIUS_MM`] (mm) are refused as below it: which side
/// LinuxCNC takes depends on the last bits of a sum in the program's units.
const MIN_RADIUS_SLACK_MM: f64 = 1e-9;

/// An R-format arc whose radius is short of half its chord by more than this (mm; 0.00005 in,
/// in both units) is refused by LinuxCNC ("Arc radius too small to reach end point"); within
/// it the arc is a half circle. Measured as above; until 2026-11-28 mtec allowed 0.02 mm and
/// wrote a half circle where LinuxCNC stops.
const R_ARC_SHORT_MM: f64 = 0.00005 * 25.4;

/// LinuxCNC's motion runs an arc whose sweep (from the start to the end, in the arc's sense) is
/// below this as a full circle (posemath `pmCircleInit`, `CIRCLE_FUZZ`, radians).
pub const CIRCLE_FUZZ_RAD: f64 = 1e-6;
/// An end point this close to the start (mm, in the plane) but not on it is refused: whether
/// LinuxCNC runs a full circle or an arc of that chord depends on digits below any program's
/// resolution (a position carried over a G20/G21 switch) and on which side of the start the
/// end lies, and no printout or check can tell (found by tests/rs274/generate.py).
pub const NEAR_FULL_CIRCLE_MM: f64 = 1e-3;

fn in_plane(p: &[f64; 3], pl: Plane) -> [f64; 2] {
    [p[pl.first], p[pl.second]]
}

impl Arc {
    /// The arc through its centre (`center` already absolute, in the plane), turning
    /// clockwise (G2) or not, `turns` ≥ 1 full turns counted as LinuxCNC's P word.
    /// The block is in inch (`inch`) or mm: LinuxCNC's radius tolerance depends on its units
    /// ([`center_arc_limit_mm`]).
    pub fn from_center(
        start: [f64; 3],
        end: [f64; 3],
        center: [f64; 2],
        plane: Plane,
        clockwise: bool,
        turns: u32,
        inch: bool,
    ) -> Result<Arc, String> {
        let arc = Arc::through(start, end, center, plane, clockwise, turns, inch)?;
        if arc.r_start.min(arc.r_end) < CENTER_ARC_MIN_RADIUS_MM + MIN_RADIUS_SLACK_MM {
            return Err(format!(
                "arc radius {:.6} mm (to the start) / {:.6} mm (to the end) is below the smallest LinuxCNC runs in centre format, {CENTER_ARC_MIN_RADIUS_MM} mm (0.00005 in): it stops here with \"Zero-radius arc\"",
                arc.r_start, arc.r_end
            ));
        }
        Ok(arc)
    }

    /// [`Arc::from_center`] without LinuxCNC's smallest centre-format radius (an R arc's centre,
    /// which has none); a centre on the start point is still refused.
    fn through(
        start: [f64; 3],
        end: [f64; 3],
        center: [f64; 2],
        plane: Plane,
        clockwise: bool,
        turns: u32,
        inch: bool,
    ) -> Result<Arc, String> {
        let s = in_plane(&start, plane);
        let e = in_plane(&end, plane);
        let r_start = (s[0] - center[0]).hypot(s[1] - center[1]);
        let r_end = (e[0] - center[0]).hypot(e[1] - center[1]);
        if r_start < 1e-9 {
            return Err("arc radius is zero (the centre is the start point)".into());
        }
        let mismatch = (r_end - r_start).abs();
        if mismatch > center_arc_limit_mm(r_start, r_end, inch) {
            return Err(format!(
                "arc end point is not on the circle: radius {r_start:.6} mm at the start, {r_end:.6} mm at the end"
            ));
        }
        let theta_start = (s[1] - center[1]).atan2(s[0] - center[0]);
        let theta_end = (e[1] - center[1]).atan2(e[0] - center[0]);
        let chord = (e[0] - s[0]).hypot(e[1] - s[1]);
        let ambiguous = || {
            format!(
                "arc end point {:.4} um from its start: LinuxCNC runs this as a full circle or as an arc of that chord depending on digits below the program's resolution; give the end exactly at the start (or no axis words) for a full circle",
                chord * 1e3
            )
        };
        if (1e-9..NEAR_FULL_CIRCLE_MM).contains(&chord) {
            return Err(ambiguous());
        }
        // the sweep in the arc's sense, in [0, 2π) as LinuxCNC computes it, then its rule
        let mut sweep = (theta_end - theta_start).rem_euclid(2.0 * PI);
        if clockwise {
            sweep = (2.0 * PI - sweep).rem_euclid(2.0 * PI);
        }
        if chord >= 1e-9 && sweep < 2.0 * CIRCLE_FUZZ_RAD {
            // a radius above 500 m: this close to LinuxCNC's threshold, refused as above
            return Err(ambiguous());
        }
        if sweep < CIRCLE_FUZZ_RAD {
            sweep = 2.0 * PI; // end on the start: a full circle
        }
        if clockwise {
            sweep = -sweep;
        }
        let extra = 2.0 * PI * (turns.max(1) - 1) as f64;
        sweep += if clockwise { -extra } else { extra };
        Ok(Arc {
            plane,
            start,
            end,
            center,
            r_start,
            r_end,
            theta_start,
            sweep,
        })
    }

    /// The arc of signed radius `r` (R word): positive takes the short way (≤ 180°),
    /// negative the long way.
    pub fn from_radius(
        start: [f64; 3],
        end: [f64; 3],
        r: f64,
        plane: Plane,
        clockwise: bool,
    ) -> Result<Arc, String> {
        let s = in_plane(&start, plane);
        let e = in_plane(&end, plane);
        let chord = (e[0] - s[0]).hypot(e[1] - s[1]);
        if chord < 1e-9 {
            return Err("an R-format arc cannot have its end point at its start point".into());
        }
        let half = chord / 2.0;
        let h2 = r * r - half * half;
        let h = if h2 >= 0.0 {
            h2.sqrt()
        } else if half - r.abs() <= R_ARC_SHORT_MM {
            0.0
        } else {
            return Err(format!(
                "arc radius {:.6} mm is smaller than half the distance between its end points ({half:.6} mm)",
                r.abs()
            ));
        };
        let u = [(e[0] - s[0]) / chord, (e[1] - s[1]) / chord];
        let left = [-u[1], u[0]];
        // the centre lies left of S→E for a short counter-clockwise arc (and right for G2)
        let side = if clockwise { -1.0 } else { 1.0 } * r.signum();
        let m = [(s[0] + e[0]) / 2.0, (s[1] + e[1]) / 2.0];
        let center = [m[0] + side * h * left[0], m[1] + side * h * left[1]];
        Arc::through(start, end, center, plane, clockwise, 1, false)
    }

    /// The point at fraction `t` ∈ [0, 1] of the sweep; `t = 1` is exactly the end point.
    pub fn point(&self, t: f64) -> [f64; 3] {
        if t >= 1.0 {
            return self.end;
        }
        if t <= 0.0 {
            return self.start;
        }
        let theta = self.theta_start + self.sweep * t;
        let r = self.r_start + (self.r_end - self.r_start) * t;
        let mut p = [0.0; 3];
        p[self.plane.first] = self.center[0] + r * theta.cos();
        p[self.plane.second] = self.center[1] + r * theta.sin();
        let n = self.plane.normal;
        p[n] = self.start[n] + (self.end[n] - self.start[n]) * t;
        p
    }

    /// Number of chords so that each chord's sagitta r·(1 − cos(Δθ/2)) is at most `chord_tol_mm`.
    pub fn chord_count(&self, chord_tol_mm: f64) -> usize {
        let r = self.r_start.max(self.r_end);
        let max_step = if chord_tol_mm >= r {
            PI / 2.0
        } else {
            (2.0 * (1.0 - chord_tol_mm / r).acos()).min(PI / 2.0)
        };
        ((self.sweep.abs() / max_step).ceil() as usize).max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9)
    }

    #[test]
    fn quarter_circle_ccw_from_radius() {
        // G17 G3 from (1,0) to (0,1) with R1: centre at the origin, +90°
        let a = Arc::from_radius([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0, XY, false).unwrap();
        assert!(a.center[0].abs() < 1e-12 && a.center[1].abs() < 1e-12);
        assert!((a.sweep - PI / 2.0).abs() < 1e-12);
        let mid = a.point(0.5);
        let s = 0.5f64.sqrt();
        assert!(close(mid, [s, s, 0.0]));
        // G2 with R1: centre at (1,1), clockwise 90°
        let b = Arc::from_radius([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0, XY, true).unwrap();
        assert!((b.center[0] - 1.0).abs() < 1e-12 && (b.center[1] - 1.0).abs() < 1e-12);
        assert!((b.sweep + PI / 2.0).abs() < 1e-12);
        // negative R: the long way round (270°)
        let c = Arc::from_radius([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], -1.0, XY, false).unwrap();
        assert!((c.sweep - 1.5 * PI).abs() < 1e-12);
    }

    #[test]
    fn full_circle_helix_and_zx_plane() {
        let a = Arc::from_center(
            [1.0, 0.0, 0.0],
            [1.0, 0.0, -2.0],
            [0.0, 0.0],
            XY,
            true,
            2,
            false,
        )
        .unwrap();
        assert!((a.sweep + 4.0 * PI).abs() < 1e-12);
        assert!(close(a.point(0.25), [-1.0, 0.0, -0.5]));
        assert!(close(a.point(0.5), [1.0, 0.0, -1.0]));
        assert_eq!(a.point(1.0), [1.0, 0.0, -2.0]);
        // G18 G3 from X1 Z0 about the origin: plane (Z, X); a quarter turn CCW moves to Z1? the
        // point (z, x) = (0, 1) at 90° goes to 180° = (-1, 0): Z-1, X0.
        let b = Arc::from_center(
            [1.0, 0.0, 0.0],
            [0.0, 0.0, -1.0],
            [0.0, 0.0],
            ZX,
            false,
            1,
            false,
        )
        .unwrap();
        assert!((b.sweep - PI / 2.0).abs() < 1e-12);
        let mid = b.point(0.5);
        let s = 0.5f64.sqrt();
        assert!(close(mid, [s, 0.0, -s]));
    }

    #[test]
    fn an_end_next_to_the_start_is_a_full_circle_only_on_the_start_and_refused_near_it() {
        // on the start (to 1e-9 mm): a full circle either way round
        for cw in [false, true] {
            let a = Arc::from_center(
                [10.0, 0.0, 0.0],
                [10.0, 1e-12, 0.0],
                [0.0, 0.0],
                XY,
                cw,
                1,
                false,
            )
            .unwrap();
            assert!((a.sweep.abs() - 2.0 * PI).abs() < 1e-9, "{}", a.sweep);
        }
        // 0.04 um ahead or behind (a position carried over a G20/G21 switch): LinuxCNC makes a
        // tiny arc or a full circle depending on the side; refused, naming the distance
        for y in [4e-5, -4e-5] {
            let e = Arc::from_center(
                [10.0, 0.0, 0.0],
                [10.0, y, 0.0],
                [0.0, 0.0],
                XY,
                false,
                1,
                false,
            )
            .unwrap_err();
            assert!(e.contains("0.0400 um from its start"), "{e}");
        }
        // 1 um and more: the arc LinuxCNC runs, the short or the long way by the sense
        let short = Arc::from_center(
            [10.0, 0.0, 0.0],
            [10.0, 2e-3, 0.0],
            [0.0, 0.0],
            XY,
            false,
            1,
            false,
        )
        .unwrap();
        assert!((short.sweep - 2e-4).abs() < 1e-9);
        let long = Arc::from_center(
            [10.0, 0.0, 0.0],
            [10.0, 2e-3, 0.0],
            [0.0, 0.0],
            XY,
            true,
            1,
            false,
        )
        .unwrap();
        assert!((long.sweep + 2.0 * PI - 2e-4).abs() < 1e-9);
    }

    #[test]
    fn chord_count_meets_sagitta() {
        let a = Arc::from_center(
            [10.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 0.0],
            XY,
            false,
            1,
            false,
        )
        .unwrap();
        let n = a.chord_count(0.5e-3);
        let dtheta = a.sweep / n as f64;
        assert!(10.0 * (1.0 - (dtheta / 2.0).cos()) <= 0.5e-3 + 1e-15);
        assert!(Arc::from_center(
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0],
            XY,
            false,
            1,
            false
        )
        .is_err());
        assert!(Arc::from_radius([0.0, 0.0, 0.0], [3.0, 0.0, 0.0], 1.0, XY, false).is_err());
    }

    /// LinuxCNC's smallest centre-format radius, as rs274 (2.9.0~pre1) showed it by bisection:
    /// r = 0.00127 mm runs and 0.00126 mm stops in G21, 0.00005 in runs and 0.000049 in stops
    /// in G20, to the start or to the end; an R arc of radius 0.0011 mm runs.
    #[test]
    fn centre_arcs_below_linuxcnc_s_smallest_radius_are_refused() {
        let half = |r: f64, inch: bool| {
            Arc::from_center([0.0; 3], [2.0 * r, 0.0, 0.0], [r, 0.0], XY, true, 1, inch)
        };
        assert!(half(0.0013, false).is_ok() && half(0.00126, false).is_err());
        assert!(half(0.00005 * 25.4 * 1.001, true).is_ok());
        assert!(half(0.000049 * 25.4, true).is_err());
        let e = half(0.0011, false).unwrap_err();
        assert!(
            e.contains("Zero-radius arc") && e.contains("0.001100"),
            "{e}"
        );
        // the end radius counts too: start radius 0.0013, end radius 0.00126
        let end = [0.0013 - 0.00004, 0.00126, 0.0];
        assert!(Arc::from_center([0.0; 3], end, [0.0013, 0.0], XY, false, 1, false).is_err());
        // an R arc has no such limit
        let r = Arc::from_radius([0.0; 3], [0.0017, 0.0008, 0.0], 0.0011, XY, true).unwrap();
        assert!((r.r_start - 0.0011).abs() < 1e-12);
    }

    /// LinuxCNC's limits as rs274 (2.9.0~pre1) showed them by bisection: a centre-format arc
    /// runs up to √2 · 0.02 mm (G21) or √2 · 0.002 in (G20) of radius difference, or 0.1 % of
    /// the larger radius; an R arc may be short of half its chord by 0.00005 in.
    #[test]
    fn radius_tolerances_are_linuxcnc_s() {
        let ends = |r: f64, d: f64| ([0.0, 0.0, 0.0], [2.0 * r + d, 0.0, 0.0], [r, 0.0]);
        let ok = |r: f64, d: f64, inch: bool| {
            let (s, e, c) = ends(r, d);
            Arc::from_center(s, e, c, XY, true, 1, inch).is_ok()
        };
        // mm: rs274 runs 0.028 and stops at 0.0283 (r = 2 and 20 mm)
        assert!(ok(2.0, 0.028, false) && !ok(2.0, 0.0285, false));
        assert!(ok(20.0, 0.028, false) && !ok(20.0, 0.0285, false));
        // the relative part: r = 200 mm runs up to 0.2002 mm
        assert!(ok(200.0, 0.2, false) && !ok(200.0, 0.201, false));
        // ... up to 100 times the absolute part: r = 3000 mm runs 2.82 mm, stops at 2.835 mm
        // (0.1 % would be 3 mm); r = 300 in runs 0.282 in, stops at 0.2835 in
        assert!(ok(3000.0, 2.82, false) && !ok(3000.0, 2.835, false));
        assert!(ok(7620.0, 0.282 * 25.4, true) && !ok(7620.0, 0.2835 * 25.4, true));
        // inch: 0.0028 in runs, 0.003 in stops (r = 1 in = 25.4 mm)
        assert!(ok(25.4, 0.0028 * 25.4, true) && !ok(25.4, 0.003 * 25.4, true));
        assert!(!ok(25.4, 0.0028 * 25.4, false));
        // R format: 0.00127 mm short of half the chord is a half circle, 0.0013 mm is refused
        let half = Arc::from_radius([0.0; 3], [4.0025, 0.0, 0.0], 2.0, XY, true).unwrap();
        assert!((half.sweep.abs() - PI).abs() < 1e-9);
        assert!(Arc::from_radius([0.0; 3], [4.0027, 0.0, 0.0], 2.0, XY, true).is_err());
    }
}
