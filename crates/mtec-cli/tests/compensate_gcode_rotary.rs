//! `mtec compensate gcode` on five-axis programs (issue 16 item 5), checked with LinuxCNC's own
//! interpreter: `rs274 -g` reads the original and the compensated program, and the tool tip
//! reached along rs274's canonical moves is compared with the programmed one.
//!
//! - Where the tool should go: the ideal chain (`VolumetricModel::tool_frame(q, false)`) along
//!   the joint path of the original's canonical moves (LinuxCNC interpolates every joint
//!   linearly in a move, trivkins).
//! - Where it goes: the chain with the model's errors (`tool_frame(q, true)`, the exact HTM
//!   product) along the joint path of the compensated program's canonical moves.
//!
//! Every sample of every compensated feed move must lie within the bound of the nominal tool-tip
//! path of the original move it follows, pieces follow their move in order and end where it
//! ends (same rotary angles, tool tip within the bound); each rapid's end is reached; and the
//! pieces of a move take as long as the move (durations from rs274's own feed rates, G93 already
//! turned into units per minute, and LinuxCNC's rule for a move's length: XYZ if X, Y or Z
//! moves, else the rotary one). The bound: `--tolerance-um` plus rs274's 4-decimal printout of
//! both programs' X Y Z (√3 · 0.05 µm each; √3 · 1.27 µm in inch programs); rotary words are written with 4 decimals at most, so
//! rs274 prints them exactly. The same check on the uncompensated program must fail by far (the
//! check can see an error).
//!
//! Without rs274 the tests print a note and pass, unless `CI` is set.

mod support;

use mtec_model::{Axis, Machine, VolumetricModel};
use std::path::{Path, PathBuf};
use support::{mtec, rs274, run_rs274, text};

const TOLERANCE_UM: f64 = 0.5;
/// rs274 prints 4 decimals: half a unit on each of X, Y, Z, in both programs.
const PRINT_UM: f64 = 2.0 * 1.732_050_807_568_877_2 * 0.05;
const BOUND_UM: f64 = TOLERANCE_UM + PRINT_UM;
/// The same for a G20 program, whose listing is in inches (half of 0.0001 in is 1.27 µm).
const BOUND_INCH_UM: f64 = TOLERANCE_UM + 2.0 * 1.732_050_807_568_877_2 * 1.27;
/// Sample spacing of the nominal path (mm of X Y Z, deg of the rotary axes): its chords are
/// within ~0.003 µm of the curve the tool tip draws.
const NOMINAL_STEP: (f64, f64) = (0.02, 0.01);
/// Sample spacing along the compensated moves.
const ACTUAL_STEP: (f64, f64) = (0.05, 0.02);

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/rotary")
}

/// The true machine of a `mtec.kinematic-model/1` file.
fn true_machine(model: &Path) -> VolumetricModel {
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(model).unwrap()).unwrap();
    let spec = serde_json::from_value(doc["machine"].clone()).unwrap();
    let errors = serde_json::from_value(doc["errors"].clone()).unwrap();
    VolumetricModel::new(&Machine::from_spec(spec).unwrap(), &errors)
}

/// One canonical straight move: joints X Y Z (mm) A B C (deg) at its ends, minutes it takes.
#[derive(Debug, Clone, Copy)]
struct Move {
    line: usize,
    feed: bool,
    from: [f64; 6],
    to: [f64; 6],
    minutes: f64,
}

fn numbers(args: &str) -> Vec<f64> {
    args.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect()
}

/// The straight moves of rs274's listing, from machine 0 (where rs274 starts). X Y Z in mm
/// (inch listings scaled), angles in degrees. Offsets must be zero here (none of these programs
/// sets one); an arc or probe move fails the test.
fn moves(canon: &str) -> Vec<Move> {
    let (mut scale, mut feed) = (1.0, 0.0);
    let mut pos = [0.0; 6];
    let mut out = Vec::new();
    for (i, line) in canon.lines().enumerate() {
        let Some(open) = line.find('(') else { continue };
        let name = line[..open].split_whitespace().last().unwrap_or("");
        let args = &line[open + 1..line.rfind(')').unwrap_or(line.len())];
        let v = numbers(args);
        match name {
            "USE_LENGTH_UNITS" => scale = if args.contains("INCHES") { 25.4 } else { 1.0 },
            "SET_G5X_OFFSET" | "SET_G92_OFFSET" | "USE_TOOL_LENGTH_OFFSET" => {
                let skip = usize::from(name == "SET_G5X_OFFSET");
                assert!(v[skip..].iter().all(|x| *x == 0.0), "offset: {line}")
            }
            "SET_FEED_RATE" => feed = v[0],
            "SET_FEED_MODE" => assert_eq!(v[1], 0.0, "feed per revolution: {line}"),
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" => {
                let to: [f64; 6] = std::array::from_fn(|k| if k < 3 { v[k] * scale } else { v[k] });
                let d = |r: std::ops::Range<usize>, s: f64| {
                    r.map(|k| ((to[k] - pos[k]) / s).powi(2))
                        .sum::<f64>()
                        .sqrt()
                };
                // LinuxCNC's length of a move (program units): XYZ if they move, else ABC
                let (l_xyz, l_rot) = (d(0..3, scale), d(3..6, 1.0));
                let length = if l_xyz > 1e-12 { l_xyz } else { l_rot };
                let rapid = name == "STRAIGHT_TRAVERSE";
                out.push(Move {
                    line: i + 1,
                    feed: !rapid,
                    from: pos,
                    to,
                    minutes: if rapid { 0.0 } else { length / feed },
                });
                pos = to;
            }
            "ARC_FEED" | "STRAIGHT_PROBE" => panic!("not expected here: {line}"),
            _ => {}
        }
    }
    out
}

