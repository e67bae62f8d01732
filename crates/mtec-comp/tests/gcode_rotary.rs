//! G-code with rotary axes (issue 16, item 5): programs with A/C words on a table-tilting
//! `WCAYFXZT` machine are compensated, long rotary moves are split within the tolerance, the
//! feed of split moves keeps each move's duration (G93 and G94), and what cannot be compensated
//! is refused with line and column.
//!
//! The check replays the rewritten program independently of the rewriter: a small reader of
//! the output's words, LinuxCNC's joint interpolation, the exact chain product with the errors
//! (`VolumetricModel::tool_frame`) for where the tool really goes, and the ideal chain along the
//! original program's joint path for where it should go.

use mtec_comp::gcode::{rewrite, RewriteOptions};
use mtec_comp::kinematic::{KinematicFile, KinematicModel};
use mtec_model::{Machine, VolumetricModel};

const MODEL: &str = r#"{"format": "mtec.kinematic-model/1",
 "machine": {"name": "table-tilting five-axis", "chain": "WCAYFXZT",
   "axes": {"X": {"travel": [-400, 400]}, "Y": {"travel": [-300, 300]}, "Z": {"travel": [-400, 100]},
            "A": {"travel": [-120, 120], "centre_mm": [0, 0, -50]}, "C": {"travel": [-720, 720]}},
   "tool_offset_mm": [0, 0, 120], "error_frame": "reference"},
 "errors": {"format": "mtec.errors/1", "elements": {
   "EXX": {"type": "polynomial", "coeffs": [0, 0.01]},
   "EYY": {"type": "polynomial", "coeffs": [2, -0.008]},
   "ECX": {"type": "polynomial", "coeffs": [5, 0.01]},
   "EX0C": {"type": "constant", "value": 12},
   "EY0C": {"type": "constant", "value": -8},
   "EA0C": {"type": "constant", "value": 25},
   "EY0A": {"type": "constant", "value": 15},
   "EZ0A": {"type": "constant", "value": -10},
   "EXC": {"type": "fourier", "a0": 0, "cos": [0, 1.5, 0.8], "sin": [0, 0.9, 0.4]},
   "EYC": {"type": "fourier", "a0": 0, "cos": [0, -1.1, 0.3], "sin": [0, 1.4, -0.5]},
   "EAC": {"type": "fourier", "a0": 0, "cos": [0, 12, 5], "sin": [0, -7, 3]},
   "EBC": {"type": "fourier", "a0": 0, "cos": [0, 8, -4], "sin": [0, 10, 2]},
   "ECC": {"type": "fourier", "a0": 0, "cos": [15, 6], "sin": [-9, 3]},
   "EBA": {"type": "fourier", "a0": 10, "cos": [5], "sin": [3]},
   "EAA": {"type": "fourier", "a0": 20, "cos": [8], "sin": [-6]},
   "EXA": {"type": "polynomial", "coeffs": [1, 0.02]}
 }}}"#;

fn model() -> (KinematicModel, VolumetricModel) {
    let f: KinematicFile = serde_json::from_str(MODEL).unwrap();
    let machine = Machine::from_spec(f.machine.clone()).unwrap();
    let vm = VolumetricModel::new(&machine, &f.errors);
    (KinematicModel::from_file(f, "test").unwrap(), vm)
}

fn run(
    program: &str,
    m: &dyn mtec_comp::ErrorModel,
    opt: &RewriteOptions,
) -> Result<String, String> {
    let mut out = Vec::new();
    rewrite(program.as_bytes(), &mut out, m, opt)
        .map(|_| String::from_utf8(out).unwrap())
        .map_err(|e| e.to_string())
}

/// One straight move of a program as LinuxCNC runs it: joint values at its ends (mm, deg,
/// machine = program in these tests) and its duration (min).
#[derive(Debug, Clone, Copy)]
struct Move {
    feed: bool,
    from: [f64; 5],
    to: [f64; 5],
    minutes: f64,
}

