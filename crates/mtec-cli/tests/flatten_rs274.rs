//! `compensate gcode --flatten-with rs274` checked against LinuxCNC's interpreter itself.
//!
//! For each program (the real LinuxCNC programs in `../shared/data/gcode/linuxcnc` beside the
//! repository root or `$MTEC_SHARED_DIR`, and the hand-written ones in `tests/data/flatten`):
//! flatten and compensate it with a zero model, run `rs274 -g` on the original and on the
//! output, and check that the motion calls (STRAIGHT_TRAVERSE, STRAIGHT_FEED, ARC_FEED) are the
//! same sequence with the same end points, arc centres, turns and feeds in *machine*
//! coordinates (canonical + G5x + G92 + tool length offset, as rs274 prints them) to 1e-4 in
//! the program's units — or that flattening refused with the expected reason.
//!
//! Without rs274 the tests print a note and pass, unless `CI` is set: then they fail.

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn mtec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// rs274 on PATH; `None` (with a note) when absent and not in CI.
fn rs274() -> Option<PathBuf> {
    support::tool_on_path(&["rs274"], "linuxcnc-uspace", "flattening not checked")
}

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/flatten")
}

/// `../shared/data/gcode/linuxcnc` beside the repository root (or a git worktree's main
/// checkout), or `$MTEC_SHARED_DIR/data/gcode/linuxcnc`.
fn real_programs_dir() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    [
        std::env::var_os("MTEC_SHARED_DIR").map(PathBuf::from),
        Some(root.join("../shared")),
        Some(root.join("../../shared")),
    ]
    .into_iter()
    .flatten()
    .map(|p| p.join("data/gcode/linuxcnc"))
    .find(|p| p.is_dir())
}

/// `rs274 -g [-t table] [-v var] file` in its own folder (and HOME: rs274 writes
/// `$HOME/.tool.mmap`); returns standard output, or the error text.
fn run_rs274(
    bin: &Path,
    file: &Path,
    table: Option<&Path>,
    var: Option<&Path>,
) -> Result<String, String> {
    let dir = tempfile::tempdir().unwrap();
    let mut c = Command::new(bin);
    c.current_dir(dir.path()).env("HOME", dir.path()).arg("-g");
    if let Some(t) = table {
        let copy = dir.path().join("tool.tbl");
        std::fs::copy(t, &copy).unwrap();
        c.arg("-t").arg(copy);
    }
    if let Some(v) = var {
        let copy = dir.path().join("params.var");
        std::fs::copy(v, &copy).unwrap();
        c.arg("-v").arg(copy);
    }
    let o = c.arg(file).output().unwrap();
    if o.status.success() {
        Ok(String::from_utf8_lossy(&o.stdout).into_owned())
    } else {
        Err(text(&o))
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Kind {
    Traverse,
    Feed,
    Arc { plane: usize, turns: i64 },
}

/// A motion call in machine coordinates (mm), with the feed in force (mm/min or mm/rev).
#[derive(Debug, Clone)]
struct Motion {
    line: usize,
    kind: Kind,
    end: [f64; 3],
    /// Arc centre, in-plane coordinates (machine, mm), in X, Y, Z order of the plane's axes.
    centre: [f64; 2],
    feed: f64,
    per_rev: bool,
    /// mm per program unit when the call was printed (the comparison tolerance scales with it).
    scale: f64,
}

fn numbers(args: &str) -> Vec<f64> {
    args.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect()
}

/// The motion calls of a canonical listing, in machine coordinates. Written separately from
/// the flattener (same conventions, verified by experiment: see flatten.rs).
fn motions(canon: &str) -> Vec<Motion> {
    let mut scale = 1.0;
    let (mut g5x, mut g92, mut tool) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    let (mut plane, mut feed, mut per_rev) = (0usize, 0.0, false);
    let mut out = Vec::new();
    for (i, line) in canon.lines().enumerate() {
        let Some(open) = line.find('(') else { continue };
        let name = line[..open].split_whitespace().last().unwrap_or("");
        let args = &line[open + 1..line.rfind(')').unwrap_or(line.len())];
        let v = numbers(args);
        let off = |a: usize| g5x[a] + g92[a] + tool[a];
        match name {
            "USE_LENGTH_UNITS" => scale = if args.contains("INCHES") { 25.4 } else { 1.0 },
            "SET_G5X_OFFSET" => g5x = [v[1] * scale, v[2] * scale, v[3] * scale],
            "SET_G92_OFFSET" => g92 = [v[0] * scale, v[1] * scale, v[2] * scale],
            "USE_TOOL_LENGTH_OFFSET" => tool = [v[0] * scale, v[1] * scale, v[2] * scale],
            "SELECT_PLANE" => {
                plane = if args.contains("XY") {
                    0
                } else if args.contains("XZ") {
                    1
                } else {
                    2
                }
            }
            "SET_FEED_RATE" => feed = v[0] * scale,
            "SET_FEED_MODE" => per_rev = v[1] == 1.0,
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" => out.push(Motion {
                line: i + 1,
                kind: if name == "STRAIGHT_FEED" {
                    Kind::Feed
                } else {
                    Kind::Traverse
                },
                end: std::array::from_fn(|a| v[a] * scale + off(a)),
                centre: [0.0; 2],
                feed,
                per_rev,
                scale,
            }),
            "ARC_FEED" => {
                let (f, s, n) = [(0, 1, 2), (2, 0, 1), (1, 2, 0)][plane];
                let mut end = [0.0; 3];
                end[f] = v[0] * scale + off(f);
                end[s] = v[1] * scale + off(s);
                end[n] = v[5] * scale + off(n);
                out.push(Motion {
                    line: i + 1,
                    kind: Kind::Arc {
                        plane,
                        turns: v[4] as i64,
                    },
                    end,
                    centre: [v[2] * scale + off(f), v[3] * scale + off(s)],
                    feed,
                    per_rev,
                    scale,
                });
            }
            _ => {}
        }
    }
    out
}