/// Tool tip (mm, workpiece frame) at joints `j`: ideal chain or with the errors.
fn tip(vm: &VolumetricModel, j: &[f64; 6], actual: bool) -> [f64; 3] {
    let m = vm.machine();
    let mut q = vec![0.0; m.axes.len()];
    for (k, a) in Axis::ALL.iter().enumerate() {
        match m.axis_index(*a) {
            Some(i) => q[i] = j[k],
            None => assert_eq!(j[k], 0.0, "axis {a:?} moves but the machine has none"),
        }
    }
    let p = vm.tool_frame(&q, actual).p;
    [p.x, p.y, p.z]
}

fn lerp(a: &[f64; 6], b: &[f64; 6], s: f64) -> [f64; 6] {
    std::array::from_fn(|k| a[k] + (b[k] - a[k]) * s)
}

fn samples(m: &Move, step: (f64, f64)) -> usize {
    let d = |r: std::ops::Range<usize>| {
        r.map(|k| (m.to[k] - m.from[k]).abs())
            .fold(0.0f64, f64::max)
    };
    ((d(0..3) / step.0).max(d(3..6) / step.1).ceil() as usize).max(20)
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn segment_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    let t = if l2 == 0.0 {
        0.0
    } else {
        ((ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2]) / l2).clamp(0.0, 1.0)
    };
    dist(p, [a[0] + ab[0] * t, a[1] + ab[1] * t, a[2] + ab[2] * t])
}

/// What the walk found: worst distance (µm) of the actual tool tip from the nominal path and
/// at the end of a move, worst relative change of a move's duration.
#[derive(Debug)]
struct Walk {
    worst_um: f64,
    worst_end_um: f64,
    worst_time: f64,
    feed_moves: usize,
    pieces: usize,
}

/// Walks the nominal moves in order, each followed by the actual moves up to the one that ends
/// where it ends (same angles, tool tip within `reach_um`). Panics (naming rs274's listing
/// lines) when the actual program skips, adds or misses a move; returns the distances otherwise.
fn walk(
    vm: &VolumetricModel,
    nominal: &[Move],
    actual: &[Move],
    bound_um: f64,
    reach_um: f64,
) -> Walk {
    let mut w = Walk {
        worst_um: 0.0,
        worst_end_um: 0.0,
        worst_time: 0.0,
        feed_moves: 0,
        pieces: 0,
    };
    let mut k = 0;
    for n in nominal {
        let end = tip(vm, &n.to, false);
        if !n.feed {
            let a = actual
                .get(k)
                .unwrap_or_else(|| panic!("rapid {} missing", n.line));
            assert!(
                !a.feed,
                "canonical line {}: a feed move for a rapid",
                a.line
            );
            assert!(n.to[3..] == a.to[3..], "rapid {}: angles differ", a.line);
            let off = dist(tip(vm, &a.to, true), end) * 1e3;
            assert!(off <= reach_um, "rapid {}: ends {off:.3} um off", a.line);
            w.worst_end_um = w.worst_end_um.max(off);
            k += 1;
            continue;
        }
        w.feed_moves += 1;
        let ns = samples(n, NOMINAL_STEP);
        let path: Vec<[f64; 3]> = (0..=ns)
            .map(|j| tip(vm, &lerp(&n.from, &n.to, j as f64 / ns as f64), false))
            .collect();
        let nearest = |p: [f64; 3], lo: usize, hi: usize| -> (f64, usize) {
            (lo..hi)
                .map(|j| (segment_distance(p, path[j], path[j + 1]), j))
                .fold((f64::INFINITY, 0), |b, c| if c.0 < b.0 { c } else { b })
        };
        let mut cursor: usize = 0;
        let mut minutes = 0.0;
        loop {
            let a = actual
                .get(k)
                .unwrap_or_else(|| panic!("move at canonical line {}: never reached", n.line));
            assert!(
                a.feed,
                "canonical line {}: a rapid inside a feed move",
                a.line
            );
            let m = samples(a, ACTUAL_STEP);
            for j in 0..=m {
                let p = tip(vm, &lerp(&a.from, &a.to, j as f64 / m as f64), true);
                // the path ahead of the last nearest point first; all of it if that is far
                let (mut d, mut at) =
                    nearest(p, cursor.saturating_sub(50), (cursor + 2000).min(ns));
                if d * 1e3 > bound_um {
                    (d, at) = nearest(p, 0, ns);
                }
                cursor = at;
                w.worst_um = w.worst_um.max(d * 1e3);
            }
            minutes += a.minutes;
            w.pieces += 1;
            k += 1;
            let off = dist(tip(vm, &a.to, true), end) * 1e3;
            if a.to[3..] == n.to[3..] && off <= reach_um {
                w.worst_end_um = w.worst_end_um.max(off);
                break;
            }
        }
        if n.minutes > 0.0 {
            w.worst_time = w.worst_time.max((minutes / n.minutes - 1.0).abs());
        }
    }
    assert_eq!(k, actual.len(), "moves after the program's last one");
    w
}