/// Reads the moves of a program of G0/G1 lines in G90/G91, G93/G94, F words, with
/// LinuxCNC's rules for the duration: length = XYZ length if X, Y or Z moves, else the rotary
/// length; G94: length/F; G93: length/max(0.1, length·F).
fn moves(program: &str, start: [f64; 5]) -> Vec<Move> {
    let mut pos = start;
    let (mut absolute, mut inverse, mut feed, mut rapid) = (true, false, 0.0, true);
    let mut out = Vec::new();
    for line in program.lines() {
        let line = line.split('(').next().unwrap().trim().to_ascii_uppercase();
        let mut words: Vec<(char, f64)> = Vec::new();
        let b = line.as_bytes();
        let mut i = 0;
        while i < b.len() {
            let c = b[i] as char;
            if c.is_ascii_alphabetic() {
                let mut j = i + 1;
                while j < b.len() && (b[j] == b'.' || b[j] == b'-' || b[j].is_ascii_digit()) {
                    j += 1;
                }
                words.push((c, line[i + 1..j].parse().unwrap()));
                i = j;
            } else {
                i += 1;
            }
        }
        let mut moved = false;
        let mut to = pos;
        for &(c, v) in &words {
            match (c, v as i64) {
                ('G', 0) => rapid = true,
                ('G', 1) => rapid = false,
                ('G', 90) => absolute = true,
                ('G', 91) => absolute = false,
                ('G', 93) => inverse = true,
                ('G', 94) => inverse = false,
                ('F', _) => feed = v,
                _ => {}
            }
            if let Some(k) = "XYZAC".find(c) {
                to[k] = if absolute { v } else { pos[k] + v };
                moved = true;
            }
        }
        if !moved {
            continue;
        }
        let d = |r: std::ops::Range<usize>| r.map(|k| (to[k] - pos[k]).powi(2)).sum::<f64>().sqrt();
        let (lx, lr) = (d(0..3), d(3..5));
        let length = if lx > 0.0 { lx } else { lr };
        let minutes = if rapid {
            0.0
        } else if inverse {
            length / (length * feed).max(0.1)
        } else {
            length / feed
        };
        out.push(Move {
            feed: !rapid,
            from: pos,
            to,
            minutes,
        });
        pos = to;
    }
    out
}

fn lerp(a: [f64; 5], b: [f64; 5], s: f64) -> [f64; 5] {
    std::array::from_fn(|k| a[k] + (b[k] - a[k]) * s)
}

fn tip(vm: &VolumetricModel, q: [f64; 5], actual: bool) -> nalgebra::Vector3<f64> {
    vm.tool_frame(&q, actual).p
}

/// Largest distance (µm) of the actual tool tip along the rewritten feed moves from the
/// nominal tool-tip path of the original's feed moves, each rewritten move compared with the
/// original move whose span of the nominal path it follows (found by its end point), and the
/// ratio of their durations per original move.
fn replay(original: &str, rewritten: &str, vm: &VolumetricModel, start: [f64; 5]) -> (f64, f64) {
    let nominal: Vec<Move> = moves(original, start);
    let actual: Vec<Move> = moves(rewritten, start);
    // the nominal path, densely: (move index, s, point)
    let mut worst = 0.0f64;
    let mut worst_time = 0.0f64;
    let mut k = 0; // the rewritten move being followed
    for (i, n) in nominal.iter().enumerate() {
        let samples: Vec<nalgebra::Vector3<f64>> = (0..=4000)
            .map(|j| tip(vm, lerp(n.from, n.to, j as f64 / 4000.0), false))
            .collect();
        let end = samples[4000];
        let mut minutes = 0.0;
        // the rewritten moves up to the one that reaches this move's end
        loop {
            let a = actual[k];
            if n.feed {
                for j in 0..=200 {
                    let p = tip(vm, lerp(a.from, a.to, j as f64 / 200.0), true);
                    let d = samples
                        .windows(2)
                        .map(|w| segment_distance(p, w[0], w[1]))
                        .fold(f64::INFINITY, f64::min);
                    worst = worst.max(d * 1e3);
                }
            }
            minutes += a.minutes;
            k += 1;
            let reached = (tip(vm, a.to, true) - end).norm() * 1e3;
            if reached < 1.0 && (a.to[3] - n.to[3]).abs() < 1e-9 && (a.to[4] - n.to[4]).abs() < 1e-9
            {
                assert!(reached <= 0.5, "move {i}: end missed by {reached} um");
                break;
            }
            assert!(k < actual.len(), "move {i}: its end is never reached");
        }
        if n.feed && n.minutes > 0.0 {
            worst_time = worst_time.max((minutes / n.minutes - 1.0).abs());
        }
    }
    (worst, worst_time)
}