/// Compares two listings' motion; returns the number of calls compared.
fn same_motion(original: &str, flattened: &str, what: &str) -> usize {
    let a = motions(original);
    let b = motions(flattened);
    assert_eq!(
        a.len(),
        b.len(),
        "{what}: {} motion calls in the original, {} after flattening",
        a.len(),
        b.len()
    );
    assert!(!a.is_empty(), "{what}: no motion at all");
    for (x, y) in a.iter().zip(&b) {
        let tol = 1e-4 * x.scale.max(y.scale) + 1e-9;
        let ctx = || {
            format!(
                "{what}: original canonical line {} vs flattened line {}: {x:?} / {y:?}",
                x.line, y.line
            )
        };
        assert_eq!(x.kind, y.kind, "{}", ctx());
        for k in 0..3 {
            assert!((x.end[k] - y.end[k]).abs() <= tol, "end: {}", ctx());
        }
        if matches!(x.kind, Kind::Arc { .. }) {
            for k in 0..2 {
                assert!(
                    (x.centre[k] - y.centre[k]).abs() <= tol,
                    "centre: {}",
                    ctx()
                );
            }
        }
        if x.kind != Kind::Traverse {
            assert_eq!(x.per_rev, y.per_rev, "feed mode: {}", ctx());
            assert!(
                (x.feed - y.feed).abs() <= tol + 1e-9 * x.feed.abs(),
                "feed: {}",
                ctx()
            );
        }
    }
    a.len()
}

/// A copy of `program` (in `dir`) that first moves the machine to another position
/// (`G53 G0`, after a leading `%`): how it runs when the machine does not start at zero.
fn started_elsewhere(program: &Path, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(program).unwrap();
    let start = "G53 G0 X31.7 Y-12.9 Z8.3\n";
    let body = match text.trim_start().strip_prefix('%') {
        Some(rest) => format!(
            "%{}{start}{}",
            &rest[..rest.find('\n').map_or(0, |i| i + 1)],
            &rest[rest.find('\n').map_or(rest.len(), |i| i + 1)..]
        ),
        None => format!("{start}{text}"),
    };
    let name = program.file_name().unwrap().to_string_lossy();
    let p = dir.join(format!("elsewhere-{name}"));
    std::fs::write(&p, body).unwrap();
    p
}

const ZERO_MODEL: &str = r#"{"format": "mtec.zero-model/1"}"#;

enum Expect {
    /// Flattens; the output reproduces the original's motion.
    Same,
    /// Refused (exit 2) with these words in the message.
    Refused(&'static str),
}

/// Flattens `program` with the CLI and checks the outcome; returns a one-line summary.
fn check(
    bin: &Path,
    program: &Path,
    table: Option<&Path>,
    var: Option<&Path>,
    extra: &[&str],
    expect: &Expect,
) -> String {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    let out = dir.path().join("flat.ngc");
    let mut c = mtec();
    c.args(["compensate", "gcode", "--model"])
        .arg(&model)
        .args(["--flatten-with", "rs274", "--rs274"])
        .arg(bin)
        // the test tables and parameter files are written in inches, as rs274 reads them
        .args(["--machine-units", "inch"])
        .args(extra);
    if let Some(t) = table {
        c.arg("--tool-table").arg(t);
    }
    if let Some(v) = var {
        c.arg("--var-file").arg(v);
    }
    let o = c.arg(program).arg("-o").arg(&out).output().unwrap();
    let name = program.file_name().unwrap().to_string_lossy().into_owned();
    match expect {
        Expect::Same => {
            assert_eq!(o.status.code(), Some(0), "{name}: {}", text(&o));
            let flat = std::fs::read_to_string(&out).unwrap();
            assert!(
                flat.lines().all(|l| l.len() <= 255),
                "{name}: a line over 255 characters"
            );
            // the header first, after the leading % of a program that ends at its %
            let header = flat.lines().find(|l| *l != "%").unwrap();
            assert!(
                header.starts_with("(mtec: ") && header.contains("flattened by rs274"),
                "{name}: {header}"
            );
            let original = run_rs274(bin, program, table, var)
                .unwrap_or_else(|e| panic!("{name}: rs274 on the original: {e}"));
            // the flattened program is plain: no tool table needed for it to move the same
            let again = run_rs274(bin, &out, None, var)
                .unwrap_or_else(|e| panic!("{name}: rs274 on the flattened program: {e}"));
            let n = same_motion(&original, &again, &name);
            // and the same from another start position: an axis the original has not
            // commanded yet stays where the machine stood in both
            let original = run_rs274(bin, &started_elsewhere(program, dir.path()), table, var)
                .unwrap_or_else(|e| panic!("{name}: rs274 on the original from elsewhere: {e}"));
            let again = run_rs274(bin, &started_elsewhere(&out, dir.path()), None, var)
                .unwrap_or_else(|e| panic!("{name}: rs274 on the flattened from elsewhere: {e}"));
            same_motion(&original, &again, &format!("{name} started elsewhere"));
            format!("{name}: flattened, {n} motion calls identical, also from another start")
        }
        Expect::Refused(words) => {
            assert_eq!(o.status.code(), Some(2), "{name}: {}", text(&o));
            let msg = text(&o);
            assert!(msg.contains(words), "{name}: expected '{words}' in: {msg}");
            assert!(!out.exists(), "{name}: output written despite the refusal");
            format!(
                "{name}: refused: {}",
                msg.lines().last().unwrap_or("").trim()
            )
        }
    }
}

#[test]
fn real_linuxcnc_programs_flatten_to_the_same_motion_or_are_refused_with_the_reason() {
    let Some(bin) = rs274() else { return };
    let Some(dir) = real_programs_dir() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "the shared LinuxCNC programs are required in CI (set MTEC_SHARED_DIR)"
        );
        eprintln!("note: ../shared/data/gcode/linuxcnc not found (set MTEC_SHARED_DIR)");
        return;
    };
    let data = data_dir();
    let mill = data.join("mill.tbl");
    let lathe = data.join("lathe.tbl");
    use Expect::*;
    let cases: [(&str, Option<&Path>, &[&str], Expect); 14] = [
        // T1 M6: with no table rs274 would take its built-in T1 (0.511 in), so mtec gives it
        // the user's table or an empty one (refused: see tool_lengths_come_from_the_user_only)
        ("3D_Chips", Some(&mill), &[], Same),
        ("arcspiral", None, &[], Same),
        ("cds", Some(&mill), &[], Same),
        ("comp", Some(&mill), &[], Same),
        // written for a machine with a W quill: stand-alone rs274 (X Y Z A B C) stops at the
        // W word, located in the source from the line rs274 prints
        (
            "cone",
            None,
            &[],
            Refused("cone.ngc:34:8: rs274 stopped with an error (exit 1): Bad character 'w'"),
        ),
        ("contour", None, &[], Same),
        // flattened with its A moves; a three-axis model cannot compensate them (with a
        // fourth-axis model it is compensated: tests/compensate_gcode_rotary.rs)
        (
            "daisy",
            None,
            &[],
            Refused("axis A moves but the error model has no rotary axes"),
        ),
        ("flowsnake", None, &[], Same),
        ("g76", Some(&lathe), &[], Refused("spindle-synchronised")),
        ("gridprobe", None, &[], Refused("probing")),
        ("hole-circle", None, &[], Same),
        (
            "increment",
            None,
            &[],
            Refused("File ended with no percent sign or program end"),
        ),
        // a lathe program never states Y: the rewriter needs it for its feed moves
        ("lathe_pawn", None, &["--start-position-mm", "0,0,0"], Same),
        ("spiral_tangent_test", None, &[], Same),
    ];
    let mut summary = Vec::new();
    for (name, table, extra, expect) in &cases {
        let p = dir.join(format!("{name}.ngc"));
        summary.push(check(&bin, &p, *table, None, extra, expect));
    }
    eprintln!("{}", summary.join("\n"));
}

