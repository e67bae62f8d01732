//! Golden-file tests of the controller table writers. Each expected text is worked by hand from
//! the format's documentation (cited in each writer's module docs) for the affine test model
//!   ex = 3 + 0.02·x,  ey = −0.01·x + 0.1·z,  ez = 0.004·y   (µm, positions in mm),
//! whose compensation value is c = −e.

use mtec_comp::table::{self, axis_profile, Axis, AxisProfile, TableError};
use mtec_comp::ErrorModel;

struct Affine;
impl ErrorModel for Affine {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        [3.0 + 0.02 * p[0], -0.01 * p[0] + 0.1 * p[2], 0.004 * p[1]]
    }
    fn describe(&self) -> String {
        "affine test model".into()
    }
}

fn profile(input: Axis, output: Axis, from: f64, to: f64, step: f64) -> AxisProfile {
    axis_profile(&Affine, input, output, from, to, step, [0.0; 3]).unwrap()
}

/// LinuxCNC type 1: trims = c; x = 0, 100, 200 → ex = 3, 5, 7 µm → −0.003, −0.005, −0.007 mm.
#[test]
fn linuxcnc_type1_golden() {
    let p = profile(Axis::X, Axis::X, 0.0, 200.0, 100.0);
    let text = table::linuxcnc::write(&p, 1).unwrap();
    assert_eq!(
        text,
        "0.000000 -0.003000 -0.003000\n100.000000 -0.005000 -0.005000\n200.000000 -0.007000 -0.007000\n"
    );
}

/// LinuxCNC type 0: actual positions = nominal + e (the doc's example `-1.000 -1.005 -0.995`).
#[test]
fn linuxcnc_type0_golden() {
    let p = profile(Axis::X, Axis::X, 0.0, 200.0, 100.0);
    let text = table::linuxcnc::write(&p, 0).unwrap();
    assert_eq!(
        text,
        "0.000000 0.003000 0.003000\n100.000000 100.005000 100.005000\n200.000000 200.007000 200.007000\n"
    );
}

#[test]
fn linuxcnc_checker_rules() {
    let err = table::linuxcnc::check("nominal fwd rev\n0 0 0\n").unwrap_err();
    assert!(
        matches!(err, TableError::Constraint { line: Some(1), .. }),
        "{err}"
    );
    let err = table::linuxcnc::check("0 0 0\n0 0 0\n").unwrap_err();
    assert!(err.to_string().contains("does not increase"), "{err}");
    let many: String = (0..257).map(|i| format!("{i} 0 0\n")).collect();
    let err = table::linuxcnc::check(&many).unwrap_err();
    assert!(err.to_string().contains("at most 256"), "{err}");
    let ok: String = (0..256).map(|i| format!("{i} 0 0\n")).collect();
    table::linuxcnc::check(&ok).unwrap();
    // a cross-axis profile cannot become a joint file
    let p = profile(Axis::Y, Axis::Z, -400.0, 400.0, 400.0);
    assert!(table::linuxcnc::write(&p, 1).is_err());
}

/// CEC, Z = F(Y): ez = 0.004·y at y = −400, 0, 400 → c = +1.6, 0, −1.6 µm, added to the Z
/// setpoint; layout as the K3 example (802D sl FM §11.3).
#[test]
fn sinumerik_cec_golden() {
    let p = profile(Axis::Y, Axis::Z, -400.0, 400.0, 400.0);
    let text = table::sinumerik::write_cec(&p, &Default::default()).unwrap();
    assert_eq!(
        text,
        "%_N_NC_CEC_INI
CHANDATA(1)
$AN_CEC[0,0]=0.0016
$AN_CEC[0,1]=0
$AN_CEC[0,2]=-0.0016
$AN_CEC_INPUT_AXIS[0]=(AX2)
$AN_CEC_OUTPUT_AXIS[0]=(AX3)
$AN_CEC_STEP[0]=400.0
$AN_CEC_MIN[0]=-400.0
$AN_CEC_MAX[0]=400.0
$AN_CEC_DIRECTION[0]=0
$AN_CEC_MULT_BY_TABLE[0]=0
$AN_CEC_IS_MODULO[0]=0
M17
"
    );
    let broken = text.replace("$AN_CEC_MAX[0]=400.0", "$AN_CEC_MAX[0]=500.0");
    let err = table::sinumerik::check_cec(&broken, None).unwrap_err();
    assert!(err.to_string().contains("but _MAX is 500"), "{err}");
    let err = table::sinumerik::check_cec(&text, Some(2)).unwrap_err();
    assert!(err.to_string().contains("at most 2"), "{err}");
}

