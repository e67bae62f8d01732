//! The rewriter on small programs whose correct output is worked out by hand.

use crate::gcode_support;
use gcode_support::*;
use mtec_comp::gcode::{
    correction_mm, rewrite, GcodeError, Offsets, OnUnsupported, ProblemKind, RewriteOptions,
    RewriteReport,
};
use mtec_comp::ErrorModel;
use std::collections::BTreeMap;

/// e_y = 0.001·x² µm: a smooth bend that splits long moves along X into pieces.
struct Bend;
impl ErrorModel for Bend {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        [0.0, 1e-3 * p[0] * p[0], 0.0]
    }
    fn describe(&self) -> String {
        "bend".into()
    }
}

fn run(input: &str, model: &dyn ErrorModel, opts: &RewriteOptions) -> (String, RewriteReport) {
    let mut out = Vec::new();
    let rep = rewrite(input.as_bytes(), &mut out, model, opts).unwrap();
    (String::from_utf8(out).unwrap(), rep)
}

fn refuse(
    input: &str,
    model: &dyn ErrorModel,
    opts: &RewriteOptions,
) -> mtec_comp::gcode::Diagnostic {
    let mut out = Vec::new();
    match rewrite(input.as_bytes(), &mut out, model, opts) {
        Err(GcodeError::At(d)) => d,
        other => panic!("expected a located error, got {other:?}"),
    }
}

#[test]
fn zero_model_is_byte_identical_with_crlf_bom_and_no_final_newline() {
    let input = b"\xEF\xBB\xBF%\r\nO1234 (PART)\r\nN10 G21 G90 G17 ; setup\r\n\r\nN20 G0 X0 Y0 Z5\r\n/N25 M8\r\nN30 G1 Z-1 F100 (plunge)\r\nN40 X100.00000 Y+50 (long)\r\nN50 G2 X120 Y70 R20\r\nN60 G3 X100 Y90 I-20 J0\r\n(comment \xff\xfe bytes)\r\nN70 G0 Z5\r\nM30\r\n%\r\ntrailing junk after the tape end ((\r\nno newline";
    let mut out = Vec::new();
    let rep = rewrite(&input[..], &mut out, &ZeroModel, &RewriteOptions::default()).unwrap();
    assert_eq!(out, input.to_vec());
    assert_eq!(rep.lines_read, 16);
    assert_eq!(rep.lines_written, 16);
    assert!(!rep.header_written);
}

#[test]
fn constant_error_shifts_every_point_and_keeps_arcs() {
    // e = [+10, -20, +5] um everywhere ⇒ the command is the target minus e: c = [-0.01, +0.02, -0.005] mm
    let model = ConstModel([10.0, -20.0, 5.0]);
    let input =
        "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nX100 (cut)\nG2 X120 Y20 R20\nG3 X100 Y40 I-20 J0\n";
    // no max-segment split here (it applies to every compensated feed move)
    let opts = RewriteOptions {
        max_segment_mm: 1e6,
        ..RewriteOptions::default()
    };
    let (out, rep) = run(input, &model, &opts);
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines[1].starts_with("(mtec compensate gcode"), "{out}");
    assert_eq!(lines[2], "G0 X-0.01 Y0.02 Z4.995");
    // the 6 mm plunge has a constant correction: one piece
    assert_eq!(lines[3], "G1 Z-1.005 F100");
    assert_eq!(lines[4], "X99.99 (cut)");
    // arcs kept: the end points move; an R arc is written with its centre instead (I/J are
    // relative to the shifted start, so the centre moves with it; R would move the centre)
    assert_eq!(lines[5], "G2 X119.99 Y20.02 I20.0 J0.0");
    assert_eq!(lines[6], "G3 X99.99 Y40.02 I-20 J0");
    assert_eq!(lines.len(), 7);
    assert_eq!(rep.arcs_linearised, 0);
    assert_eq!(rep.lines_added, 0);
    assert!((rep.max_correction_um - (100.0f64 + 400.0 + 25.0).sqrt()).abs() < 1e-6);
}

/// e_x = 0.02·x um (20 um/m scale error), worked by hand.
struct ScaleX;
impl ErrorModel for ScaleX {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        [0.02 * p[0], 0.0, 0.0]
    }
    fn describe(&self) -> String {
        "scale".into()
    }
}

#[test]
fn long_move_is_split_and_ends_exactly_at_target_plus_correction() {
    // p + 2e-5 p = t ⇒ c(t) = -2e-5 t / (1 + 2e-5): the correction changes by 0.02 um per mm,
    // so with 0.5 um tolerance a piece may be up to ~25 mm; the max segment (10 mm) decides.
    let input = "G21 G90\nG0 X0 Y0 Z0\nG1 X100 F500\n";
    let (out, rep) = run(input, &ScaleX, &RewriteOptions::default());
    let lines: Vec<&str> = out.lines().collect();
    // the original line is the first piece, then 9 new G1 lines; the last ends at 100 + c(100)
    assert_eq!(lines[3], "G1 X9.9998 F500");
    assert_eq!(lines.len(), 4 + 9);
    let c100: f64 = -2e-5 * 100.0 / (1.0 + 2e-5);
    assert_eq!(
        *lines.last().unwrap(),
        format!("G1 X{}", 100.0 + (c100 * 1e4).round() / 1e4)
    );
    assert_eq!(rep.lines_added, 9);
    // a tighter tolerance (with words fine enough to carry it) does not split this move at all:
    // the model is linear along it, so the straight command between corrected ends is exact
    let opts = RewriteOptions {
        tolerance_um: 0.05,
        max_segment_mm: 1e9,
        decimals_mm: 6,
        ..RewriteOptions::default()
    };
    let (out, _) = run(input, &ScaleX, &opts);
    let xs: Vec<f64> = out
        .lines()
        .skip(3)
        .map(|l| {
            l.split_whitespace().find(|w| w.starts_with('X')).unwrap()[1..]
                .parse()
                .unwrap()
        })
        .collect();
    assert_eq!(xs.len(), 1, "{out}");
    assert!((xs[0] - (100.0 + c100)).abs() < 1e-6);
}