fn compensate(model: &Path, program: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    mtec(
        &[
            &[
                "compensate",
                "gcode",
                "--model",
                model.to_str().unwrap(),
                program.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--start-position-mm",
                "0,0,0",
                "--start-rotary-deg",
                "0,0,0",
            ][..],
            extra,
        ]
        .concat(),
    )
}

/// Compensates `program` with `model`, runs rs274 on both, walks the compensated and the
/// uncompensated program against the nominal path. Returns (compensated, uncompensated).
fn check(bin: &Path, model: &str, program: &str) -> (Walk, Walk) {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("in.ngc");
    std::fs::write(&src, program).unwrap();
    check_file(bin, model, &src, &[])
}

/// [`check`] of a program file, with more options for mtec.
fn check_file(bin: &Path, model: &str, src: &Path, extra: &[&str]) -> (Walk, Walk) {
    let dir = tempfile::tempdir().unwrap();
    let model = data().join(model);
    let out = dir.path().join("out.ngc");
    let o = compensate(&model, src, &out, extra);
    assert!(o.status.success(), "{}", text(&o));
    let written = std::fs::read_to_string(&out).unwrap();
    // rotary words at most 4 decimals: rs274 prints them as written
    for w in written
        .lines()
        .filter(|l| !l.starts_with('('))
        .flat_map(|l| l.split_whitespace())
        .filter(|w| w.starts_with(['A', 'B', 'C']))
    {
        assert!(
            w.split('.').nth(1).is_none_or(|d| d.len() <= 4),
            "rotary word {w} has more than 4 decimals"
        );
    }
    let listing = run_rs274(bin, src).unwrap();
    let bound = if listing.contains("CANON_UNITS_INCHES") {
        BOUND_INCH_UM
    } else {
        BOUND_UM
    };
    let nominal = moves(&listing);
    let compensated = moves(
        &run_rs274(bin, &out)
            .unwrap_or_else(|e| panic!("rs274 refuses the output: {e}\n{written}")),
    );
    let vm = true_machine(&model);
    let comp = walk(&vm, &nominal, &compensated, bound, bound);
    // the original itself, on the machine with errors: one move per move
    let none = walk(&vm, &nominal, &nominal, bound, f64::INFINITY);
    (comp, none)
}

const TABLE_PROGRAM: &str = "(five-axis, table tilts with A and turns with C)
G21 G90 G94 G17
G0 X10 Y0 Z-100 A0 C0
G1 Z-130 F400
G1 X60 C120 F800
G1 A-45 C200
G1 X20 Y30 Z-120 A-20 C-30
G1 C40 F3000
G93 G1 X40 Y-10 C90 F2
G1 A-30 F4
G94 G91 G1 X-10 Y5 A10 C-25.5 F600
G90 G0 Z0
M2
";

const HEAD_PROGRAM: &str = "(five-axis, the head turns with C and tilts with B)
G21 G90 G94
G0 X0 Y0 Z-50 B0 C0
G1 X50 B30 F500
G1 C90
G1 Y40 B-20 C180
G93 G1 X-30 C270 F1.5
G94 G1 X0 Y0 Z-80 B15 F1200
G0 Z0 B0
M2
";