#[test]
fn hand_written_programs_with_control_flow_cycles_and_compensation_flatten_exactly() {
    let Some(bin) = rs274() else { return };
    let data = data_dir();
    let mill = data.join("mill.tbl");
    let var = data.join("offsets.var");
    let mut summary = Vec::new();
    for name in [
        "subs_loops",
        "canned",
        "cutter_comp",
        "polar",
        "offsets",
        "coverage",
    ] {
        let p = data.join(format!("{name}.ngc"));
        // its G52 replaces a G92 offset the machine may keep (and its G10 L2 changes a table
        // nobody gave): refused without the parameter file
        let unknown_start = if name == "offsets" {
            Expect::Refused("offsets.ngc:10:1: this G52/G92.x replaces the G92 offset")
        } else {
            Expect::Same
        };
        summary.push(check(&bin, &p, Some(&mill), None, &[], &unknown_start));
        // the same with non-zero work offsets read from a parameter file (G54, G55 set)
        summary.push(check(&bin, &p, Some(&mill), Some(&var), &[], &Expect::Same));
    }
    eprintln!("{}", summary.join("\n"));
}

#[test]
fn recorded_flattening_of_the_unit_test_reproduces_rs274s_motion() {
    // mtec-comp's unit test flattens a recorded rs274 listing into a recorded program; check
    // here, with rs274, that this program moves as the original does
    let Some(bin) = rs274() else { return };
    let comp = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../mtec-comp/tests/data/flatten");
    let data = data_dir();
    let mill = data.join("mill.tbl");
    let original = run_rs274(&bin, &data.join("offsets.ngc"), Some(&mill), None).unwrap();
    let recorded = std::fs::read_to_string(comp.join("offsets.canon")).unwrap();
    assert_eq!(
        motions(&original).len(),
        motions(&recorded).len(),
        "offsets.canon is not rs274's output for offsets.ngc any more"
    );
    same_motion(&original, &recorded, "offsets.canon");
    let flat = run_rs274(&bin, &comp.join("offsets.flat.ngc"), None, None).unwrap();
    same_motion(&original, &flat, "offsets.flat.ngc");
}

#[test]
fn constructs_without_a_plain_equivalent_are_refused_naming_the_canonical_line() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    for (body, words) in [
        ("G0 X0 Y0 Z5\nG38.2 Z-10 F50\n", "probing"),
        ("M3 S500\nG0 X1 Z1\nG33 Z-5 K1\n", "spindle-synchronised"),
        ("M3 S500\nG0 X1 Z1\nG33.1 Z-5 K1\n", "rigid tapping"),
        ("G0 X0 Y0\nG5 X10 Y10 I5 J0 P5 Q0 F100\n", "splines"),
        // a rotary move is flattened, and refused by the rewriter with this three-axis model
        (
            "G0 X0 Y0\nG1 X1 A10 F100\n",
            "axis A moves but the error model has no rotary axes",
        ),
        (
            "G0 X0 Y0\nG2 X10 Y0 I5 J0 A10 F100\n",
            "turns the rotary axis A",
        ),
        ("G10 L2 P1 R30\nG0 X1 Y1\n", "rotated"),
        ("G0 X1\nM100\n", "Unknown m code used: M100"),
        ("o1 while [1]\nG0 X1\no1 endwhile\n", "did not finish"),
    ] {
        let p = dir.path().join("bad.ngc");
        std::fs::write(&p, format!("G21 G90 G17\n{body}M2\n")).unwrap();
        let extra: &[&str] = if words == "did not finish" {
            &["--rs274-timeout-s", "2"]
        } else {
            &[]
        };
        let msg = check(&bin, &p, None, None, extra, &Expect::Refused(words));
        if words != "did not finish" && !words.starts_with("Unknown") && !words.contains("model") {
            assert!(msg.contains("canonical line"), "{msg}");
            // and the block rs274 issued the call from, found by a numbered run: the last line
            // of the body; the rotation of G54 is issued when M2 selects G54 (rs274 starts in
            // G59.3 when the work offsets are not given)
            let line = 1 + body.lines().count() + usize::from(words == "rotated");
            assert!(msg.contains(&format!("bad.ngc:{line}:1:")), "{msg}");
        }
    }
}