#[test]
fn work_offset_and_tool_length_place_the_model_in_machine_coordinates() {
    // G54 X offset 200 mm: program X10 is machine X210; c = -2e-5·210/(1+2e-5) = -0.0041999 mm
    let opts = RewriteOptions {
        offsets: Offsets {
            work_mm: {
                let mut w = [[0.0; 3]; 9];
                w[0] = [200.0, 0.0, 0.0];
                w
            },
            tool_length_mm: [(3, 55.0)].into(),
            known: [true; 9],
            ..Offsets::default()
        },
        ..RewriteOptions::default()
    };
    let (out, _) = run("G21 G54 G43 H3\nG0 X10 Y0 Z0\n", &ScaleX, &opts);
    assert_eq!(out.lines().nth(2), Some("G0 X9.9958 Y0 Z0"));
    // a model in z shows the tool length: machine z = program z + 55
    struct ScaleZ;
    impl ErrorModel for ScaleZ {
        fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
            [0.0, 0.0, 0.1 * p[2]]
        }
        fn describe(&self) -> String {
            "z".into()
        }
    }
    let (out, _) = run("G21 G54 G43 H3\nG0 X10 Y0 Z0\n", &ScaleZ, &opts);
    // c_z = -1e-4·55/(1+1e-4) = -0.0054995 mm
    assert_eq!(out.lines().nth(2), Some("G0 X10 Y0 Z-0.0055"));
    // G43 with a tool that has no length is refused at the G43 word
    let d = refuse("G21\nG43 H7\n", &ScaleX, &opts);
    assert_eq!((d.line, d.column, d.kind), (2, 1, ProblemKind::Unsupported));
    assert!(d.message.contains("tool 7"));
}

#[test]
fn incremental_and_inch_programs_do_not_drift() {
    let input = "G20 G91\nG0 X0 Y0 Z0\nG1 X1 Y1 F10\nX1\nX1\nY-2\nX-3\n";
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    let (out, _) = run(input, &PolyModel, &opts);
    let work = [[0.0; 3]; 6];
    let start = Some([0.0; 3]);
    let want = interpret(input, &work, &BTreeMap::new(), start);
    let got = interpret(&out, &work, &BTreeMap::new(), start);
    // the last output point, through the machine, is back at the origin within inch rounding
    let end = machine(&PolyModel, got.last().unwrap().end);
    assert!(
        dist(end, want.last().unwrap().end) < 0.127e-3 * 3f64.sqrt(),
        "{out}"
    );
    check_lands_on_target(
        input,
        &out,
        &PolyModel,
        &work,
        &BTreeMap::new(),
        start,
        0.23e-3,
        0.8e-3,
    );
}

#[test]
fn arcs_are_linearised_when_the_correction_varies_and_modal_g2_is_restored() {
    let input = "G21 G90 G17\nG0 X0 Y0 Z0\nG1 X50 F300\nG2 X100 Y0 R25\nX150 Y0 R25\nG1 Y10\n";
    let (out, rep) = run(input, &PolyModel, &RewriteOptions::default());
    assert_eq!(rep.arcs_linearised, 2);
    let lines: Vec<&str> = out.lines().collect();
    // the first arc's own line became its first chord
    let arc1 = lines
        .iter()
        .position(|l| l.starts_with("G1 X") && l.ends_with(""))
        .unwrap();
    assert!(arc1 > 0);
    assert!(
        !out.contains("R25"),
        "R words are gone with the arcs:\n{out}"
    );
    // the modal arc line got a G1 (output was G1 already: nothing inserted) -- and the path holds
    check_lands_on_target(
        input,
        &out,
        &PolyModel,
        &[[0.0; 3]; 6],
        &BTreeMap::new(),
        None,
        0.09e-3,
        1.1e-3,
    );
    // a modal R arc kept as an arc is written in centre form; one of radius 1 um, below
    // LinuxCNC's smallest centre-format radius (1.27 um: rs274 stops at "Zero-radius arc"),
    // becomes a chord instead
    let input = "G21 G90 G17\nG0 X0 Y0 Z0\nG2 X50 Y0 R25 F100\nX50.01 Y0.01 R0.01\n";
    let (out, _) = run(
        input,
        &ConstModel([1.0, 1.0, 1.0]),
        &RewriteOptions::default(),
    );
    assert_eq!(
        out.lines().nth(4),
        Some("X50.009 Y0.009 I0.01 J0.0"),
        "{out}"
    );
    let input = "G21 G90 G17\nG0 X0 Y0 Z0\nG2 X50 Y0 R25 F100\nX50.001 Y0.001 R0.001\n";
    let (out, _) = run(
        input,
        &ConstModel([1.0, 1.0, 1.0]),
        &RewriteOptions::default(),
    );
    assert_eq!(out.lines().nth(4), Some("G1 X50.0 Y0.0"), "{out}");
}