/// LEC, X: x = −200, 200, 600 → ex = −1, 7, 15 µm. A positive LEC value moves the axis
/// negative, so the value is +e: −0.001, 0.007, 0.015 mm (the K3 example's layout).
#[test]
fn sinumerik_lec_golden() {
    let p = profile(Axis::X, Axis::X, -200.0, 600.0, 400.0);
    let text = table::sinumerik::write_lec(&p, &Default::default()).unwrap();
    assert_eq!(
        text,
        "%_N_AX_EEC_INI
CHANDATA(1)
$AA_ENC_COMP[0,0,X1]=-0.001
$AA_ENC_COMP[0,1,X1]=0.007
$AA_ENC_COMP[0,2,X1]=0.015
$AA_ENC_COMP_STEP[0,X1]=400.0
$AA_ENC_COMP_MIN[0,X1]=-200.0
$AA_ENC_COMP_MAX[0,X1]=600.0
$AA_ENC_COMP_IS_MODULO[0,X1]=0
M17
"
    );
    let broken = text.replace("$AA_ENC_COMP[0,2,X1]", "$AA_ENC_COMP[0,3,X1]");
    assert!(table::sinumerik::check_lec(&broken, None).is_err());
}

/// FANUC, X: x = −100, 0, 100, 200, reference at 0 = point 40. c = −1, −3, −5, −7 µm;
/// relative to the reference: +2, 0, −2, −4; increments over the intervals ending at 0, 100,
/// 200: −2, −2, −2 at points 40, 41, 42 (point R holds the interval ending at the reference).
#[test]
fn fanuc_linear_golden() {
    let p = profile(Axis::X, Axis::X, -100.0, 200.0, 100.0);
    let opts = table::fanuc::FanucOptions {
        reference_number: 40,
        ..Default::default()
    };
    let text = table::fanuc::write(&p, &opts).unwrap();
    assert_eq!(
        text,
        "%
N03620A1P40
N03621A1P40
N03622A1P42
N03623A1P1
N03624A1P100000
N10040P-2
N10041P-2
N10042P-2
%
"
    );
    // magnification 2: units of 2 µm: relative +1, 0, −1, −2 → increments −1, −1, −1
    let opts2 = table::fanuc::FanucOptions {
        reference_number: 40,
        magnification: 2,
        ..Default::default()
    };
    let text2 = table::fanuc::write(&p, &opts2).unwrap();
    assert!(
        text2.contains("N03623A1P2\n") && text2.contains("N10041P-1\n"),
        "{text2}"
    );
    // reference at the − end (x = −100, point 0): 3621 = 3620 = 0 and point 0 holds 0;
    // relative to c(−100) = −1: 0, −2, −4, −6 → increments −2 at points 1, 2, 3
    let at_start = table::fanuc::FanucOptions {
        reference_mm: -100.0,
        ..Default::default()
    };
    assert_eq!(
        table::fanuc::write(&p, &at_start).unwrap(),
        "%\nN03620A1P0\nN03621A1P0\nN03622A1P3\nN03623A1P1\nN03624A1P100000\nN10000P0\nN10001P-2\nN10002P-2\nN10003P-2\n%\n"
    );
    // values beyond the range are refused
    let tight = table::fanuc::FanucOptions {
        reference_number: 40,
        max_increment: 1,
        ..Default::default()
    };
    assert!(table::fanuc::write(&p, &tight).is_err());
}

/// FANUC rotary axis (parameter manual example 2 pattern): one turn in 4 intervals of 90°,
/// reference number 60 → points 60..64, values 61..64 sum to zero, point 60 repeats point 64.
#[test]
fn fanuc_rotary_golden_and_sum_rule() {
    let p = AxisProfile {
        input_axis: Axis::Z,
        output_axis: Axis::Z,
        start_mm: 0.0,
        step_mm: 90.0,
        comp_um: vec![0.0, 3.0, 1.0, -2.0, 0.0],
        rotary: true,
        max_correction_um: table::DEFAULT_MAX_CORRECTION_UM,
        at_mm: [0.0; 3],
    };
    let opts = table::fanuc::FanucOptions {
        axis_number: 4,
        reference_number: 60,
        ..Default::default()
    };
    let text = table::fanuc::write(&p, &opts).unwrap();
    assert_eq!(
        text,
        "%
N03620A4P60
N03621A4P60
N03622A4P64
N03623A4P1
N03624A4P90000
N03625A4P360000
N10060P2
N10061P3
N10062P-2
N10063P-3
N10064P2
%
"
    );
    let open = AxisProfile {
        comp_um: vec![0.0, 3.0, 1.0, -2.0, 1.0],
        ..p
    };
    let err = table::fanuc::write(&open, &opts).unwrap_err();
    assert!(err.to_string().contains("sum to 1"), "{err}");
}

