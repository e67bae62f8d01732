//! Which axes of a flattened program's moves the original left where the machine started.
//!
//! Stand-alone rs274 starts every program at machine 0, so its canonical output gives every
//! axis a value in every move, also an axis the program has not commanded yet. On the machine
//! such an axis stays wherever the machine stood: `G0 Z5` as the first move lifts the tool and
//! leaves X and Y alone, while `G0 X0 Y0 Z5` (what rs274's output reads like) also drives X and
//! Y to the work zero. Flattening must therefore know, move by move, which axes the program has
//! really set.
//!
//! The test runs the program twice: as it is (machine 0 at the start) and with one line put in
//! front that moves the machine elsewhere first ([`probe_program`]: `G53 G0` to
//! [`PROBE_START`]). Then, for every move and axis ([`held_axes`]):
//! - the same position in both runs: the program set it (written);
//! - the start position in each run (machine 0 and the probe's start): never commanded yet,
//!   *held* (not written, as in the original);
//! - anything else: the position depends on the start in another way (an incremental move, a
//!   read of the current position, an offset set from it): refused, since no plain program
//!   written for one start is right for every start.
//!
//! Every other call must be the same in both runs (comments and messages excepted): a program
//! whose control flow or offsets depend on where it starts is refused the same way.

use super::canon::{parse_line, Call, FlattenError};

/// Where the probe run starts, in machine coordinates (X Y Z in the program's default units,
/// A B C in degrees): values no program is likely to command by chance.
pub const PROBE_START: [f64; 6] = [7.1234, -5.4321, 3.2109, 17.25, -11.5, 23.75];

/// The program with the probe's first line (`G53 G0 X… Y… Z… A… B… C…`) put in front, after a
/// leading `%` line if there is one.
pub fn probe_program(program: &[u8]) -> Vec<u8> {
    let p = PROBE_START;
    let line = format!(
        "G53 G0 X{} Y{} Z{} A{} B{} C{}\n",
        p[0], p[1], p[2], p[3], p[4], p[5]
    );
    with_first_line(program, &line)
}

/// A tool no table is likely to hold, loaded by the spindle-tool probe
/// ([`spindle_tool_probe_program`]); its table line (inches, as stand-alone rs274 reads it) is
/// [`PROBE_TOOL_LINE`].
pub const PROBE_TOOL: u32 = 99999;
/// The probe tool's line of a LinuxCNC tool table: 4.8607 in (123.46 mm) long.
pub const PROBE_TOOL_LINE: &str = "T99999 P99999 Z4.8607 ;\n";

/// The program with `T99999 M6` in front (after a leading `%`): the tool in the spindle when it
/// starts is then the probe tool instead of stand-alone rs274's tool 0. A program whose tool
/// length offsets differ between the two runs ([`tool_length_offsets`]) uses the tool the
/// machine happens to hold at start: a `G43` without `H`, or an `M6` without a `T`, before its
/// first tool change.
pub fn spindle_tool_probe_program(program: &[u8]) -> Vec<u8> {
    with_first_line(program, &format!("T{PROBE_TOOL} M6\n"))
}

/// The arguments of every `USE_TOOL_LENGTH_OFFSET` call of a canonical printout, in order.
pub fn tool_length_offsets(canon: &str) -> Vec<&str> {
    canon
        .lines()
        .filter_map(|l| l.split_once("USE_TOOL_LENGTH_OFFSET("))
        .map(|(_, args)| args.trim_end().trim_end_matches(')'))
        .collect()
}

/// `program` with `line` put in front, after a leading `%` line if there is one.
fn with_first_line(program: &[u8], line: &str) -> Vec<u8> {
    // the first line that is not blank: LinuxCNC wants a leading % there
    let mut at = 0;
    let mut rest = program;
    while let Some(nl) = rest.iter().position(|&b| b == b'\n') {
        let l = &rest[..nl];
        if l.iter().all(|b| b.is_ascii_whitespace()) {
            at += nl + 1;
            rest = &rest[nl + 1..];
            continue;
        }
        if l.iter().copied().find(|b| !b.is_ascii_whitespace()) == Some(b'%') {
            at += nl + 1;
        }
        break;
    }
    let mut out = Vec::with_capacity(program.len() + line.len());
    out.extend_from_slice(&program[..at]);
    out.extend_from_slice(line.as_bytes());
    out.extend_from_slice(&program[at..]);
    out
}