#[test]
fn restores_modal_arc_after_linearisation() {
    // first arc linearised (the model varies), the second tiny one is kept: it needs its G2 back
    let input = "G21 G90\nG0 X0 Y0 Z0\nG2 X50 Y0 R25 F100\nX50.01 Y0.01 R0.01\n";
    let (out, _) = run(
        input,
        &PolyModel,
        &RewriteOptions {
            tolerance_um: 5.0,
            ..RewriteOptions::default()
        },
    );
    let last = out.lines().last().unwrap();
    assert!(last.starts_with("G2 X"), "{out}");
}

#[test]
fn unsupported_constructs_are_refused_with_line_and_column_or_passed_through() {
    let cases: &[(&str, usize, usize, &str)] = &[
        ("G21\nG0 X0 Y0 Z0\nG1 X#<depth>\n", 3, 5, "depth"),
        ("G21\n#5221 = 3\n", 2, 1, "#5221"),
        ("G21\no100 sub\n", 2, 1, "O-word"),
        ("G21 G0 X0 Y0 Z0\nG81 X1 Y1 Z-1 R1\n", 2, 1, "G81"),
        ("G21\nG41 D1\n", 2, 1, "G41"),
        (
            "G21 G0 X0 Y0 Z0\nG1 X1 A30 F100\n",
            2,
            7,
            "axis A moves but the error model has no rotary axes",
        ),
        ("G21\nM98 P100\n", 2, 1, "M98"),
        ("G21\nG1 X1 (open\n", 2, 7, "comment"),
        ("G21 G0 X0 Y0 Z0 F9\nG1 X1 X2\n", 2, 7, "two X words"),
        // LinuxCNC stops at a feed with F0 (or none yet) and at G95 with S0 (or none yet)
        ("G21 G0 X0 Y0 Z0\nG1 X1\n", 2, 4, "feed rate of zero"),
        (
            "G21 G0 X0 Y0 Z0 F9\nF0\nG2 X2 R1\n",
            3,
            4,
            "feed rate of zero",
        ),
        (
            "G21 G0 X0 Y0 Z0\nG95 F0.1\nG1 X1\n",
            3,
            4,
            "spindle speed of zero",
        ),
        (
            "G21 G0 X0 Y0 Z0\nS900 G95 F0.1\nS0\nG3 Y2 R1\n",
            4,
            4,
            "spindle speed of zero",
        ),
        // every G93/G94/G95 sets the feed rate to zero in LinuxCNC, even without a mode change
        (
            "G21 G0 X0 Y0 Z0 F9\nG94\nG1 X1\n",
            3,
            4,
            "feed rate of zero",
        ),
        ("G21 G0 X0 Y0 Z0\nG4\n", 2, 1, "dwell time"),
        ("G21 G0 X0 Y0 Z0\nG4 P-1\n", 2, 1, "dwell time"),
        (
            "G21 G0 X0 Y0 Z0 F9\nG2\n",
            2,
            1,
            "R i j k words all missing",
        ),
        ("G21\nG1 X10 Y0 Z0 F10\n", 2, 4, "position of"),
        ("G21 G0 X0 Y0 Z0\n/G1 X3\n", 2, 1, "block delete"),
        // G10 L1/L2/L20 are followed (tests/gcode_offsets_state.rs); L10 sets the tool table
        // from the current position
        ("G21 G0 X0 Y0 Z0\nG10 L10 P1 Z3\n", 2, 5, "G10 L10"),
    ];
    for (input, line, col, words) in cases {
        // G1 X10 from an unknown start is accepted with end-point-only correction when the
        // target is known; here Y/Z are given so it is accepted: skip that case for refusal
        if words == &"position of" {
            let (_, rep) = run(input, &PolyModel, &RewriteOptions::default());
            assert_eq!(rep.moves_end_point_only, 1);
            continue;
        }
        let d = refuse(input, &PolyModel, &RewriteOptions::default());
        assert_eq!((d.line, d.column), (*line, *col), "{input:?}: {d}");
        assert!(d.message.contains(words), "{input:?}: {d}");
        let opts = RewriteOptions {
            on_unsupported: OnUnsupported::PassThroughWithWarning,
            ..RewriteOptions::default()
        };
        let (out, rep) = run(input, &PolyModel, &opts);
        assert!(rep.warnings_total >= 1);
        let bad_line = input.lines().nth(line - 1).unwrap();
        assert!(
            out.lines().any(|l| l == bad_line),
            "{input:?}: the line was not copied:\n{out}"
        );
    }
}

