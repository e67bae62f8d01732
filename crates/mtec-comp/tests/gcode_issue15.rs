//! Regression tests of issue 15: programs the rewriter used to write wrong with exit code 0.
//! Each output is pushed through the machine p + e(p) sample by sample (every 0.02 mm) and
//! checked against the original path with the documented bound: `--tolerance-um` for straight
//! moves, plus `--chord-tolerance-um` for linearised arcs.

use crate::gcode_support;
use gcode_support::*;
use mtec_comp::gcode::{
    rewrite, BlockDelete, GcodeError, Offsets, ProblemKind, RewriteOptions, Units,
};
use mtec_comp::{ErrorModel, GridMap, Outside};

fn run(input: &str, model: &dyn ErrorModel, opts: &RewriteOptions) -> String {
    let mut out = Vec::new();
    rewrite(input.as_bytes(), &mut out, model, opts).unwrap();
    String::from_utf8(out).unwrap()
}

fn refused(input: &str, model: &dyn ErrorModel, opts: &RewriteOptions) -> (usize, usize, String) {
    let mut out = Vec::new();
    match rewrite(input.as_bytes(), &mut out, model, opts) {
        Err(GcodeError::At(d)) => (d.line, d.column, d.message),
        other => panic!(
            "expected a refusal, got {other:?}\n{}",
            String::from_utf8_lossy(&out)
        ),
    }
}

/// The documented bound for programs with arcs (mm).
fn bound_mm(o: &RewriteOptions) -> f64 {
    (o.tolerance_um + o.chord_tolerance_um) * 1e-3
}

/// e_x = 0.002·x µm: 2 µm/m, so a 60 mm arc varies by 0.12 µm and stays an arc.
struct GentleScale;
impl ErrorModel for GentleScale {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        [0.002 * p[0] + 7.0, -5.0 + 0.001 * p[1], 3.0]
    }
    fn describe(&self) -> String {
        "gentle scale (test)".into()
    }
}

#[test]
fn r_arcs_near_a_semicircle_keep_their_centre() {
    let o = RewriteOptions::default();
    // the case: G2 X80 Y0 R30 from X20 Y0 (exactly 180°)
    let input = "G21 G90 G17\nG0 X20 Y0 Z0\nG1 X20 Y0 F100\nG2 X80 Y0 R30\nG3 X20.0 Y0.5 R30.2\n";
    let out = run(input, &GentleScale, &o);
    assert!(!out.contains("R30"), "R kept on a corrected arc:\n{out}");
    let w = check_path_dense(
        input,
        &out,
        &GentleScale,
        &[[0.0; 3]; 6],
        None,
        0.02,
        bound_mm(&o),
    );
    assert!(w < bound_mm(&o));
    // the inch case: G3 X.3 R0.05 from X.2
    let input = "G20 G90 G17\nG0 X.2 Y0 Z0\nG1 X.2 Y0 F10\nG3 X.3 R0.05\n";
    let out = run(input, &GentleScale, &o);
    assert!(!out.contains("R0.05"), "{out}");
    check_path_dense(
        input,
        &out,
        &GentleScale,
        &[[0.0; 3]; 6],
        None,
        0.02,
        bound_mm(&o),
    );
}

#[test]
fn full_circles_without_axis_words_are_compensated() {
    let o = RewriteOptions::default();
    // explicit and modal, with P turns, in G17 and G18
    let input = "G21 G90 G17\nG0 X10 Y0 Z0\nG1 X10 Y0 F100\nG3 I-5\nG2 X10 Y0 I-5\nI-5\nI-5 J0\nG3 I-5 P2\nG18 G2 K5\nG17 G1 X20\n";
    let out = run(input, &PolyModel, &o);
    assert!(
        !out.contains("\nI-5\n"),
        "a full circle copied unchanged:\n{out}"
    );
    // every circle was linearised: no centre word may survive beside the G1 (rs274 refuses a
    // J word with no G2/G3 to use it; found by tests/rs274 when two removed words shared a blank)
    for l in out.lines().filter(|l| !l.starts_with('(')) {
        assert!(
            !l.contains('I') && !l.contains('J') && !l.contains('K'),
            "centre word left on a linearised line: {l}\n{out}"
        );
    }
    let w = check_path_dense(
        input,
        &out,
        &PolyModel,
        &[[0.0; 3]; 6],
        None,
        0.02,
        bound_mm(&o),
    );
    assert!(w > 0.0 && w < bound_mm(&o));
}