/// Offsets of one run, to turn canonical positions (work frame, current units) into machine
/// positions: machine = canonical + G5x + G92 + tool length (see [`super::flatten`]).
#[derive(Default)]
struct Frame {
    inch: bool,
    /// 0 XY, 1 XZ, 2 YZ (SELECT_PLANE): which axes an ARC_FEED's values belong to.
    plane: usize,
    g5x: [f64; 3],
    g92: [f64; 3],
    tool: [f64; 3],
}

impl Frame {
    fn scale(&self) -> f64 {
        if self.inch {
            25.4
        } else {
            1.0
        }
    }

    fn update(&mut self, c: &Call) -> Result<(), FlattenError> {
        let s = self.scale();
        match c.name {
            "USE_LENGTH_UNITS" => self.inch = c.args.first() == Some(&"CANON_UNITS_INCHES"),
            "SELECT_PLANE" => {
                self.plane = match c.args.first().copied() {
                    Some("CANON_PLANE_XZ") => 1,
                    Some("CANON_PLANE_YZ") => 2,
                    _ => 0,
                }
            }
            "SET_G5X_OFFSET" => {
                let v = c.numbers(4)?;
                self.g5x = [v[1] * s, v[2] * s, v[3] * s];
            }
            "SET_G92_OFFSET" => {
                let v = c.numbers(3)?;
                self.g92 = [v[0] * s, v[1] * s, v[2] * s];
            }
            "USE_TOOL_LENGTH_OFFSET" => {
                let v = c.numbers(3)?;
                self.tool = [v[0] * s, v[1] * s, v[2] * s];
            }
            _ => {}
        }
        Ok(())
    }

    /// Machine X Y Z (mm) and A B C (deg) at the end of a motion call, and a tolerance of
    /// 0.6 of the printed resolution (mm) for the linear axes.
    fn end(&self, c: &Call) -> Result<Option<([f64; 6], f64)>, FlattenError> {
        let s = self.scale();
        let (xyz, abc) = match c.name {
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" | "STRAIGHT_PROBE" => {
                let v = c.numbers(6)?;
                ([v[0], v[1], v[2]], [v[3], v[4], v[5]])
            }
            "ARC_FEED" => {
                let v = c.numbers(9)?;
                // (first, second, normal) = (X, Y, Z) in G17, (Z, X, Y) in G18, (Y, Z, X) in G19
                let (f, se, n) = [(0, 1, 2), (2, 0, 1), (1, 2, 0)][self.plane];
                let mut xyz = [0.0; 3];
                xyz[f] = v[0];
                xyz[se] = v[1];
                xyz[n] = v[5];
                (xyz, [v[6], v[7], v[8]])
            }
            _ => return Ok(None),
        };
        let m = [
            xyz[0] * s + self.g5x[0] + self.g92[0] + self.tool[0],
            xyz[1] * s + self.g5x[1] + self.g92[1] + self.tool[1],
            xyz[2] * s + self.g5x[2] + self.g92[2] + self.tool[2],
            abc[0],
            abc[1],
            abc[2],
        ];
        Ok(Some((m, 0.6e-4 * s)))
    }
}

fn is_motion(name: &str) -> bool {
    matches!(
        name,
        "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" | "STRAIGHT_PROBE" | "ARC_FEED"
    )
}

/// The next call of a canonical text (blank lines skipped).
fn next_call<'a>(
    lines: &mut std::iter::Enumerate<std::str::Lines<'a>>,
) -> Result<Option<Call<'a>>, FlattenError> {
    for (i, raw) in lines.by_ref() {
        if let Some(c) = parse_line(raw, i + 1)? {
            return Ok(Some(c));
        }
    }
    Ok(None)
}

const DEPENDS: &str = "depends on where the machine stands when the program starts (an incremental move, or a read of the current position, before that axis is commanded): a flattened program is written for one start; command every axis absolutely before it is used";