fn segment_distance(
    p: nalgebra::Vector3<f64>,
    a: nalgebra::Vector3<f64>,
    b: nalgebra::Vector3<f64>,
) -> f64 {
    let ab = b - a;
    let t = if ab.norm_squared() == 0.0 {
        0.0
    } else {
        ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
    };
    (a + ab * t - p).norm()
}

/// A three-axis model: a constant error.
struct Flat;
impl mtec_comp::ErrorModel for Flat {
    fn error_um(&self, _p: [f64; 3]) -> [f64; 3] {
        [3.0, -2.0, 1.0]
    }
    fn describe(&self) -> String {
        "flat".into()
    }
}

fn options() -> RewriteOptions {
    RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        start_rotary_deg: Some([0.0; 3]),
        ..RewriteOptions::default()
    }
}

const G94_PROGRAM: &str = "G21 G90 G94 G17
G0 X10 Y0 Z-100 A0 C0
G1 Z-130 F400
G1 X60 C120 F800
G1 A-45 C200
G1 X20 Y30 Z-120 A-20 C-30
G1 C40 F3000
G0 Z0
M2
";

#[test]
fn rotary_moves_in_g94_follow_the_nominal_path_and_keep_their_duration() {
    let (m, vm) = model();
    let out = run(G94_PROGRAM, &m, &options()).unwrap();
    let (dev, time) = replay(G94_PROGRAM, &out, &vm, [0.0; 5]);
    eprintln!(
        "{out}\nworst deviation {dev:.3} um, worst duration change {:.3} %",
        time * 100.0
    );
    assert!(dev <= 0.5 + 0.05, "{dev} um");
    assert!(time <= 0.01, "{time}");
    // the long rotary moves were split, the pure rotary one got its own feeds
    assert!(out.lines().count() > 30);
    assert!(out.contains("\nF3000"), "{out}");
}

const G93_PROGRAM: &str = "G21 G90 G93
G0 X0 Y0 Z-120 A0 C0
G1 X40 C90 F2
G1 A-30 F4
G1 C180 F0.5
G1 X10 Y10 F10
G94
M2
";

#[test]
fn inverse_time_moves_keep_their_duration_piece_by_piece() {
    let (m, vm) = model();
    let out = run(G93_PROGRAM, &m, &options()).unwrap();
    let (dev, time) = replay(G93_PROGRAM, &out, &vm, [0.0; 5]);
    eprintln!(
        "{out}\nworst deviation {dev:.3} um, worst duration change {:.3} %",
        time * 100.0
    );
    assert!(dev <= 0.55, "{dev} um");
    assert!(time <= 0.01, "{time}");
}

#[test]
fn incremental_rotary_words_end_exactly_where_the_program_does() {
    let (m, vm) = model();
    let program = "G21 G91 G94\nG0 X0\nG1 X30 Y5 Z-125 A-20.123456 C95.5 F600\nG1 C-30.25\nM2\n";
    let out = run(program, &m, &options()).unwrap();
    let (dev, time) = replay(program, &out, &vm, [0.0; 5]);
    assert!(dev <= 0.55 && time <= 0.01, "{dev} {time}\n{out}");
    // the written increments add up to the programmed ones exactly
    let sum = |l: char| -> f64 {
        out.lines()
            .flat_map(|line| line.split_whitespace())
            .filter(|w| w.starts_with(l))
            .map(|w| w[1..].parse::<f64>().unwrap())
            .sum()
    };
    assert!((sum('A') + 20.123456).abs() < 1e-9, "{}", sum('A'));
    assert!((sum('C') - 65.25).abs() < 1e-9, "{}", sum('C'));
}