#[test]
fn refusals_that_flattening_resolves_say_so_and_only_those() {
    let hint = "--flatten-with rs274";
    // LinuxCNC's interpreter turns these into plain moves
    for input in [
        "G21\n#5221 = 3\n",
        "G21\no100 sub\n",
        "G21 G0 X0 Y0 Z0\nG81 X1 Y1 Z-1 R1\n",
        "G21 G0 X0 Y0 Z0\nG98 G83 X1 Y1 Z-1 R1 Q0.5\n",
        "G21\nG41 D1\n",
        "G21 G0 X0 Y0 Z0\nG92.3\n",
    ] {
        let d = refuse(input, &PolyModel, &RewriteOptions::default());
        assert!(d.message.contains(hint), "{input:?}: {d}");
    }
    // flattening changes nothing here: a rotary axis the model lacks, a parameter never set
    // or a block LinuxCNC refuses, threading, probing, a tool table entry set from the position
    for input in [
        "G21 G0 X0 Y0 Z0\nG1 X1 A30 F100\n",
        "G21\nG0 X0 Y0 Z0\nG1 X#<depth>\n",
        "G21\nM98 P100\n",
        "G21 G0 X0 Y0 Z0\nG1 X1\n",
        "G21 G0 X0 Y0 Z0\nG4\n",
        "G21 G0 X0 Y0 Z0\nG33 Z-1 K1\n",
        "G21 G0 X0 Y0 Z0\nG38.2 Z-1 F10\n",
        "G21 G0 X0 Y0 Z0\nG10 L10 P1 Z3\n",
    ] {
        let d = refuse(input, &PolyModel, &RewriteOptions::default());
        assert!(!d.message.contains(hint), "{input:?}: {d}");
    }
}

#[test]
fn correction_failures_are_errors_at_the_line() {
    let d = refuse(
        "G21\nG0 X0 Y0 Z0\nG0 X30000\n",
        &ScaleX,
        &RewriteOptions::default(),
    );
    assert_eq!((d.line, d.kind), (3, ProblemKind::Correction));
    assert!(d.message.contains("exceeds --max-correction-um"), "{d}");
    struct Nan;
    impl ErrorModel for Nan {
        fn error_um(&self, _p: [f64; 3]) -> [f64; 3] {
            [f64::NAN, 0.0, 0.0]
        }
        fn describe(&self) -> String {
            "nan".into()
        }
    }
    let d = refuse("G21\nG0 X0 Y0 Z0\n", &Nan, &RewriteOptions::default());
    assert_eq!(d.line, 2);
    assert!(d.message.contains("non-finite"));
    // the solve agrees with the closed form of the scale model
    let c = correction_mm(&ScaleX, [210.0, 0.0, 0.0], 500.0).unwrap();
    assert!((c[0] + 2e-5 * 210.0 / (1.0 + 2e-5)).abs() < 1e-9);
}

#[test]
fn byte_order_mark_stays_first_when_the_first_line_changes() {
    let input = "\u{feff}G21 G90 G0 X0 Y0 Z0\nG1 X1 F100\n";
    let (out, rep) = run(
        input,
        &ConstModel([1.0, 0.0, 0.0]),
        &RewriteOptions::default(),
    );
    assert!(rep.header_written);
    assert!(out.starts_with("\u{feff}(mtec compensate gcode"), "{out:?}");
    assert_eq!(out.lines().nth(1), Some("G21 G90 G0 X-0.001 Y0 Z0"));
    assert_eq!(out.matches('\u{feff}').count(), 1);
}

#[test]
fn g80_in_a_block_with_another_motion_code_is_ignored_as_linuxcnc_does() {
    // rs274 (linuxcnc-uspace 2.9): `G0 G80` and `G1 G80` keep G0 / G1 in either order, so the
    // axis words of the next block move; only a G80 alone cancels the motion mode
    let model = ConstModel([10.0, -20.0, 5.0]);
    let opts = RewriteOptions {
        max_segment_mm: 1e6,
        ..RewriteOptions::default()
    };
    let input = "G0 G90 G21 G17 G80\nX-75 Y-75 Z5\nG1 G80 Z-2 F100\nG80 G1 X-40\n";
    let (out, _) = run(input, &model, &opts);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "G0 G90 G21 G17 G80", "{out}");
    assert!(lines[1].starts_with("(mtec compensate gcode"), "{out}");
    assert_eq!(lines[2], "X-75.01 Y-74.98 Z4.995", "{out}");
    assert_eq!(lines[3], "G1 G80 Z-2.005 F100", "{out}");
    assert_eq!(lines[4], "G80 G1 X-40.01", "{out}");
    // a G80 alone still leaves no motion mode: axis words after it are refused at the word
    let d = refuse("G0 X0 Y0 Z5\nG80\nX2\n", &model, &opts);
    assert_eq!((d.line, d.column), (3, 1), "{d:?}");
}

#[test]
fn a_tape_mark_after_the_first_line_is_refused_as_linuxcnc_refuses_it() {
    // rs274: "Bad character '%' used" unless % is the program's first line (blank lines before
    // it allowed) or comes after M2/M30, where LinuxCNC reads no further
    let zero = ZeroModel;
    let opts = RewriteOptions::default();
    for (program, line) in [("(job)\n%\nG0 X1\nM2\n%\n", 2), ("G0 X1\n  %\nG0 X2\n", 2)] {
        let d = refuse(program, &zero, &opts);
        assert_eq!((d.line, d.kind), (line, ProblemKind::Syntax), "{program}");
        assert!(
            d.message.contains("Bad character '%' used"),
            "{}",
            d.message
        );
        assert_eq!(d.column, if program.contains("  %") { 3 } else { 1 });
    }
    for program in [
        "\n \n%\nG0 X1\n%\nG0 X2\n",
        "G0 X1\nM30\n%\n",
        "G0 X1\nm2\n%\n(after)\n",
    ] {
        let (out, _) = run(program, &zero, &opts);
        assert_eq!(out, program);
    }
}