#[test]
fn what_the_machine_decides_at_run_time_is_kept_or_refused() {
    // found on LinuxCNC's own example programs (/usr/share/linuxcnc/ncfiles and the sample
    // configurations of linuxcnc-uspace), run through tests/rs274/run_all.py
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    // cds.ngc: the first move lifts Z only; X and Y stay where the machine stands (not X0 Y0),
    // and an M9 with nothing on still reaches the machine
    let p = write(
        "lift.ngc",
        "G21 G90 M9\nG0 Z5\nG0 X10 Y10\nG1 Z-1 F100\nG2 X20 I5\nM2\n",
    );
    check(&bin, &p, None, None, &[], &Expect::Same);
    let flat = flatten_text(&bin, &p);
    let first_move = flat.lines().find(|l| l.starts_with("G0 ")).unwrap();
    assert_eq!(first_move, "G0 Z5.0", "{flat}");
    assert!(flat.lines().any(|l| l == "M9"), "{flat}");
    // db_demo/base.ngc and on_abort.ngc: a program that ends at its % ends at a % again (M2
    // would also stop the spindle and reset the modes)
    let p = write("percent.ngc", "%\nG21 G90\nM3 S1000\nG0 X1 Y2 Z3\n%\n");
    check(&bin, &p, None, None, &[], &Expect::Same);
    let flat = flatten_text(&bin, &p);
    assert_eq!(flat.lines().next(), Some("%"), "{flat}");
    assert_eq!(flat.lines().last(), Some("%"), "{flat}");
    assert!(!flat.contains("M2"), "{flat}");
    for (name, body, words) in [
        // an incremental first move goes somewhere that depends on the start
        (
            "incremental.ngc",
            "G21 G91\nG0 X10\nG90 G0 Y5\nM2\n",
            "axis X depends on where the machine stands",
        ),
        // the current position read before an axis is set
        (
            "position.ngc",
            "G21 G90\nG0 Z[#5422 + 5]\nM2\n",
            "depends on where the machine stands",
        ),
        // `G0 A0` turns a table that stood elsewhere back to 0: the word is kept, so a
        // three-axis model refuses it as it refuses it without flattening (it was dropped)
        (
            "a-zero.ngc",
            "G21 G90\no1 if [1]\nG0 X1 Y1 Z1 A0\no1 endif\nG1 X5 F100\nM2\n",
            "axis A moves but the error model has no rotary axes",
        ),
        // db_demo/base.ngc: #<_task> is 0 in stand-alone rs274 and 1 on the machine, so the
        // loop runs zero times in rs274 and five on the machine: refused at line and column
        (
            "task.ngc",
            "G21 G90\n#<ct> = 0\no100 while [[#<ct> lt 5] and [#<_task> ne 0]]\n#<ct> = [#<ct> + 1]\nG0 X#<ct>\no100 endwhile\nM2\n",
            "task.ngc:3:31: #<_task> reads the machine's state",
        ),
        // work offsets live in the controller's parameter file in machine units, which
        // stand-alone rs274 reads as inches (and mtec makes up without --var-file): `#5221`
        // read 0 here where the machine reads its G54 X (found 2026-11-28, hand-written)
        (
            "offset-read.ngc",
            "G21 G90\nG0 X0 Y0 Z0\nG1 X[#5221 + 10] F500\nM2\n",
            "offset-read.ngc:3:6: #5221 reads or sets a work offset",
        ),
        // `#5242 = 3` is G55's Y in mm on a metric machine and 76.2 mm in rs274
        (
            "offset-write.ngc",
            "G21 G90\n#5242 = 3\nG55\nG0 X0 Y0 Z0\nM2\n",
            "offset-write.ngc:2:1: #5242 reads or sets",
        ),
        // an indirect reference may address them: the probe macros' active-system offset
        (
            "offset-indirect.ngc",
            "G21 G90\n#<x> = #[5201 + [20 * #5220]]\nG0 X#<x> Y0 Z0\nM2\n",
            "offset-indirect.ngc:2:8: #[5201 + [20 * #5220]] reads or sets",
        ),
        // the tool table too: rs274 gives a G21 program a 1-inch tool's #5403 as 1
        (
            "tool-read.ngc",
            "G21 G90\nT1 M6\nG0 X#5403 Y0 Z0\nM2\n",
            "tool-read.ngc:3:5: #5403 reads or sets the loaded tool's offsets",
        ),
        // machine coordinates add the work offsets, which none were given for
        (
            "abs.ngc",
            "G21 G90\nG0 X1 Y0 Z0\nG1 X#<_abs_x> F100\nM2\n",
            "abs.ngc:3:5: #<_abs_x> reads the position in machine coordinates",
        ),
    ] {
        let p = write(name, body);
        check(&bin, &p, None, None, &[], &Expect::Refused(words));
    }
}