#[test]
fn five_axis_programs_follow_the_programmed_tool_tip_path_in_rs274() {
    let Some(bin) = rs274() else { return };
    for (model, program) in [
        ("table-tilting.json", TABLE_PROGRAM),
        ("head.json", HEAD_PROGRAM),
    ] {
        let (comp, none) = check(&bin, model, program);
        eprintln!(
            "{model}: {} feed moves in {} pieces; tool tip off the path by {:.3} um compensated \
             (bound {BOUND_UM:.3}), {:.1} um uncompensated; durations within {:.4} %",
            comp.feed_moves,
            comp.pieces,
            comp.worst_um,
            none.worst_um,
            comp.worst_time * 100.0
        );
        assert!(
            comp.worst_um <= BOUND_UM && comp.worst_end_um <= BOUND_UM,
            "{model}: {comp:?}"
        );
        // the rewriter keeps F while a piece takes within 1 % of its share (FEED_TOLERANCE)
        assert!(comp.worst_time <= 0.01, "{model}: {comp:?}");
        // long rotary moves were split
        assert!(comp.pieces > 2 * comp.feed_moves, "{model}: {comp:?}");
        // the check sees the machine's error when nothing is compensated
        assert!(none.worst_um > 20.0 * BOUND_UM, "{model}: {none:?}");
    }
}

#[test]
fn start_angles_and_check_step_are_options_with_their_reasons() {
    let dir = tempfile::tempdir().unwrap();
    let model = data().join("table-tilting.json");
    let src = dir.path().join("in.ngc");
    // the first feed move turns C from wherever the table stands
    std::fs::write(&src, "G21 G90 G94\nG0 X10 Y0 Z-100\nG1 X20 C30 F500\nM2\n").unwrap();
    let out = dir.path().join("out.ngc");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "compensate",
            "gcode",
            "--model",
            model.to_str().unwrap(),
            src.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--start-position-mm",
            "0,0,0",
        ];
        args.extend_from_slice(extra);
        mtec(&args)
    };
    // unknown start angle of A: refused at the move, with line and column
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("in.ngc:3:"), "{}", text(&o));
    assert!(
        text(&o).contains("position of A is not known"),
        "{}",
        text(&o)
    );
    // known: compensated
    let o = run(&["--start-rotary-deg", "0,0,0"]);
    assert!(o.status.success(), "{}", text(&o));
    // malformed option values are usage errors naming the option
    for (args, want) in [
        (&["--start-rotary-deg", "0,0"][..], "--start-rotary-deg"),
        (&["--start-rotary-deg", "0,x,0"][..], "--start-rotary-deg"),
        (
            &["--start-rotary-deg", "0,0,0", "--check-step-deg", "0"][..],
            "--check-step-deg",
        ),
    ] {
        let o = run(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o));
        assert!(text(&o).contains(want), "{args:?}: {}", text(&o));
    }
    // the help teaches both
    let help = text(&mtec(&["compensate", "gcode", "--help"]));
    for want in ["--start-rotary-deg", "--check-step-deg", "G93", "WCAYFXZT"] {
        assert!(help.contains(want), "help lacks {want}");
    }
}

/// `../shared/data/gcode/linuxcnc` beside the repository (or a worktree's main checkout), or
/// `$MTEC_SHARED_DIR/data/gcode/linuxcnc`.
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

/// LinuxCNC's `daisy.ngc` (subroutines, parameters, G20, G93 moves of X Y Z A) flattened by
/// rs274 and compensated with a fourth-axis model: the original as rs274 runs it is the nominal.
#[test]
fn real_fourth_axis_program_daisy_is_flattened_and_compensated() {
    let Some(bin) = rs274() else { return };
    let Some(dir) = real_programs_dir() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "the real programs (../shared/data/gcode/linuxcnc) are required in CI"
        );
        return;
    };
    // an inch program: rs274 prints 0.0001 in
    let bound = BOUND_INCH_UM;
    let (comp, none) = check_file(
        &bin,
        "fourth-axis.json",
        &dir.join("daisy.ngc"),
        &["--flatten-with", "rs274"],
    );
    eprintln!(
        "daisy: {} feed moves in {} pieces; tool tip off the path by {:.3} um compensated \
         (bound {bound:.3}), {:.1} um uncompensated; durations within {:.4} %",
        comp.feed_moves,
        comp.pieces,
        comp.worst_um,
        none.worst_um,
        comp.worst_time * 100.0
    );
    assert!(
        comp.worst_um <= bound && comp.worst_end_um <= bound,
        "{comp:?}"
    );
    assert!(comp.worst_time <= 0.01, "{comp:?}");
    assert!(none.worst_um > 2.0 * bound, "{none:?}");
}