/// LinuxCNC's naive-CAM detector (emccanon.cc `linkable`) runs consecutive straight feeds
/// within its tolerance of one line as that line, so in G64 with Q > 0 (or P without Q, which
/// rs274 prints as `SET_NAIVECAM_TOLERANCE(P)`) the pieces of a split move can be merged: the
/// rewriter warns once, at the first split move, naming the G64; Q0, G61 and a move written in
/// one piece give no warning.
#[test]
fn split_moves_under_a_naive_cam_tolerance_are_warned_about_once() {
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    let warned = |program: &str| -> Vec<(usize, usize, String)> {
        let (_, rep) = run(program, &Bend, &opts);
        rep.warnings
            .iter()
            .filter(|d| d.kind == ProblemKind::Controller)
            .map(|d| (d.line, d.column, d.message.clone()))
            .collect()
    };
    let w = warned("G21 G90\nG64 P0.01\nG0 X0 Y0 Z0\nG1 X100 F500\nG1 X200\nM2\n");
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!((w[0].0, w[0].1), (4, 1));
    assert!(
        w[0].2.contains("G64 of line 2") && w[0].2.contains("0.0100 mm"),
        "{}",
        w[0].2
    );
    // inch: P0.0005 in = 0.0127 mm; the move is the first split one (after a one-piece move)
    let w = warned("G20 G90\nG64 P0.001 Q0.0005\nG0 X0 Y0 Z0\nG1 Y1 F20\nG1 X4\nM2\n");
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, 5);
    assert!(w[0].2.contains("0.0127 mm"), "{}", w[0].2);
    // G64 in a block that sets offsets or goes to the reference point still sets the tolerance
    for (program, line) in [
        (
            "G21 G90\nG0 X0 Y0 Z0\nG92 X0 Y0 Z0 G64 P0.5\nG1 X100 F500\nM2\n",
            3,
        ),
        (
            "G21 G90\nG0 X0 Y0 Z0\nG52 X0 G64 P0.5\nG1 X100 F500\nM2\n",
            3,
        ),
        (
            "G21 G90\nG0 X0 Y0 Z0\nG10 L2 P1 X0 G64 Q0.5\nG1 X100 F500\nM2\n",
            3,
        ),
        ("G21 G90\nG64 P0.5 G28\nG0 X0 Y0 Z0\nG1 X100 F500\nM2\n", 2),
    ] {
        let w = warned(program);
        assert_eq!(w.len(), 1, "{program}: {w:?}");
        assert!(
            w[0].2.contains(&format!("G64 of line {line}")),
            "{}",
            w[0].2
        );
    }
    for quiet in [
        "G21 G90\nG64 P0.01\nG0 X0 Y0 Z0\nG92 X0 Y0 Z0 G61\nG1 X100 F500\nM2\n",
        "G21 G90\nG64 P0.01 Q0\nG0 X0 Y0 Z0\nG1 X100 F500\nM2\n",
        "G21 G90\nG64 P0.01\nG61\nG0 X0 Y0 Z0\nG1 X100 F500\nM2\n",
        "G21 G90\nG64\nG0 X0 Y0 Z0\nG1 X100 F500\nM2\n",
        "G21 G90\nG64 P0.01\nG0 X0 Y0 Z0\nG1 Y100 F500\nM2\n",
    ] {
        assert_eq!(warned(quiet), vec![], "{quiet}");
    }
}

/// Blocks LinuxCNC refuses must be refused here too, at the word, not rewritten into blocks it
/// refuses as well (found 2026-11-28 with hand-written programs: `G1 X40 P5` was split and
/// compensated; rs274 stops at both with "P word with no G2 G3 G4 … to use it"). Each refusal
/// below was checked with rs274; the accepted blocks are ones rs274 runs.
#[test]
fn words_linuxcnc_refuses_in_a_move_are_refused_at_the_word() {
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    let model = ConstModel([3.0, -2.0, 1.0]);
    for (line, column, what) in [
        ("G1 X40 P5", 8, "P word"),
        ("G1 X40 Q1", 8, "Q word"),
        ("G1 X40 R5", 8, "R word"),
        ("G0 X40 K1", 8, "K word"),
        ("G1 X40 E1 F200", 8, "E word"),
        ("G1 X40 G49 H1", 12, "H word"),
        ("G2 X40 I17.5 J0 L1", 17, "L word"),
        ("G3 X40 I17.5 J0 D1", 17, "D word"),
        ("G1 X40 N5", 8, "N word after other words"),
        ("G1 X40 O100", 8, "O-word after other words"),
        // words no code in the block uses, with codes that take other words (rs274, random
        // blocks, 2026-11-28): M5/M51 take no E, G64 no E, G92.1 no D, G10 L2 no K or E
        ("G1 X40 M51 E2", 12, "E word"),
        ("G1 X40 G64 E1", 12, "E word"),
        ("G1 X40 G92.1 D1", 14, "D word"),
        ("M5 K2", 4, "K word"),
        ("G10 L2 P1 X1 K2", 14, "K word"),
        ("G10 L2 P1 X1 Q0 E1", 17, "E word"),
        ("G92 X1 R0.5", 8, "R word"),
        ("G10 L20 P2 J1", 12, "I or J word"),
        ("M19 R400", 1, "within 0..360"),
        ("M62", 1, "P word"),
        ("M66", 1, "P or E word"),
        ("M61", 1, "Q word"),
        ("G53", 1, "G53 without an axis word"),
        ("G2 R5", 1, "without an end point"),
        ("G0 X40 L-1", 8, "negative loop or mode number"),
    ] {
        let program = format!("G21 G90 G17\nG0 X0 Y0 Z0\nG1 X5 F300\n{line}\nM2\n");
        let d = refuse(&program, &model, &opts);
        assert_eq!((d.line, d.column), (4, column), "{line}: {}", d.message);
        assert!(d.message.contains(what), "{line}: {}", d.message);
    }
    for line in [
        "G2 X40 I17.5 J0 P1",
        "G4 P1 X40",
        "G1 X40 M62 P1",
        "G1 X40 M66 P0 L0 Q1",
        "N5 G1 X40",
        "G1 X40 S100 T2",
        // LinuxCNC takes Q-1 for an absent Q (but refuses L-1); M19 with R and P; Q with G64
        "G1 X40 Q-1",
        "G64 P0.01 Q0",
        "M19 R90 P1",
        "M66 E0 L0",
        "G53 G0 X0",
    ] {
        let program = format!("G21 G90 G17\nG0 X0 Y0 Z0\nG1 X5 F300\n{line}\nM2\n");
        let mut out = Vec::new();
        assert!(
            rewrite(program.as_bytes(), &mut out, &model, &opts).is_ok(),
            "{line}"
        );
    }
}