/// `compensate gcode --flatten-with rs274` of `program` with the zero `model` and the options
/// `given` (flag, file), written to `dir/flat.ngc`: exit code, messages, the output if written.
fn flatten_zero(
    bin: &Path,
    dir: &Path,
    model: &Path,
    program: &Path,
    given: &[(&str, &Path)],
) -> (Option<i32>, String, Option<String>) {
    let out = dir.join("flat.ngc");
    let _ = std::fs::remove_file(&out);
    let mut c = mtec();
    c.args(["compensate", "gcode", "--model"])
        .arg(model)
        .args(["--flatten-with", "rs274", "--rs274"])
        .arg(bin);
    for (flag, file) in given {
        c.arg(flag).arg(file);
    }
    let o = c.arg(program).arg("-o").arg(&out).output().unwrap();
    (
        o.status.code(),
        text(&o),
        std::fs::read_to_string(&out).ok(),
    )
}

/// The flattened text of `program` (zero model).
fn flatten_text(bin: &Path, program: &Path) -> String {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    let out = dir.path().join("flat.ngc");
    let o = mtec()
        .args(["compensate", "gcode", "--model"])
        .arg(&model)
        .args(["--flatten-with", "rs274", "--rs274"])
        .arg(bin)
        .arg(program)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    std::fs::read_to_string(&out).unwrap()
}

#[test]
fn compensated_flat_program_is_accepted_by_rs274_and_moves_by_the_correction() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("poly.json");
    // e_x = 20 um everywhere: every X command moves by -0.02 mm
    std::fs::write(
        &model,
        r#"{"format": "mtec.poly-model/1", "terms": [{"powers": [0,0,0], "coef_um": [20.0, 0.0, 0.0]}]}"#,
    )
    .unwrap();
    let prog = data_dir().join("subs_loops.ngc");
    let out = dir.path().join("comp.ngc");
    let o = mtec()
        .args(["compensate", "gcode", "--model"])
        .arg(&model)
        .args(["--flatten-with", "rs274", "--max-segment-mm", "1000"])
        .arg(&prog)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let original = motions(&run_rs274(&bin, &prog, None, None).unwrap());
    let comp = motions(&run_rs274(&bin, &out, None, None).unwrap());
    // a constant correction splits nothing (with no segment limit): same calls, X shifted
    assert_eq!(original.len(), comp.len());
    for (a, b) in original.iter().zip(&comp).skip(1) {
        assert!(((b.end[0] - a.end[0]) + 0.02).abs() < 2e-4, "{a:?} / {b:?}");
        assert!((b.end[1] - a.end[1]).abs() < 2e-4 && (b.end[2] - a.end[2]).abs() < 2e-4);
    }
}

#[test]
fn missing_rs274_is_a_usage_error_that_says_what_to_install() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    let prog = dir.path().join("p.ngc");
    std::fs::write(&prog, "G0 X1\nM2\n").unwrap();
    let out = dir.path().join("o.ngc");
    let run = |extra: &[&str], path: &str| {
        mtec()
            .env("PATH", path)
            .args(["compensate", "gcode", "--model"])
            .arg(&model)
            .args(["--flatten-with", "rs274"])
            .args(extra)
            .arg(&prog)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap()
    };
    let o = run(&[], dir.path().to_str().unwrap());
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("linuxcnc-uspace"), "{}", text(&o));
    let missing = dir.path().join("no-rs274");
    let o = run(&["--rs274", missing.to_str().unwrap()], "/usr/bin:/bin");
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("linuxcnc-uspace"), "{}", text(&o));
    assert!(!out.exists());
    // a tool table that cannot be read is a usage error (exit 2), with or without flattening
    let o = mtec()
        .args(["compensate", "gcode", "--model"])
        .arg(&model)
        .args(["--tool-table", "t.tbl"])
        .arg(&prog)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}

#[test]
fn help_says_what_flattening_writes_and_refuses() {
    let o = mtec()
        .args(["compensate", "gcode", "--help"])
        .output()
        .unwrap();
    let h = text(&o);
    for words in [
        "--flatten-with",
        "LinuxCNC-only",
        "cutter radius compensation and\ntool lengths are baked in",
        "probing (G38.x)",
        "spindle-synchronised motion",
        "linuxcnc-uspace",
    ] {
        assert!(h.contains(words), "'{words}' missing from --help:\n{h}");
    }
}

#[test]
fn block_delete_switch_reaches_rs274() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bd.ngc");
    std::fs::write(&p, "G21 G90\nG0 X0 Y0 Z1\n/G0 X5\nG0 Y5\nM2\n").unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    let mut counts = Vec::new();
    for bd in ["off", "on"] {
        let out = dir.path().join(format!("bd-{bd}.ngc"));
        let o = mtec()
            .args(["compensate", "gcode", "--model"])
            .arg(&model)
            .args(["--flatten-with", "rs274", "--block-delete", bd])
            .arg(&p)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", text(&o));
        counts.push(motions(&run_rs274(&bin, &out, None, None).unwrap()).len());
    }
    assert_eq!(counts, [3, 2], "block delete on skips the '/' line");
}

#[test]
fn model_is_evaluated_at_machine_positions_with_the_var_files_work_offsets() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("poly.json");
    // e_x = 1 um per mm of machine X
    std::fs::write(
        &model,
        r#"{"format": "mtec.poly-model/1", "terms": [{"powers": [1,0,0], "coef_um": [1.0, 0.0, 0.0]}]}"#,
    )
    .unwrap();
    let prog = dir.path().join("p.ngc");
    std::fs::write(&prog, "G21 G90 G54\nG0 X0 Y0 Z5\nM2\n").unwrap();
    // offsets.var: G54 X = 3 (inch, as rs274 reads it) = 76.2 mm
    let var = data_dir().join("offsets.var");
    let mut first_x = Vec::new();
    for with_var in [false, true] {
        let out = dir.path().join(format!("o-{with_var}.ngc"));
        let mut c = mtec();
        c.args(["compensate", "gcode", "--model"])
            .arg(&model)
            .args(["--flatten-with", "rs274", "--machine-units", "inch"]);
        if with_var {
            c.arg("--var-file").arg(&var);
        }
        let o = c.arg(&prog).arg("-o").arg(&out).output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", text(&o));
        let v = if with_var { Some(var.as_path()) } else { None };
        let m = motions(&run_rs274(&bin, &out, None, v).unwrap());
        first_x.push(m[0].end[0]);
    }
    // machine X 0: no correction; machine X 76.2: p + 0.001 p = 76.2, p = 76.1239
    assert!(first_x[0].abs() < 1e-9, "{first_x:?}");
    assert!((first_x[1] - 76.2 / 1.001).abs() < 2e-4, "{first_x:?}");
}