/// HEIDENHAIN: Z = F(Y), the .COM has AXISPOS (Y positions) and a Z column with the axis error
/// (ez = 0.004·y: −1.6, 0, +1.6 µm); the .CMA enters ZY.COM in the column of Y (the axis it depends on) and marks the line
/// active with `*`.
#[test]
fn heidenhain_golden() {
    let p = profile(Axis::Y, Axis::Z, -400.0, 400.0, 400.0);
    let t = table::heidenhain::write(&p, "ZY.COM", "CONFIG.CMA").unwrap();
    let words: Vec<Vec<&str>> = t
        .com
        .lines()
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(
        words,
        vec![
            vec!["BEGIN", "ZY.COM", "MM"],
            vec!["NR", "AXISPOS", "Z"],
            vec!["0", "-400.0000", "-0.0016"],
            vec!["1", "+0.0000", "+0.0000"],
            vec!["2", "+400.0000", "+0.0016"],
            vec!["[END]"],
        ]
    );
    assert_eq!(
        t.cma,
        "BEGIN CONFIG.CMA
NR    X            Y            Z            ACTIVE
0                  ZY.COM                    *
[END]
"
    );
    let long: String = format!(
        "BEGIN A.COM MM\nNR AXISPOS X\n{}[END]\n",
        (0..257)
            .map(|i| format!("{i} {i}.0 0\n"))
            .collect::<String>()
    );
    let err = table::heidenhain::check_com(&long).unwrap_err();
    assert!(err.to_string().contains("at most 256"), "{err}");
}

/// Beckhoff ISG CSV: X Y Z arguments, EXX EYY EZZ = the error field in mm, x slowest.
#[test]
fn beckhoff_golden() {
    let axes = [vec![0.0, 100.0], vec![0.0], vec![0.0, 50.0]];
    let text = table::beckhoff::write(&Affine, &axes, "test model", 500.0).unwrap();
    assert_eq!(
        text,
        "// volumetric error map written by mtec (TF5280 ISG CSV format)
// test model
// arguments X Y Z in mm; EXX EYY EZZ = volumetric error ex ey ez of the tool tip in mm
X Y Z EXX EYY EZZ
0.0 0.0 0.0 0.003000 0.000000 0.000000
0.0 0.0 50.0 0.003000 0.005000 0.000000
100.0 0.0 0.0 0.005000 -0.001000 0.000000
100.0 0.0 50.0 0.005000 0.004000 0.000000
"
    );
    let missing = text.replace("100.0 0.0 50.0 0.005000 0.004000 0.000000\n", "");
    let err = table::beckhoff::check(&missing).unwrap_err();
    assert!(err.to_string().contains("complete grid"), "{err}");
}

/// Issue 15, defect 7: a constant error of `e_um` on every axis (a model in the wrong units, a
/// broken fit).
struct Constant(f64);
impl ErrorModel for Constant {
    fn error_um(&self, _p: [f64; 3]) -> [f64; 3] {
        [self.0; 3]
    }
    fn describe(&self) -> String {
        format!("constant {} um", self.0)
    }
}

/// Every writer's output for a constant model of `e_um`, sampled along X over 0..200 step 100
/// (FANUC with its reference at 0, Heidenhain as Z = F(X), Beckhoff on a 2×1×1 grid).
fn every_writer(e_um: f64) -> Vec<(&'static str, Result<String, TableError>)> {
    let m = Constant(e_um);
    let p = |out: Axis| {
        axis_profile(&m, Axis::X, out, 0.0, 200.0, 100.0, [0.0, 10.0, 20.0])
            .map(|p| p.with_max_correction_um(table::DEFAULT_MAX_CORRECTION_UM))
    };
    let b = || p(Axis::X);
    vec![
        (
            "linuxcnc 1",
            b().and_then(|p| table::linuxcnc::write(&p, 1)),
        ),
        (
            "linuxcnc 0",
            b().and_then(|p| table::linuxcnc::write(&p, 0)),
        ),
        (
            "sinumerik-cec",
            p(Axis::Y).and_then(|p| table::sinumerik::write_cec(&p, &Default::default())),
        ),
        (
            "sinumerik-lec",
            b().and_then(|p| table::sinumerik::write_lec(&p, &Default::default())),
        ),
        (
            "fanuc",
            b().and_then(|p| table::fanuc::write(&p, &Default::default())),
        ),
        (
            "heidenhain",
            p(Axis::Z).and_then(|p| table::heidenhain::write(&p, "ZX.COM", "C.CMA").map(|t| t.com)),
        ),
        (
            "beckhoff",
            table::beckhoff::write(
                &m,
                &[vec![0.0, 100.0], vec![0.0], vec![0.0]],
                "test",
                table::DEFAULT_MAX_CORRECTION_UM,
            ),
        ),
    ]
}

