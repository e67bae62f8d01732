//! The ballbar installation: five modes, each a workpiece ball on the table and a tool ball held
//! still by the spindle while C turns.
//!
//! TOML (SPEC §4):
//! ```toml
//! [[mode]]
//! id = 1
//! workpiece_ball_mm = [0, 0, 100]    # on the table, coordinates at C = 0
//! tool_ball_mm = [150, 0, 100]       # fixed while C turns
//! ```
//! Exactly five `[[mode]]` tables (five unknowns, one reading each per angle), distinct integer
//! ids, finite coordinates, and the two balls of a mode at least 1 mm apart.

use super::BallbarError;
use mtec_io::{line_col, InputError};
use nalgebra::Vector3;
use serde::Deserialize;
use std::path::Path;

/// One installation mode: where the two ball centres are.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Mode {
    pub id: i64,
    /// Workpiece ball centre on the table at C = 0 (mm).
    pub workpiece_ball_mm: [f64; 3],
    /// Tool ball centre, fixed in the machine frame (mm).
    pub tool_ball_mm: [f64; 3],
}

impl Mode {
    pub fn workpiece(&self) -> Vector3<f64> {
        Vector3::from(self.workpiece_ball_mm)
    }
    pub fn tool(&self) -> Vector3<f64> {
        Vector3::from(self.tool_ball_mm)
    }
    /// Nominal bar length (mm); independent of C because C turns about Z.
    pub fn bar_length_mm(&self) -> f64 {
        (self.workpiece() - self.tool()).norm()
    }
}

/// A validated set of five installation modes.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Setup {
    pub modes: Vec<Mode>,
}

/// The free dimensions of the source layout (two centre mounts, one bar length).
///
/// Modes 1–2: ball on the centre mount, on the axis at height `h`; tool cup at radius `b` on +X
/// (mode 1) and +Y (mode 2), same height (radial bars). Modes 3–5: ball on the second mount at
/// radius `a` and height `h`, placed at the table angles `mount2_angles_deg`; tool cup on the
/// axis above mount 1 at `k = sqrt(b² − a²)` above the ball plane (inclined bars of length `b`).
/// The three angles must differ: a ball at one table angle only gives one combination of the
/// radial and axial motions.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PresetDims {
    pub h_mm: f64,
    pub a_mm: f64,
    pub b_mm: f64,
    pub mount2_angles_deg: [f64; 3],
}

impl PresetDims {
    /// Height of the inclined bars' tool cup above the ball plane: `k = sqrt(b² − a²)`.
    pub fn k_mm(&self) -> f64 {
        (self.b_mm * self.b_mm - self.a_mm * self.a_mm).sqrt()
    }
}

impl Setup {
    /// Checks a mode list (count, ids, finite coordinates, bar lengths).
    pub fn new(modes: Vec<Mode>) -> Result<Setup, BallbarError> {
        if modes.len() != 5 {
            return Err(BallbarError::Geometry(format!(
                "the ballbar method needs exactly 5 modes (one reading per unknown error motion \
                 EXC, EYC, EZC, EAC, EBC at each angle); the setup has {}",
                modes.len()
            )));
        }
        for (i, m) in modes.iter().enumerate() {
            if let Some(j) = modes[..i].iter().position(|o| o.id == m.id) {
                return Err(BallbarError::Geometry(format!(
                    "mode id {} is used twice (modes {} and {})",
                    m.id,
                    j + 1,
                    i + 1
                )));
            }
            check_mode(m)?;
        }
        Ok(Setup { modes })
    }