/// A program that reads a work offset, or asks whether the machine is metric, flattens only
/// on an inch machine (with its own parameter file for the offset): the one case where
/// stand-alone rs274 reads the value the machine reads.
#[test]
fn a_work_offset_or_the_machine_s_units_flatten_only_as_an_inch_machine_reads_them() {
    let Some(_) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    let var = data_dir().join("offsets.var");
    for (name, body, refusal) in [
        (
            "offset.ngc",
            "G21 G90 G54\nG0 X[#5221] Y0 Z5\nM2\n",
            "offset.ngc:2:6: #5221 reads or sets",
        ),
        // 0 in rs274, 1 on a metric machine: the inch branch would be flattened
        (
            "metric.ngc",
            "G21 G90\no1 if [#<_metric_machine>]\nG0 X1 Y0 Z0\no1 else\nG0 X25.4 Y0 Z0\no1 endif\nM2\n",
            "metric.ngc:2:8: #<_metric_machine> is 1 on this metric machine",
        ),
    ] {
        let prog = dir.path().join(name);
        std::fs::write(&prog, body).unwrap();
        for (units, code) in [("mm", 2), ("inch", 0)] {
            let o = mtec()
                .args(["compensate", "gcode", "--model"])
                .arg(&model)
                .args(["--flatten-with", "rs274", "--machine-units", units, "--var-file"])
                .arg(&var)
                .arg(&prog)
                .arg("-o")
                .arg(dir.path().join(format!("o-{units}.ngc")))
                .output()
                .unwrap();
            assert_eq!(o.status.code(), Some(code), "{name} {units}: {}", text(&o));
            if code == 2 {
                assert!(text(&o).contains(refusal), "{}", text(&o));
            }
        }
    }
}

/// Stand-alone rs274 given no tool table uses a built-in one (T1 = 0.511 in): flattening baked
/// those lengths into every coordinate after a G43 (found 2026-11-27 on a FreeCAD drilling
/// program: 72 mm in Z). rs274 now gets the user's table, the lengths of `--offsets`, or an
/// empty table; a G43 that takes the tool the spindle holds at start is refused.
#[test]
fn tool_lengths_come_from_the_user_only() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let model = write("zero.json", ZERO_MODEL);
    let run = |program: &Path, extra: &[&Path], flag: &str| {
        let given: Vec<(&str, &Path)> = extra.iter().map(|p| (flag, *p)).collect();
        flatten_zero(&bin, dir.path(), &model, program, &given)
    };
    let drill = write(
        "drill.ngc",
        "G21 G90\nT1 M6\nG43 H1\nG0 X1 Y1 Z8\nG1 Z-2 F100\nM2\n",
    );
    // no table, no lengths: refused at the G43 that uses the unknown length, saying what to
    // give (rs274 gets tools 1-999 with an absurd length, so that a tool change alone passes)
    let (code, msg, out) = run(&drill, &[], "");
    assert_eq!(code, Some(2), "{msg}");
    assert!(
        msg.contains("drill.ngc:3:1:") && msg.contains("a tool whose length is not known"),
        "{msg}"
    );
    assert!(
        msg.contains("--tool-table") && msg.contains("[tool_lengths_mm]"),
        "{msg}"
    );
    assert!(out.is_none());
    // a tool change without G43 needs no length: flattened (found 2026-11-28 on public
    // programs, refused before with "Requested tool 1 not found")
    let plain = write(
        "plain-t1.ngc",
        "G21 G90\nT1 M6\nS5000 M3\nG0 X1 Y1 Z5\nG1 Z0 F100\nM2\n",
    );
    let (code, msg, out) = run(&plain, &[], "");
    assert_eq!(code, Some(0), "{msg}");
    assert!(out.is_some_and(|o| o.contains("T1") && !o.contains("G43")));
    // the lengths of --offsets reach rs274: Z8 with an 85.25 mm tool is Z93.25 without G43
    let offsets = write(
        "offsets.toml",
        "format = \"mtec.gcode-offsets/1\"\nactive = \"G54\"\n[work_offsets_mm]\nG54 = [0.0, 0.0, 0.0]\n[tool_lengths_mm]\n1 = 85.25\n",
    );
    let (code, msg, out) = run(&drill, &[&offsets], "--offsets");
    assert_eq!(code, Some(0), "{msg}");
    let flat = out.unwrap();
    let rapid = flat.lines().find(|l| l.starts_with("G0 X1.0")).unwrap();
    assert_eq!(rapid, "G0 X1.0 Y1.0 Z93.25", "{flat}");
    assert!(
        flat.lines().any(|l| l == "G1 X1.0 Y1.0 Z83.25 F100.0"),
        "{flat}"
    );
    // G41/G42 take the radius from the table: a table made of --offsets lengths has none
    let comp = write(
        "comp.ngc",
        "G21 G90\nT1 M6\nG0 X-10 Y-10 Z5\nG1 Z-1 F100\nG41 D1 X0 Y0\nY20\nG40 X30\nM2\n",
    );
    let (code, msg, _) = run(&comp, &[&offsets], "--offsets");
    assert_eq!(code, Some(2), "{msg}");
    assert!(
        msg.contains("comp.ngc:5:1:") && msg.contains("--tool-table"),
        "{msg}"
    );
    // G41.1 carries its diameter: flattened
    let dynamic = write(
        "dynamic.ngc",
        "G21 G90\nG0 X-10 Y-10 Z5\nG1 Z-1 F100\nG41.1 D6 X0 Y0\nY20\nG40 X30\nM2\n",
    );
    let (code, msg, _) = run(&dynamic, &[&offsets], "--offsets");
    assert_eq!(code, Some(0), "{msg}");
    // G43 without H before any tool change, and M6 without T: the spindle's tool at start
    let table = data_dir().join("mill.tbl");
    for (name, body, at) in [
        (
            "bare.ngc",
            "G21 G90\nG0 X1 Y1 Z8\ng 43 (tool in the spindle)\nG0 Z5\nT1 M6\nG43\nM2\n",
            "bare.ngc:3:1:",
        ),
        (
            "m6.ngc",
            "G21 G90\nM6\nG43\nG0 X1 Y1 Z5\nM2\n",
            "m6.ngc:3:1:",
        ),
    ] {
        let p = write(name, body);
        let (code, msg, out) = run(&p, &[&table], "--tool-table");
        assert_eq!(code, Some(2), "{name}: {msg}");
        assert!(
            msg.contains(at) && msg.contains("depends on the tool in the spindle"),
            "{name}: {msg}"
        );
        assert!(out.is_none(), "{name}");
    }
    // after a T… M6 a bare G43 is that tool's: flattened to the same motion
    let after = write(
        "after.ngc",
        "G21 G90\nG49\nT1 M6\nG43\nG0 X1 Y1 Z5\nG1 Z-1 F100\nM2\n",
    );
    check(&bin, &after, Some(&table), None, &[], &Expect::Same);
    // M61 Q2 then a bare G43: LinuxCNC takes tool 2's length (checked in its simulation:
    // linuxcnc_sim.rs), stand-alone rs274 tool 1's, which flattening would have baked in
    let two = write("two.tbl", "T1 P1 Z0.5 D0.25\nT2 P2 Z1.5 D0.25\n");
    let m61 = write(
        "m61.ngc",
        "G21 G90\nT1 M6\nG43\nG0 X1 Y1 Z5\nM61 Q2\nG43 (bare)\nG0 Z4\nM2\n",
    );
    let (code, msg, out) = run(&m61, &[&two], "--tool-table");
    assert_eq!(code, Some(2), "{msg}");
    assert!(
        msg.contains("m61.ngc:6:1:") && msg.contains("G43 without H after an M61"),
        "{msg}"
    );
    assert!(out.is_none());
    // G43 H2 names the tool: both take its length, flattened to the same motion
    let named = write(
        "m61h.ngc",
        "G21 G90\nT1 M6\nG43\nG0 X1 Y1 Z5\nM61 Q2\nG43 H2\nG0 Z4\nM2\n",
    );
    check(&bin, &named, Some(&two), None, &[], &Expect::Same);
}