/// M70-M73 save and restore the modal state (units, distance modes, plane, feed …): `M70`,
/// `G91`, `M72`, `G1 X20` ran on LinuxCNC as an absolute move, and the rewriter, not following
/// the restore, wrote it as incremental pieces (10 mm off). They are refused at the M word.
#[test]
fn modal_state_save_and_restore_is_refused_at_the_m_word() {
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    for (program, line, column) in [
        (
            "G21 G90\nG0 X0 Y0 Z0\nG1 F100\nM70\nG91\nG1 X5\nM72\nG1 X20\n",
            4,
            1,
        ),
        ("G21 G90\nG0 X0 Y0 Z0\nG1 F100 M73\n", 3, 9),
        ("G21 G90\nM71\n", 2, 1),
    ] {
        let d = refuse(program, &PolyModel, &opts);
        assert_eq!(
            (d.line, d.column),
            (line, column),
            "{program}: {}",
            d.message
        );
        assert!(
            d.message.contains("modal state save/restore"),
            "{}",
            d.message
        );
    }
}

/// With `--start-position-mm` the machine stands there uncorrected: a feed as the first move
/// starts off the path by the error there. It was refused ("a piece shorter than 1 nm"); now,
/// when that error is over the tolerance, it is corrected at its end point only, as from an
/// unknown start (found 2026-11-28 on a jscut program that starts with `G1 Z2`). A first rapid,
/// or a start where the error is within the tolerance, is unchanged.
#[test]
fn a_first_feed_from_an_uncorrected_start_is_corrected_at_its_end() {
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    let model = ConstModel([27.0, -10.0, 5.0]);
    let (out, rep) = run("G21 G90\nG1 X50 F1000\nG1 X100\nM2\n", &model, &opts);
    let lines: Vec<&str> = out.lines().filter(|l| !l.starts_with("(mtec")).collect();
    assert_eq!(lines[1], "G1 X49.973 Y0.01 Z-0.005 F1000", "{out}");
    assert_eq!(lines[2], "G1 X59.973", "{out}");
    assert_eq!(rep.moves_end_point_only, 1);
    // within the tolerance at the start: the path is followed from there as before
    let small = ConstModel([0.3, 0.0, 0.0]);
    let (_, rep) = run("G21 G90\nG1 X50 F1000\nM2\n", &small, &opts);
    assert_eq!(rep.moves_end_point_only, 0);
}

/// A centre-format arc whose end radius differs from its start radius is run by LinuxCNC up to
/// √2 · 0.02 mm (rs274 bisection, 2026-11-28). Written as an arc with a corrected end and
/// centre, an arc close to that limit could pass it (rounding, the change of the correction):
/// then it is cut into chords, so the compensated program runs wherever the original does.
#[test]
fn an_arc_near_linuxcnc_s_radius_limit_is_cut_into_chords() {
    let model = ConstModel([3.0, -2.0, 1.0]);
    let opts = RewriteOptions::default();
    for (mismatch, linearised) in [(0.0275, 0), (0.0281, 1)] {
        let input = format!("G21 G90 G17\nG0 X0 Y0 Z0\nF100\nG2 X[4 + {mismatch}] Y0 I2 J0\nM2\n");
        let (out, rep) = run(&input, &model, &opts);
        assert_eq!(rep.arcs_linearised, linearised, "{mismatch}: {out}");
    }
    // beyond the limit LinuxCNC stops, and so does mtec, at the arc's first word after G2
    let d = refuse(
        "G21 G90 G17\nG0 X0 Y0 Z0\nF100\nG2 X4.029 Y0 I2 J0\nM2\n",
        &model,
        &opts,
    );
    assert_eq!((d.line, d.column), (4, 4), "{}", d.message);
    assert!(d.message.contains("not on the circle"), "{}", d.message);
}