    /// The source layout with the given dimensions (see [`PresetDims`]); ids 1..5.
    pub fn preset(d: PresetDims) -> Result<Setup, BallbarError> {
        let PresetDims {
            h_mm: h,
            a_mm: a,
            b_mm: b,
            mount2_angles_deg,
        } = d;
        if !(h.is_finite() && a.is_finite() && b.is_finite()) || a <= 0.0 || b <= a {
            return Err(BallbarError::Geometry(format!(
                "preset needs 0 < a < b (a = {a} mm, b = {b} mm) so that k = sqrt(b² − a²) > 0"
            )));
        }
        let k = d.k_mm();
        let mut modes = vec![
            Mode {
                id: 1,
                workpiece_ball_mm: [0.0, 0.0, h],
                tool_ball_mm: [b, 0.0, h],
            },
            Mode {
                id: 2,
                workpiece_ball_mm: [0.0, 0.0, h],
                tool_ball_mm: [0.0, b, h],
            },
        ];
        for (i, phi_deg) in mount2_angles_deg.iter().enumerate() {
            let phi = phi_deg.to_radians();
            modes.push(Mode {
                id: 3 + i as i64,
                workpiece_ball_mm: [a * phi.cos(), a * phi.sin(), h],
                tool_ball_mm: [0.0, 0.0, h + k],
            });
        }
        Setup::new(modes)
    }

    /// The preset used by the `dbb-rotary` scenario: h = 100 mm, a = 300 mm, b = 500 mm
    /// (k = 400 mm), second mount at 0°, 120°, 240°. A long bar because the angular motions are
    /// resolved only to ≈ 0.21 µm / b per µm of reading noise (see `conditioning`).
    pub fn default_dims() -> PresetDims {
        PresetDims {
            h_mm: 100.0,
            a_mm: 300.0,
            b_mm: 500.0,
            mount2_angles_deg: [0.0, 120.0, 240.0],
        }
    }

    /// Position of the mode with this id in the list.
    pub fn index_of(&self, id: i64) -> Option<usize> {
        self.modes.iter().position(|m| m.id == id)
    }

    /// The setup as TOML text in the SPEC §4 format.
    pub fn to_toml(&self) -> String {
        let mut s = String::from(
            "# mtec ballbar setup: one [[mode]] per installation (docs/formats.md, Ballbar).\n\
             # workpiece_ball_mm: ball on the table at C = 0; tool_ball_mm: fixed while C turns.\n",
        );
        for m in &self.modes {
            let f = |v: [f64; 3]| format!("[{}, {}, {}]", v[0], v[1], v[2]);
            s.push_str(&format!(
                "\n[[mode]]\nid = {}\nworkpiece_ball_mm = {}\ntool_ball_mm = {}\n",
                m.id,
                f(m.workpiece_ball_mm),
                f(m.tool_ball_mm)
            ));
        }
        s
    }

    /// Reads and validates a setup TOML file.
    pub fn read(path: &Path) -> Result<Setup, InputError> {
        let text = mtec_io::read_text(path)?;
        Setup::parse(path, &text)
    }

    /// Parses setup TOML text read from `path`; every error names the line and column.
    pub fn parse(path: &Path, text: &str) -> Result<Setup, InputError> {
        let raw: RawSetup = mtec_io::parse_toml(path, text)?;
        let at = |span: std::ops::Range<usize>, msg: String| {
            let (l, c) = line_col(text, span.start);
            InputError::at(path, l, c, msg)
        };
        if raw.mode.len() != 5 {
            return Err(InputError::file(
                path,
                format!(
                    "expected exactly 5 [[mode]] tables (one reading per unknown error motion \
                     EXC, EYC, EZC, EAC, EBC at each angle), found {}",
                    raw.mode.len()
                ),
            ));
        }
        let mut modes = Vec::with_capacity(5);
        for (i, rm) in raw.mode.iter().enumerate() {
            let id = *rm.id.get_ref();
            if let Some(j) = raw.mode[..i].iter().position(|o| *o.id.get_ref() == id) {
                return Err(at(
                    rm.id.span(),
                    format!(
                        "mode id {id} is used twice (mode tables {} and {})",
                        j + 1,
                        i + 1
                    ),
                ));
            }
            let m = Mode {
                id,
                workpiece_ball_mm: *rm.workpiece_ball_mm.get_ref(),
                tool_ball_mm: *rm.tool_ball_mm.get_ref(),
            };
            for (name, v) in [
                ("workpiece_ball_mm", &rm.workpiece_ball_mm),
                ("tool_ball_mm", &rm.tool_ball_mm),
            ] {
                if v.get_ref().iter().any(|x| !x.is_finite()) {
                    return Err(at(
                        v.span(),
                        format!("{name} must hold three finite numbers"),
                    ));
                }
            }
            if let Err(e) = check_mode(&m) {
                return Err(at(rm.tool_ball_mm.span(), e.to_string()));
            }
            modes.push(m);
        }
        Setup::new(modes).map_err(|e| InputError::file(path, e.to_string()))
    }
}