#[test]
fn a_zero_model_leaves_a_rotary_program_byte_identical() {
    let f: KinematicFile = serde_json::from_str(MODEL).unwrap();
    let zero = KinematicModel::new(
        &Machine::from_spec(f.machine).unwrap(),
        &mtec_model::ErrorSet::new("zero"),
        "zero",
    )
    .unwrap();
    for p in [G94_PROGRAM, G93_PROGRAM] {
        assert_eq!(run(p, &zero, &options()).unwrap(), p);
    }
}

#[test]
fn what_cannot_be_compensated_is_refused_with_line_and_column() {
    let (m, _) = model();
    let cases: [(&str, &dyn mtec_comp::ErrorModel, &str); 6] = [
        // B is not an axis of WCAYFXZT
        (
            "G0 X0 Y0 Z0 A0 C0\nG1 X1 B10 F100\n",
            &m,
            "2:7: axis B moves but the model's machine (chain `WCAYFXZT`)",
        ),
        // W: no modelled chain has it
        (
            "G0 X0 Y0 Z0 A0 C0\nG1 W10 F100\n",
            &m,
            "2:4: axis W moves: U, V and W",
        ),
        // an arc that turns C
        (
            "G0 X0 Y0 Z0 A0 C0\nG2 X10 Y0 I5 J0 C30 F100\n",
            &m,
            "2:17: an arc that also turns the rotary axis C",
        ),
        // G93 without F
        (
            "G93\nG0 X0 Y0 Z0 A0 C0\nG1 X10 C30\n",
            &m,
            "3:4: inverse-time feed (G93) without an F word",
        ),
        // rotary offsets set by the program
        ("G10 L2 P1 C30\n", &m, "1:11: G10 with a rotary axis word"),
        // a three-axis model and a rotary word
        (
            "G0 X0 Y0 Z0\nG1 X1 A10 F100\n",
            &Flat,
            "2:7: axis A moves but the error model has no rotary axes",
        ),
    ];
    let opt = RewriteOptions {
        start_rotary_deg: None,
        ..options()
    };
    for (program, model, want) in cases {
        let e = run(program, model, &opt).unwrap_err();
        assert!(e.starts_with(want), "{program:?}: {e}");
    }
    // an unknown angle before a feed move
    let e = run("G0 X0 Y0 Z0\nG1 X10 F100\n", &m, &opt).unwrap_err();
    assert!(e.contains("2:4: the position of A is not known"), "{e}");
}

#[test]
fn a_short_inverse_time_rotary_move_that_gains_xyz_motion_keeps_its_duration() {
    // one piece: the correction adds ~1 um of X Y Z to a 10° turn of A; in G93 LinuxCNC would
    // run it at the 0.1 floor of the rate over that micrometre (1/40 of the time) unless the
    // move is written in G94 with its own feed (found by rs274 in the CLI test)
    let (m, vm) = model();
    let program = "G21 G90 G93\nG0 X40 Y-10 Z-120 A-20 C90\nG1 A-30 F4\nG94\nM2\n";
    let out = run(program, &m, &options()).unwrap();
    let (dev, time) = replay(program, &out, &vm, [0.0; 5]);
    assert!(dev <= 0.55 && time <= 0.01, "{dev} {time}\n{out}");
    assert!(out.contains("G94 G1"), "{out}");
}

/// The rotary options are read with a model that has rotary axes and refused without one,
/// where they would change nothing.
#[test]
fn rotary_options_are_refused_for_a_model_without_rotary_axes() {
    let (rotary, _) = model();
    let flat = mtec_comp::hand::ZeroModel::new("zero");
    for opts in [
        RewriteOptions {
            start_rotary_deg: Some([0.0, 0.0, 10.0]),
            ..RewriteOptions::default()
        },
        RewriteOptions {
            check_step_deg: 0.1,
            ..RewriteOptions::default()
        },
    ] {
        assert!(opts.check_for(&rotary).is_ok());
        let e = opts.check_for(&flat).unwrap_err();
        assert!(e.contains("this model has none"), "{e}");
    }
    assert!(RewriteOptions::default().check_for(&flat).is_ok());
}