/// Posts such as Mastercam's Haas post write `A0.` on 4-axis-ready lines of 3-axis programs.
/// With a 3-axis model such a word is copied when it repeats the angle the axis stands at
/// (`--start-rotary-deg`, or zero in G91); a word that turns the axis is refused at the word.
#[test]
fn a_rotary_word_that_keeps_the_axis_still_passes_a_three_axis_model() {
    let still = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        start_rotary_deg: Some([0.0, 0.0, 0.0]),
        ..RewriteOptions::default()
    };
    let program = "G21 G90\nG0 X0 Y0 Z10 A0\nG1 Z-1 F100\nG1 X10 A0.\nG91 G1 X5 A0\nG90 A0\nM2\n";
    let (out, _) = run(program, &PolyModel, &still);
    for kept in ["A0\n", "A0.\n", "A0\nG90 A0\n"] {
        assert!(out.contains(kept), "{kept:?}: {out}");
    }
    for (program, column) in [
        ("G21 G90\nG0 X0 Y0 Z10 A5\n", 14),
        ("G21 G91\nG0 X0 Y0 Z10 A0.001\n", 14),
    ] {
        let d = refuse(program, &PolyModel, &still);
        assert_eq!((d.line, d.column), (2, column), "{program}: {}", d.message);
        assert!(d.message.contains("axis A moves"), "{}", d.message);
    }
    // without the start angle the first A0 may turn the axis: refused, naming the option
    let d = refuse(program, &PolyModel, &RewriteOptions::default());
    assert!(d.message.contains("--start-rotary-deg"), "{}", d.message);
}

/// LinuxCNC runs a program without M2, M30 or a closing % to its last line and then stops with
/// an error; mtec compensates it and says so once, at the last line.
#[test]
fn a_program_without_an_end_is_warned_about_once() {
    let model = ConstModel([3.0, -2.0, 1.0]);
    let (_, rep) = run(
        "G21 G90\nG0 X0 Y0 Z0\nG1 X5 F100\n",
        &model,
        &RewriteOptions::default(),
    );
    assert_eq!(rep.warnings_total, 1, "{:?}", rep.warnings);
    assert_eq!(rep.warnings[0].line, 3);
    assert!(rep.warnings[0].message.contains("no end (M2, M30"));
    for ended in ["M2\n", "M30\n", "%\n"] {
        let program = format!("%\nG21 G90\nG0 X0 Y0 Z0\nG1 X5 F100\n{ended}");
        let (_, rep) = run(&program, &model, &RewriteOptions::default());
        assert_eq!(rep.warnings_total, 0, "{ended:?}: {:?}", rep.warnings);
    }
}

/// M0, M1, M2, M30 and M60 act after the block's motion (LinuxCNC's order of execution), so a
/// move written as several pieces carries them after its last piece; words that act before the
/// motion (M5 here) stay on the first. Before (found 2026-11-28, random blocks seed 8),
/// `G1 M2` split in two ended the program after the first piece.
#[test]
fn stops_follow_the_last_piece_of_a_split_move() {
    let opts = RewriteOptions::default();
    for stop in ["M0", "M1", "M2", "M30", "M60", "m 30"] {
        let program = format!("G21 G90\nG0 X0 Y0 Z0\nF500 S100 M3\nG1 X60 M5 {stop} (c)\nM2\n");
        let (out, _) = run(&program, &Bend, &opts);
        let lines: Vec<&str> = out.lines().filter(|l| !l.starts_with("(mtec")).collect();
        let first = lines.iter().position(|l| l.contains("(c)")).unwrap();
        let stop_at = lines.iter().position(|l| *l == stop).unwrap();
        assert!(
            lines[first].contains("M5") && !lines[first].contains(stop),
            "{out}"
        );
        // every piece between, then the stop, then the program's own end
        assert!(stop_at > first + 1, "{out}");
        assert!(
            lines[first + 1..stop_at]
                .iter()
                .all(|l| l.starts_with("G1 X")),
            "{out}"
        );
        assert!(lines[stop_at - 1].starts_with("G1 X60"), "{out}");
        assert_eq!(lines[stop_at + 1..], ["M2"], "{out}");
    }
    // a move written as one line keeps its stop
    let (out, _) = run("G21 G90\nG0 X0 Y0 Z0\nG1 X0.5 F500 M0\nM2\n", &Bend, &opts);
    assert!(out.contains("\nG1 X0.5 F500 M0\n"), "{out}");
}

/// A move before the program states its units or distance mode is compensated for
/// `--default-units` and G90, LinuxCNC's start-up modes, but the controller keeps what the last
/// program or MDI command left: warned once, at that move, naming what is missing.
#[test]
fn a_move_before_the_units_or_distance_mode_are_stated_is_warned_about() {
    let opts = RewriteOptions::default();
    let warned = |program: &str| -> Vec<(usize, String)> {
        let (_, rep) = run(program, &Bend, &opts);
        rep.warnings
            .iter()
            .filter(|d| d.message.contains("before the program states"))
            .map(|d| (d.line, d.message.clone()))
            .collect()
    };
    let w = warned("G0 X0 Y0 Z0\nG1 X10 F100\nG21 G90\nG1 X20\nM2\n");
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].0, 1);
    assert!(w[0].1.contains("units and distance mode"), "{}", w[0].1);
    let w = warned("G21\nG0 X0 Y0 Z0\nM2\n");
    assert!(
        w.len() == 1 && w[0].1.contains("its distance mode: taken as G90"),
        "{w:?}"
    );
    let w = warned("G90\nG0 X0 Y0 Z0\nF100 G1 X1\nM2\n");
    assert!(
        w.len() == 1 && w[0].1.contains("its units: taken as G21"),
        "{w:?}"
    );
    // stated in the same block as the first move, or before it: quiet
    for quiet in [
        "G21 G90 G0 X0 Y0 Z0\nM2\n",
        "G20\nG90\nG0 X0 Y0 Z0\nG91\nF10\nG1 X1\nM2\n",
    ] {
        assert_eq!(warned(quiet), vec![], "{quiet}");
    }
}