/// Stand-alone rs274 given no parameter file starts in G54 with a zero table, and flattening
/// wrote that G54 into the output: a program meant for the machine's active G55 (as
/// `--offsets` said) was cut in G54 (found 2026-11-27). rs274 now reads `--var-file`, or a
/// parameter file made of `--offsets`, or starts in a system that stands for the machine's
/// unknown one and is never written.
#[test]
fn the_work_system_at_start_is_the_users_or_left_unnamed() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let model = write("zero.json", ZERO_MODEL);
    let run = |program: &Path, offsets: Option<&Path>| {
        let given: Vec<(&str, &Path)> = offsets.map(|o| ("--offsets", o)).into_iter().collect();
        flatten_zero(&bin, dir.path(), &model, program, &given)
    };
    let before_first_move = |flat: &str| -> Vec<String> {
        flat.lines()
            .take_while(|l| !l.starts_with("G0 ") && !l.starts_with("G1 "))
            .map(str::to_string)
            .collect()
    };
    let plain = write(
        "plain.ngc",
        "G21 G90\nG0 X10 Y10 Z5\nG1 Z-1 F100\nX20\nM2\n",
    );
    let g55 = write(
        "g55.toml",
        "format = \"mtec.gcode-offsets/1\"\nactive = \"G55\"\n[work_offsets_mm]\nG54 = [250.0, 120.0, -300.0]\nG55 = [-100.0, 50.0, -250.0]\n",
    );
    let (code, msg, out) = run(&plain, Some(&g55));
    assert_eq!(code, Some(0), "{msg}");
    let flat = out.unwrap();
    let head = before_first_move(&flat);
    assert!(head.iter().any(|l| l == "G55"), "{flat}");
    assert!(!head.iter().any(|l| l == "G54"), "{flat}");
    assert!(flat.contains("G0 X10.0 Y10.0 Z5.0"), "{flat}");
    // nothing given: the output names no system before the program does
    let (code, msg, out) = run(&plain, None);
    assert_eq!(code, Some(0), "{msg}");
    let flat = out.unwrap();
    assert!(
        !before_first_move(&flat).iter().any(|l| l.starts_with("G5")),
        "{flat}"
    );
    // a program that selects G55 needs its offset, as without flattening
    let sel = write("sel.ngc", "G21 G90 G55\nG0 X10 Y10 Z5\nM2\n");
    let (code, msg, _) = run(&sel, None);
    assert_eq!(code, Some(2), "{msg}");
    assert!(
        msg.contains("G55 is selected but its offset is not known"),
        "{msg}"
    );
    // G59.3 stands for the unknown start system: a program naming it is refused
    let last = write("last.ngc", "G21 G90\nG0 X1 Y1 Z1\nG59.3\nG0 X2\nM2\n");
    let (code, msg, _) = run(&last, None);
    assert_eq!(code, Some(2), "{msg}");
    assert!(msg.contains("last.ngc:3:1:"), "{msg}");
}