#[test]
fn g53_feed_moves_are_split_like_every_feed_move() {
    let o = RewriteOptions {
        offsets: Offsets::all_known({
            let mut w = [[0.0; 3]; 9];
            w[0] = [100.0, 50.0, -20.0];
            w
        }),
        ..RewriteOptions::default()
    };
    let input = "G21 G90 G54\nG0 X0 Y0 Z0\nG53 G1 X300 Y300 Z0 F100\nG1 X10\n";
    let out = run(input, &PolyModel, &o);
    let g53_lines = out.lines().filter(|l| l.starts_with("G53 G1 X")).count();
    assert!(g53_lines > 10, "the 320 mm G53 move was not split:\n{out}");
    let mut work = [[0.0; 3]; 6];
    work[0] = [100.0, 50.0, -20.0];
    check_path_dense(
        input,
        &out,
        &PolyModel,
        &work,
        None,
        0.05,
        o.tolerance_um * 1e-3,
    );
    // G53 with an arc is refused as LinuxCNC refuses it
    let (line, _, msg) = refused("G21\nG0 X0 Y0 Z0\nG53 G2 X10 I5 F100\n", &PolyModel, &o);
    assert_eq!(line, 3);
    assert!(msg.contains("G53 needs G0 or G1"), "{msg}");
}

/// A flat 10 mm grid with one node raised by 30 µm in Y: a local feature a sampler misses.
fn bump_map() -> GridMap {
    let xs: Vec<f64> = (0..=20).map(|i| i as f64 * 10.0).collect();
    let mut values = vec![[0.0; 3]; 21 * 21];
    values[7 * 21 + 9] = [0.0, 30.0, 0.0]; // node (70, 90)
    GridMap::new([xs.clone(), xs, vec![0.0]], values, Outside::Clamp, "bump").unwrap()
}

#[test]
fn a_single_node_bump_between_samples_is_compensated() {
    let map = bump_map();
    let o = RewriteOptions::default();
    // a straight move over the bump (corrections zero at both ends), a diagonal, an arc
    // whose samples straddle it, and a full circle around it
    let input = "G21 G90 G17\nG0 X0 Y90 Z0\nG1 X200 Y90 F100\nG1 X60 Y80\nG1 X80 Y100\nG0 X50 Y90\nG2 X90 Y90 R20\nG0 X70 Y85\nG3 I0 J5\n";
    let out = run(input, &map, &o);
    let w = check_path_dense(input, &out, &map, &[[0.0; 3]; 6], None, 0.02, bound_mm(&o));
    assert!(w < bound_mm(&o), "{w}");
    // the bump is really corrected, not just skipped: the tool passes the node within bound
    assert!(out.lines().count() > 20, "{out}");
}

#[test]
fn decimals_that_lose_the_correction_are_refused() {
    for d in 0..=3 {
        let o = RewriteOptions {
            decimals_mm: d,
            ..RewriteOptions::default()
        };
        let e = o.validate().unwrap_err();
        assert!(e.contains("--decimals-mm"), "{e}");
        assert!(e.contains("use --decimals-mm 4 or more"), "{e}");
    }
    assert!(RewriteOptions::default().validate().is_ok());
    // a coarser rounding is allowed with a tolerance that holds it
    let o = RewriteOptions {
        decimals_mm: 3,
        tolerance_um: 2.0,
        ..RewriteOptions::default()
    };
    assert!(o.validate().is_ok());
    let o = RewriteOptions {
        decimals_inch: 4,
        ..RewriteOptions::default()
    };
    assert!(o.validate().unwrap_err().contains("--decimals-inch"));
}

#[test]
fn a_work_offset_missing_from_the_offsets_is_refused() {
    // no file: G54 only, as zero
    let mut o = RewriteOptions {
        offsets: Offsets::default(),
        ..RewriteOptions::default()
    };
    let (line, col, msg) = refused("G21 G90\nG0 X0 Y0 Z0\nG56 G1 X10 F100\n", &PolyModel, &o);
    assert_eq!((line, col), (3, 1));
    assert!(
        msg.contains("G56 is selected but its offset is not known"),
        "{msg}"
    );
    // listed in the file: accepted
    let file = mtec_comp::gcode::OffsetsFile {
        work_offsets_mm: [("G56".to_string(), [1.0, 2.0, 3.0])].into(),
        active: Some("G56".into()),
        ..Default::default()
    };
    o.offsets = file.validate().unwrap();
    run("G21 G90\nG0 X0 Y0 Z0\nG56 G1 X10 F100\n", &PolyModel, &o);
    // ... but then G54 is not known
    let (line, col, msg) = refused("G21 G90 G54\nG0 X0 Y0 Z0\n", &PolyModel, &o);
    assert_eq!((line, col), (1, 9));
    assert!(msg.contains("G54"), "{msg}");
}