fn check_mode(m: &Mode) -> Result<(), BallbarError> {
    let all = m.workpiece_ball_mm.iter().chain(m.tool_ball_mm.iter());
    if all.clone().any(|x| !x.is_finite()) {
        return Err(BallbarError::Geometry(format!(
            "mode {}: ball coordinates must be finite numbers",
            m.id
        )));
    }
    let l = m.bar_length_mm();
    if l < 1.0 {
        return Err(BallbarError::Geometry(format!(
            "mode {}: the two balls are {l:.3} mm apart; a ballbar is at least tens of mm long \
             (check the units: mm)",
            m.id
        )));
    }
    Ok(())
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSetup {
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    #[serde(default)]
    mode: Vec<RawMode>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMode {
    id: toml::Spanned<i64>,
    workpiece_ball_mm: toml::Spanned<[f64; 3]>,
    tool_ball_mm: toml::Spanned<[f64; 3]>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Setup, InputError> {
        Setup::parse(Path::new("s.toml"), s)
    }

    #[test]
    fn preset_round_trips_through_toml() {
        let s = Setup::preset(Setup::default_dims()).unwrap();
        let back = parse(&s.to_toml()).unwrap();
        for (a, b) in s.modes.iter().zip(&back.modes) {
            assert_eq!(a.id, b.id);
            for i in 0..3 {
                assert!((a.workpiece_ball_mm[i] - b.workpiece_ball_mm[i]).abs() < 1e-12);
                assert!((a.tool_ball_mm[i] - b.tool_ball_mm[i]).abs() < 1e-12);
            }
            assert!((a.bar_length_mm() - 500.0).abs() < 1e-9);
        }
    }

    #[test]
    fn errors_are_located() {
        let good = Setup::preset(Setup::default_dims()).unwrap().to_toml();
        // duplicated id: located at the second `id`
        let dup = good.replacen("id = 2", "id = 1", 1);
        let e = parse(&dup).unwrap_err();
        assert!(e.message.contains("used twice"), "{e}");
        let line = dup.lines().position(|l| l == "id = 1").unwrap();
        let second = dup
            .lines()
            .skip(line + 1)
            .position(|l| l == "id = 1")
            .unwrap()
            + line
            + 2;
        assert_eq!(e.line, Some(second));
        // wrong type: three numbers expected
        let e =
            parse(&good.replacen("tool_ball_mm = [500", "tool_ball_mm = [\"x\"", 1)).unwrap_err();
        assert!(e.line.is_some() && e.column.is_some(), "{e}");
        // coincident balls
        let e = parse(&good.replacen(
            "tool_ball_mm = [500, 0, 100]",
            "tool_ball_mm = [0, 0, 100]",
            1,
        ))
        .unwrap_err();
        assert!(e.message.contains("apart"), "{e}");
        assert!(e.line.is_some());
        // four modes
        let four: String = {
            let cut = good.rfind("[[mode]]").unwrap();
            good[..cut].to_string()
        };
        assert!(parse(&four).unwrap_err().message.contains("exactly 5"));
        // unknown key
        let e = parse(&good.replacen("id = 3", "id = 3\nradius_mm = 4", 1)).unwrap_err();
        assert!(e.message.contains("radius_mm"), "{e}");
    }

    #[test]
    fn preset_rejects_impossible_dims() {
        let mut d = Setup::default_dims();
        d.a_mm = 600.0;
        assert!(Setup::preset(d).is_err());
    }
}