/// LinuxCNC keeps a G92 offset between programs; stand-alone rs274 starts without one. A
/// program that cancels it (G92.1 in its preamble: 44 of LinuxCNC's own example programs)
/// lost that cancel when flattened, and a machine still holding an offset ran every move
/// beside the part (found 2026-11-27).
#[test]
fn the_g92_offset_linuxcnc_keeps_is_cancelled_as_the_original_does_or_refused() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let preamble = write(
        "preamble.ngc",
        "G17 G21 G40 G49 G80 G90 G92.1\nG0 X1 Y1 Z1\nG92 X0\nG1 X2 F100\nM2\n",
    );
    check(&bin, &preamble, None, None, &[], &Expect::Same);
    let flat = flatten_text(&bin, &preamble);
    let first = flat.lines().find(|l| !l.starts_with('(')).unwrap();
    assert!(first.ends_with(" G92.1"), "{flat}");
    for (name, body, at) in [
        (
            "late.ngc",
            "G21 G90\nG0 X1 Y1 Z1\nG92.1\nG0 X3\nM2\n",
            "late.ngc:3:1:",
        ),
        (
            "g52.ngc",
            "G21 G90\nG0 X1 Y1 Z1\nG52 X5\nG0 X3\nM2\n",
            "g52.ngc:3:1:",
        ),
    ] {
        let p = write(name, body);
        check(&bin, &p, None, None, &[], &Expect::Refused(at));
    }
    // a G92 offset in the controller's parameter file: rs274 reads it, flattening folds it
    // into the coordinates and cancels it on the machine first (inches, as rs274 reads it)
    let var = write(
        "g92.var",
        "5210\t1\n5211\t1.0\n5212\t0\n5213\t0\n5220\t1\n5221\t0\n5222\t0\n5223\t0\n",
    );
    let plain = write("plain.ngc", "G21 G90\nG0 X1 Y1 Z1\nG1 X3 F100\nM2\n");
    check(&bin, &plain, None, Some(&var), &[], &Expect::Same);
}

#[test]
fn a_stop_on_a_block_written_on_several_lines_names_the_line_rs274_stopped_at() {
    // rs274 echoes the block it stops at, not its line: when the text repeats, a second run on
    // the program with every line numbered by its N word names the line
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    for (body, at, words) in [
        // the second `G1 X20` runs with a zero feed
        (
            "G21 G90\nG1 X10 F100\nG1 X20\nF0\nG1 X20\nM2\n",
            ":5:1:",
            "zero feed rate",
        ),
        // the first arc starts where the machine stands: from elsewhere its radii differ
        (
            "G21 G90 G17\n  G2 X10 Y0 I5 J0 F100\nG0 X0 Y0\nG2 X10 Y0 I5 J0 F100\nM2\n",
            ":2:3:",
            "started at another position",
        ),
        // a tape mark after a comment line is a bad block; the closing one is never read
        (
            "(job)\n%\nG21 G90\nG1 X10 F100\nM2\n%\n",
            ":2:1:",
            "Bad character '%'",
        ),
        // N words are replaced (here one repeated), a block delete slash stays
        (
            "G21 G90\nN10 G1 X10 F100\nN20 G1 X20\n/N30 F0\nN20 G1 X20\nM2\n",
            ":5:1:",
            "zero feed rate",
        ),
    ] {
        let p = dir.path().join("repeat.ngc");
        std::fs::write(&p, body).unwrap();
        let (code, msg, _) = flatten_zero(&bin, dir.path(), &model, &p, &[]);
        assert_eq!(code, Some(2), "{msg}");
        assert!(msg.contains(&format!("repeat.ngc{at}")), "{at}: {msg}");
        assert!(msg.contains(words), "{msg}");
    }
}

/// A subroutine file run on its own ends without M2: rs274 stops at the end of the file, and
/// the refusal names the last line (it had no location: 7 of LinuxCNC's 332 programs); a
/// missing O-word is refused at its call. A
/// `(PRINT, …)` comment, whose text rs274 writes between its calls, is flattened (it refused).
#[test]
fn a_file_without_an_end_is_located_and_print_comments_flatten() {
    let Some(bin) = rs274() else { return };
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("zero.json");
    std::fs::write(&model, ZERO_MODEL).unwrap();
    let sub = dir.path().join("sub.ngc");
    std::fs::write(&sub, "o<sub> sub\nG1 X1 F100\no<sub> endsub\n\n").unwrap();
    let (code, msg, _) = flatten_zero(&bin, dir.path(), &model, &sub, &[]);
    assert_eq!(code, Some(2), "{msg}");
    assert!(msg.contains("sub.ngc:3:1:"), "{msg}");
    assert!(msg.contains("add M2"), "{msg}");
    // a call of an O-word rs274 cannot find is refused at the call, not at the line it read last
    let call = dir.path().join("call.ngc");
    std::fs::write(&call, "G21\no<nothere> call\nM2\n").unwrap();
    let (code, msg, _) = flatten_zero(&bin, dir.path(), &model, &call, &[]);
    assert_eq!(code, Some(2), "{msg}");
    assert!(msg.contains("call.ngc:2:1:"), "{msg}");
    let print = dir.path().join("print.ngc");
    std::fs::write(
        &print,
        "G21 G90\n(PRINT, hello)\nG0 X10 Y10 Z5\nG1 Z-1 F100\nM2\n",
    )
    .unwrap();
    let flat = flatten_text(&bin, &print);
    assert!(flat.contains("G1 X10.0 Y10.0 Z-1.0 F100.0"), "{flat}");
    assert!(!flat.contains("hello"), "{flat}");
}