/// A model whose description is very long (a deep path to its file).
struct LongName;
impl ErrorModel for LongName {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        [1.0 + 0.01 * p[0], 0.0, 0.0]
    }
    fn describe(&self) -> String {
        format!("map from /{}", "very/deep/folder/".repeat(30))
    }
}

#[test]
fn every_written_line_fits_linuxcncs_line_length() {
    let o = RewriteOptions::default();
    let out = run("G21 G90\nG0 X0 Y0 Z0\nG1 X100 F100\n", &LongName, &o);
    for l in out.lines() {
        // rs274 refuses 253 characters and more (a CR counts): 251 is the default limit
        assert!(l.len() <= 251, "{} characters: {l}", l.len());
    }
    assert!(out.lines().nth(1).unwrap().contains("..."));
    // a line made longer than the limit by the rewrite is refused, not written
    let long_comment = format!("({})", "x".repeat(240));
    let input = format!("G21 G90\nG0 X0 Y0 Z0\nG1 X100 F100 {long_comment}\n");
    let mut out = Vec::new();
    match rewrite(input.as_bytes(), &mut out, &LongName, &o) {
        Err(GcodeError::At(d)) => {
            assert_eq!(d.line, 3);
            assert_eq!(d.kind, ProblemKind::Correction);
            assert!(d.message.contains("over the controller's limit of 251"));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn two_codes_of_one_modal_group_are_refused_as_linuxcnc_refuses_them() {
    let o = RewriteOptions::default();
    // rs274: "Two g codes used from same modal group"
    for (input, col) in [
        ("G21\nG0 X0 Y0 Z0\nG0 G1 X50\n", 4),
        ("G21\nG0 X0 Y0 Z0\nG90 G91 X10\n", 5),
        ("G21\nG0 X0 Y0 Z0\nG17 G18 G2 X10 I5\n", 5),
    ] {
        let (line, c, msg) = refused(input, &PolyModel, &o);
        assert_eq!((line, c), (3, col), "{input:?}: {msg}");
        assert!(msg.contains("same modal group"), "{msg}");
    }
}

#[test]
fn parameters_and_expressions_with_literal_values_are_evaluated_as_linuxcnc_does() {
    let o = RewriteOptions::default();
    // every read on a line sees the values from before the line's assignments
    let input = "G21 G90 G17\n#1=10 #<depth>=-2\nG0 X0 Y0 Z0\nG1 X[#1*5] Y#1 Z#<depth> F100\n#1=[#1+10] G1 X#1\nG1 Y[SIN[30]*40]\n";
    let out = run(input, &PolyModel, &o);
    let plain = "G21 G90 G17\nG0 X0 Y0 Z0\nG1 X50 Y10 Z-2 F100\nG1 X10\nG1 Y20\n";
    // the computed words became literal corrected numbers; the path is the plain program's
    assert!(
        !out.contains("X[#1*5]") && out.contains("#1=[#1+10]"),
        "{out}"
    );
    let w = check_path_dense(
        plain,
        &out.replace("#1=10 #<depth>=-2\n", "")
            .replace("#1=[#1+10] ", ""),
        &PolyModel,
        &[[0.0; 3]; 6],
        None,
        0.05,
        o.tolerance_um * 1e-3,
    );
    assert!(w < o.tolerance_um * 1e-3);
}

#[test]
fn block_delete_follows_the_operators_switch() {
    let input = "G21 G90\nG0 X0 Y0 Z0\n/G1 X30 F100\nG1 Y30 F100\n";
    // not given: refused
    let (line, _, msg) = refused(input, &PolyModel, &RewriteOptions::default());
    assert_eq!(line, 3);
    assert!(msg.contains("--block-delete"), "{msg}");
    // on: the block is skipped by the controller, so it is copied and the next move starts at X0
    let on = RewriteOptions {
        block_delete: BlockDelete::On,
        ..RewriteOptions::default()
    };
    let out = run(input, &PolyModel, &on);
    assert!(out.contains("\n/G1 X30 F100\n"), "{out}");
    check_path_dense(
        "G21 G90\nG0 X0 Y0 Z0\nG1 Y30 F100\n",
        &out.replace("/G1 X30 F100\n", ""),
        &PolyModel,
        &[[0.0; 3]; 6],
        None,
        0.05,
        0.5e-3,
    );
    // off: it runs, and is compensated like any other block
    let off = RewriteOptions {
        block_delete: BlockDelete::Off,
        ..RewriteOptions::default()
    };
    let out = run(input, &PolyModel, &off);
    assert!(!out.contains("/G1 X30 F100\n"), "{out}");
    check_path_dense(
        "G21 G90\nG0 X0 Y0 Z0\nG1 X30 F100\nG1 Y30 F100\n",
        &out.replace('/', ""),
        &PolyModel,
        &[[0.0; 3]; 6],
        None,
        0.05,
        0.5e-3,
    );
    // a split `/` block keeps its `/` on every line it becomes (and on a stop moved after it):
    // at the other switch position the controller skips all of it, as it skips the original
    let long = "G21 G90\nG0 X0 Y0 Z0\n/G1 X60 F100 M0\nG1 Y30\nM2\n";
    let out = run(long, &PolyModel, &off);
    let block: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with('/'))
        .take_while(|l| !l.starts_with("G1 Y"))
        .collect();
    assert!(
        block.len() > 2 && block.iter().all(|l| l.starts_with('/')),
        "{out}"
    );
    assert_eq!(block.last(), Some(&"/M0"), "{out}");
}

/// LinuxCNC's interpreter (rs274, linuxcnc-uspace 2.9) subtracts a tool length offset applied in
/// mm from a G53 position in inches unconverted after G20 (`G53 G0 Z1` with a 25.4 mm tool goes
/// to Z −24.4 in): the move does not go where G53 says, so the rewriter refuses it (found
/// 2026-11-27 by generator seed 10). After a fresh G43 in the new units, or with G49, it is
/// compensated as before.
#[test]
fn g53_with_a_tool_length_offset_from_other_units_is_refused() {
    let mut offsets = Offsets::all_known([[0.0; 3]; 9]);
    offsets.tool_length_mm.insert(1, 25.4);
    let o = RewriteOptions {
        offsets,
        ..RewriteOptions::default()
    };
    let prefix = "G21 G90\nG0 X0 Y0 Z100\nT1 M6\nG43 H1\n";
    let (line, column, msg) = refused(&format!("{prefix}G20\nG53 G0 Z1\n"), &PolyModel, &o);
    assert_eq!((line, column), (6, 8), "{msg}");
    assert!(msg.contains("G53 with a tool length offset"), "{msg}");
    for tail in [
        "G20\nG43 H1\nG53 G0 Z1\n",
        "G20\nG49\nG53 G0 Z1\n",
        "G53 G0 Z25\n",
        "G21\nG53 G0 Z25\n",
    ] {
        let out = run(&format!("{prefix}{tail}"), &PolyModel, &o);
        assert!(out.contains("G53 G0"), "{tail}: {out}");
    }
}

#[test]
fn default_digits_follow_the_tolerance() {
    use mtec_comp::gcode::default_decimals;
    assert_eq!(default_decimals(Units::Mm, 0.5), 4);
    assert_eq!(default_decimals(Units::Inch, 0.5), 5);
    // 0.2 um: 5 inch digits round by 0.22 um > 0.1 um, 6 by 0.022 um
    assert_eq!(default_decimals(Units::Inch, 0.2), 6);
    assert_eq!(default_decimals(Units::Mm, 0.2), 4);
    assert_eq!(default_decimals(Units::Mm, 0.1), 5);
    // the chosen digits always pass validation, down to what 9 digits can hold
    // (`with_tolerance`: what the CLI, the Python module and projects start from)
    for tol in [0.001, 0.01, 0.05, 0.1, 0.2, 0.5, 1.0, 5.0] {
        let o = RewriteOptions::with_tolerance(tol);
        assert_eq!(o.tolerance_um, tol);
        assert_eq!(
            (o.decimals_mm, o.decimals_inch),
            (
                default_decimals(Units::Mm, tol),
                default_decimals(Units::Inch, tol)
            )
        );
        assert!(o.validate().is_ok(), "{tol}: {:?}", o.validate());
    }
}

#[test]
fn a_start_position_no_machine_has_is_refused_by_every_caller() {
    let at = |p: [f64; 3]| RewriteOptions {
        start_position_mm: Some(p),
        ..RewriteOptions::default()
    };
    assert!(at([1.0, -2.5, 99_999.0]).validate().is_ok());
    for p in [[1e300, 0.0, 0.0], [0.0, -1e5, 0.0], [0.0, 0.0, f64::NAN]] {
        assert!(at(p).validate().is_err(), "{p:?}");
    }
    let e = at([1e300, 0.0, 0.0]).validate().unwrap_err();
    assert!(e.contains("1e300 is implausible"), "{e}");
    // a rotary angle many turns from zero is a position an unlimited axis can have
    let o = RewriteOptions {
        start_rotary_deg: Some([0.0, 0.0, 1e6]),
        ..RewriteOptions::default()
    };
    assert!(o.validate().is_ok());
}