/// For every motion call of `run` (rs274's output for the program), in order: which of X, Y,
/// Z, A, B, C are still where the machine started. `probe` is rs274's output for
/// [`probe_program`] of the same program with the same inputs. An error names the call of
/// `run` where the two runs part.
pub fn held_axes(run: &str, probe: &str) -> Result<Vec<[bool; 6]>, FlattenError> {
    let mut a = run.lines().enumerate();
    let mut b = probe.lines().enumerate();
    let (mut fa, mut fb) = (Frame::default(), Frame::default());
    let mut out = Vec::new();
    // the probe run's first move is the probe line: where that run starts
    let mut start_b: Option<[f64; 6]> = None;
    let mut last_a_line = 0;
    loop {
        let ca = next_call(&mut a)?;
        let mut cb = next_call(&mut b)?;
        if start_b.is_none() {
            if let Some(c) = cb.as_ref().filter(|c| is_motion(c.name)) {
                start_b = Some(fb.end(c)?.map(|(m, _)| m).unwrap_or([0.0; 6]));
                cb = next_call(&mut b)?;
            }
        }
        let (ca, cb) = match (ca, cb) {
            (None, None) => break,
            (Some(ca), Some(cb)) => (ca, cb),
            (Some(ca), None) => {
                return Err(ca.err(format!(
                    "this call is missing when the program starts elsewhere: its course {DEPENDS}"
                )))
            }
            (None, Some(_)) => {
                return Err(FlattenError {
                    line: last_a_line,
                    call: String::new(),
                    message: format!(
                    "the program goes on further when it starts elsewhere: its course {DEPENDS}"
                ),
                })
            }
        };
        last_a_line = ca.line;
        if ca.name != cb.name {
            return Err(ca.err(format!(
                "the program runs {} here when it starts elsewhere: its course {DEPENDS}",
                cb.name
            )));
        }
        if !is_motion(ca.name) {
            if !matches!(ca.name, "COMMENT" | "MESSAGE") && ca.inner.trim() != cb.inner.trim() {
                return Err(ca.err(format!(
                    "the call reads {}({}) when the program starts elsewhere: its value {DEPENDS}",
                    cb.name,
                    cb.inner.trim()
                )));
            }
            fa.update(&ca)?;
            fb.update(&cb)?;
            continue;
        }
        if ca.name == "ARC_FEED" {
            // the plane's end point and centre and the turns must not depend on the start
            // (the normal axis may still be held: a plane arc before Z is commanded)
            let (va, vb) = (ca.numbers(5)?, cb.numbers(5)?);
            if va != vb {
                return Err(ca.err(format!(
                    "the arc reads ARC_FEED({}) when the program starts elsewhere: it {DEPENDS}",
                    cb.inner.trim()
                )));
            }
        }
        let (Some((ma, tol)), Some((mb, _))) = (fa.end(&ca)?, fb.end(&cb)?) else {
            continue;
        };
        let sb = start_b.unwrap_or([0.0; 6]);
        let mut held = [false; 6];
        for k in 0..6 {
            let t = if k < 3 { tol } else { 0.6e-4 };
            if (ma[k] - mb[k]).abs() <= t {
                continue;
            }
            if ma[k].abs() <= t && (mb[k] - sb[k]).abs() <= t {
                held[k] = true;
                continue;
            }
            return Err(ca.err(format!(
                "axis {} {DEPENDS}",
                ["X", "Y", "Z", "A", "B", "C"][k]
            )));
        }
        out.push(held);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn canon(calls: &[&str]) -> String {
        let mut s = String::from(
            "    1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n    2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n",
        );
        for (i, c) in calls.iter().enumerate() {
            s.push_str(&format!("{:5} N..... {c}\n", i + 3));
        }
        s
    }

    const PROBE_MOVE: &str =
        "STRAIGHT_TRAVERSE(7.1234, -5.4321, 3.2109, 17.2500, -11.5000, 23.7500)";

    #[test]
    fn the_probe_line_goes_after_a_leading_percent() {
        assert_eq!(
            String::from_utf8(probe_program(b"\n%\nG0 X1\n%\n")).unwrap(),
            "\n%\nG53 G0 X7.1234 Y-5.4321 Z3.2109 A17.25 B-11.5 C23.75\nG0 X1\n%\n"
        );
        assert!(String::from_utf8(probe_program(b"(hi)\nG0 X1\n"))
            .unwrap()
            .starts_with("G53 G0 X7.1234"));
    }

    #[test]
    fn the_spindle_tool_probe_loads_its_tool_first_and_lists_the_tool_offsets() {
        assert_eq!(
            String::from_utf8(spindle_tool_probe_program(b"%\nG43\n%\n")).unwrap(),
            "%\nT99999 M6\nG43\n%\n"
        );
        assert!(PROBE_TOOL_LINE.starts_with(&format!("T{PROBE_TOOL} ")));
        let run = canon(&[
            "USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)",
            "STRAIGHT_TRAVERSE(1.0000, 1.0000, 8.0000, 0.0000, 0.0000, 0.0000)",
            "USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 25.4000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)",
        ]);
        assert_eq!(
            tool_length_offsets(&run),
            [
                "0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000",
                "0.0000 0.0000 25.4000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000"
            ]
        );
        assert!(tool_length_offsets(&canon(&[PROBE_MOVE])).is_empty());
    }

    #[test]
    fn uncommanded_axes_are_held_commanded_ones_written() {
        // G0 Z5, then G0 X1 Y2: X and Y held in the first move only
        let run = canon(&[
            "STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
            "STRAIGHT_TRAVERSE(1.0000, 2.0000, 5.0000, 0.0000, 0.0000, 0.0000)",
        ]);
        let probe = canon(&[
            PROBE_MOVE,
            "STRAIGHT_TRAVERSE(7.1234, -5.4321, 5.0000, 17.2500, -11.5000, 23.7500)",
            "STRAIGHT_TRAVERSE(1.0000, 2.0000, 5.0000, 17.2500, -11.5000, 23.7500)",
        ]);
        let h = held_axes(&run, &probe).unwrap();
        assert_eq!(
            h,
            vec![
                [true, true, false, true, true, true],
                [false, false, false, true, true, true]
            ]
        );
    }

    #[test]
    fn an_incremental_first_move_is_refused() {
        // G91 G0 X10 from the start: 10 in one run, 17.1234 in the other
        let run = canon(&["STRAIGHT_TRAVERSE(10.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)"]);
        let probe = canon(&[
            PROBE_MOVE,
            "STRAIGHT_TRAVERSE(17.1234, -5.4321, 3.2109, 17.2500, -11.5000, 23.7500)",
        ]);
        let e = held_axes(&run, &probe).unwrap_err();
        assert_eq!(e.line, 3);
        assert!(e.message.starts_with("axis X depends on where"), "{e}");
    }

    #[test]
    fn a_different_course_or_offset_is_refused_and_comments_may_differ() {
        let run = canon(&[
            "COMMENT(\"x=0\")",
            "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
        ]);
        let probe = canon(&[
            PROBE_MOVE,
            "COMMENT(\"x=7.1234\")",
            "SET_G92_OFFSET(-7.1234, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
        ]);
        let e = held_axes(&run, &probe).unwrap_err();
        assert_eq!(e.line, 4);
        assert!(e.message.contains("SET_G92_OFFSET(-7.1234"), "{e}");
        // one run stops earlier
        let run = canon(&["STRAIGHT_FEED(1.0000, 1.0000, 1.0000, 0.0000, 0.0000, 0.0000)"]);
        let probe = canon(&[PROBE_MOVE]);
        assert!(held_axes(&run, &probe)
            .unwrap_err()
            .message
            .contains("missing"));
    }

    #[test]
    fn arcs_in_the_xz_plane_hold_y() {
        // a lathe program in G18 never commands Y
        let run = canon(&[
            "SELECT_PLANE(CANON_PLANE_XZ)",
            "STRAIGHT_FEED(1.0000, 0.0000, 2.0000, 0.0000, 0.0000, 0.0000)",
            "ARC_FEED(3.0000, 1.0000, 2.5000, 1.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)",
        ]);
        let probe = canon(&[
            PROBE_MOVE,
            "SELECT_PLANE(CANON_PLANE_XZ)",
            "STRAIGHT_FEED(1.0000, -5.4321, 2.0000, 17.2500, -11.5000, 23.7500)",
            "ARC_FEED(3.0000, 1.0000, 2.5000, 1.0000, 1, -5.4321, 17.2500, -11.5000, 23.7500)",
        ]);
        let held = [false, true, false, true, true, true];
        assert_eq!(held_axes(&run, &probe).unwrap(), vec![held, held]);
    }

    #[test]
    fn inch_positions_compare_in_machine_mm() {
        let run = canon(&[
            "USE_LENGTH_UNITS(CANON_UNITS_INCHES)",
            "STRAIGHT_FEED(0.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
        ]);
        // the probe started at X 7.1234 mm = 0.2805 in
        let probe = canon(&[
            PROBE_MOVE,
            "USE_LENGTH_UNITS(CANON_UNITS_INCHES)",
            "STRAIGHT_FEED(0.2805, 1.0000, 0.1264, 17.2500, -11.5000, 23.7500)",
        ]);
        assert_eq!(
            held_axes(&run, &probe).unwrap(),
            vec![[true, false, true, true, true, true]]
        );
    }
}