#[test]
fn every_writer_refuses_a_10_mm_correction() {
    for (name, r) in every_writer(10_000.0) {
        let err = r.expect_err(name);
        let msg = err.to_string();
        assert!(matches!(err, TableError::TooLarge { .. }), "{name}: {msg}");
        assert!(msg.contains("-10000.000 um"), "{name}: {msg}");
        assert!(msg.contains("--max-correction-um 500"), "{name}: {msg}");
        // the position: the first table point, x = 0 (y = 10, z = 20 for the 1-D tables)
        if name == "beckhoff" {
            assert!(msg.contains("machine point 0, 0, 0 mm"), "{name}: {msg}");
            assert!(msg.contains("17320.5"), "{name}: vector length: {msg}");
        } else {
            assert!(msg.contains("table position X = 0 mm"), "{name}: {msg}");
            assert!(msg.contains("machine point 0, 10, 20 mm"), "{name}: {msg}");
        }
    }
}

#[test]
fn every_writer_refuses_a_1e297_correction() {
    for (name, r) in every_writer(1e297) {
        let err = r.expect_err(name);
        let msg = err.to_string();
        assert!(matches!(err, TableError::TooLarge { .. }), "{name}: {msg}");
        assert!(msg.contains("-1e297 um"), "{name}: {msg}");
    }
}

#[test]
fn every_writer_refuses_an_infinite_correction() {
    for (name, r) in every_writer(f64::INFINITY) {
        let err = r.expect_err(name);
        assert!(
            err.to_string().contains("not a finite number"),
            "{name}: {err}"
        );
    }
}

/// Just under the bound every writer writes its table (the Beckhoff vector: 288 um per axis is
/// 498.8 um long).
#[test]
fn every_writer_writes_a_correction_just_under_the_bound() {
    for (name, r) in every_writer(499.9) {
        if name == "beckhoff" {
            continue;
        }
        let text = r.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!text.is_empty(), "{name}");
    }
    let lin = every_writer(499.9).remove(0).1.unwrap();
    assert!(lin.starts_with("0.000000 -0.499900 -0.499900\n"), "{lin}");
    let m = Constant(288.0);
    table::beckhoff::write(&m, &[vec![0.0, 100.0], vec![0.0], vec![0.0]], "t", 500.0).unwrap();
    let err = table::beckhoff::write(
        &Constant(289.0),
        &[vec![0.0], vec![0.0], vec![0.0]],
        "t",
        500.0,
    )
    .unwrap_err();
    assert!(err.to_string().contains("500.56"), "{err}");
}

/// The bound is the caller's: raised to its largest (10 mm), a 10 mm table is written, beyond
/// that the bound is refused; a profile built by hand is held to it too; a bound that is not a
/// positive number is refused.
#[test]
fn the_bound_is_an_option_and_holds_for_hand_built_profiles() {
    let m = Constant(10_000.0);
    let p = axis_profile(&m, Axis::X, Axis::X, 0.0, 100.0, 100.0, [0.0; 3]).unwrap();
    let wide = p.clone().with_max_correction_um(10_000.0);
    assert!(table::linuxcnc::write(&wide, 1)
        .unwrap()
        .starts_with("0.000000 -10.000000 -10.000000\n"));
    let beyond = p.clone().with_max_correction_um(20_000.0);
    let err = table::linuxcnc::write(&beyond, 1).unwrap_err();
    assert!(err.to_string().contains("at most 10000 um"), "{err}");
    let by_hand = AxisProfile {
        comp_um: vec![0.0, 600.0],
        ..p.with_max_correction_um(500.0)
    };
    let err = table::linuxcnc::write(&by_hand, 1).unwrap_err();
    assert!(
        err.to_string().contains("table position X = 100 mm"),
        "{err}"
    );
    let nan_limit = by_hand.with_max_correction_um(f64::NAN);
    let err = table::sinumerik::write_lec(&nan_limit, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("positive number"), "{err}");
}

/// One rule for tables and programs: the default bound of `compensate table` is the one of
/// `compensate gcode`.
#[test]
fn the_table_bound_defaults_to_the_gcode_bound() {
    assert_eq!(
        table::DEFAULT_MAX_CORRECTION_UM,
        mtec_comp::gcode::RewriteOptions::default().max_correction_um
    );
}