/// An arc that starts where the machine stands uncorrected (right after a G92 at the start) is
/// corrected at its end point only, but it is still an arc LinuxCNC must accept: an arc whose
/// end is off its circle is refused at its word, as anywhere else, and one whose corrected end
/// alone would change its radius beyond LinuxCNC's tolerance (√2 · 0.02 mm) is refused with a
/// remedy. Found 2026-11-29 on mecode's output: such an arc was written unchecked.
#[test]
fn an_arc_from_an_uncorrected_start_is_still_checked_as_linuxcnc_checks_it() {
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    // the mecode program's block: radius 9.535 mm at the start, 6.555 mm at the end
    let bad = "G21 G17 G90\nG1 F300\nG92 X-2.8444 Y-1.5487 Z-1.3216\nG18\nG2 X2.0881 Z-7.6760 I9.4061 K-1.5633\nM2\n";
    let d = refuse(bad, &ConstModel([10.0, -10.0, 5.0]), &opts);
    assert_eq!((d.line, d.column), (5, 4), "{}", d.message);
    assert!(d.message.contains("not on the circle"), "{}", d.message);
    let arc = "G21 G17 G90\nG92 X-10 Y0 Z0\nG2 X10 Y0 I10 J0 F100\nG1 X20\nM2\n";
    // 15 um of correction at the end: within the tolerance, written as an arc to the corrected end
    let (out, rep) = run(arc, &ConstModel([12.0, -9.0, 0.0]), &opts);
    assert!(out.contains("G2 X9.988 Y0.009 I10 J0"), "{out}");
    assert_eq!(rep.moves_end_point_only, 1);
    // 50 um: the written arc's end radius would differ by 50 um from its start radius
    let d = refuse(arc, &ConstModel([30.0, -40.0, 0.0]), &opts);
    assert_eq!((d.line, d.column), (3, 4), "{}", d.message);
    assert!(
        d.message
            .contains("starts where the machine stands uncorrected")
            && d.message.contains("50.0 um"),
        "{}",
        d.message
    );
}

/// An R arc from an uncorrected start (here the first move, incremental) keeps its start where
/// the machine stands and moves its end: with R kept, a near-half circle's radius no longer
/// reaches the moved end and LinuxCNC refuses the block ("Arc radius too small to reach end
/// point"), where the original runs. It is written in centre form. Found 2026-11-29 on
/// mecode's output (`G3 X-92.7153 Y-1.0392 R46.3606` as its first move).
#[test]
fn an_r_arc_from_an_uncorrected_start_is_written_in_centre_form() {
    let opts = RewriteOptions {
        start_position_mm: Some([0.0; 3]),
        ..RewriteOptions::default()
    };
    let program = "G91 G21 G17\nG1 F300\nG3 X-92.7153 Y-1.0392 R46.3606\nG1 X10\nM2\n";
    let (out, rep) = run(program, &ConstModel([20.0, -15.0, 10.0]), &opts);
    assert_eq!(rep.moves_end_point_only, 1);
    let arc = out.lines().find(|l| l.starts_with("G3")).unwrap();
    assert!(
        !arc.contains('R') && arc.contains('I') && arc.contains('J'),
        "{out}"
    );
    // the centre is the nominal one (the start is not moved), the end is corrected by -e
    assert!(arc.contains("X-92.7353 Y-1.0242"), "{arc}");
}

/// An M code outside LinuxCNC's table (found 2026-11-30 with FreeCAD's Centroid post, whose
/// programs carry M25, "Z home" on that control) is copied with a warning at the word, once per
/// code; LinuxCNC's own codes, user M100–M199 among them, are not warned about.
#[test]
fn an_m_code_linuxcnc_does_not_have_is_warned_about_once_per_code() {
    let model = ConstModel([3.0, -2.0, 1.0]);
    let program =
        "G21 G90\nG0 X0 Y0 Z5\nM8 M25\nG1 X5 F100\nM25\nM101\nG0 Z5 M10\nM3 S1000 M9\nM5\nM2\n";
    let (out, rep) = run(program, &model, &RewriteOptions::default());
    assert_eq!(rep.warnings_total, 2, "{:?}", rep.warnings);
    assert_eq!((rep.warnings[0].line, rep.warnings[0].column), (3, 4));
    assert!(
        rep.warnings[0]
            .message
            .starts_with("M25 is not a LinuxCNC M code"),
        "{}",
        rep.warnings[0].message
    );
    assert_eq!((rep.warnings[1].line, rep.warnings[1].column), (7, 7));
    assert!(rep.warnings[1].message.starts_with("M10 is not"));
    // the blocks are copied, the moves compensated
    assert!(out.contains("\nM8 M25\n") && out.contains("\nM25\n") && out.contains("\nM101\n"));
    assert!(out.contains("\nG1 X4.997 F100\n"), "{out}");
}
