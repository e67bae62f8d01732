//! Direction-dependent tables of an ISO 230-2 run, every format against a file worked by hand
//! from its documentation, and the LinuxCNC loader's rules.
//!
//! The run (5 targets, 2 runs each way; deviation = position reached − target, µm):
//!
//! | target mm | ↑ runs     | x̄↑   | ↓ runs     | x̄↓   | c↑ = −x̄↑ | c↓ = −x̄↓ |
//! |-----------|------------|------|------------|------|----------|----------|
//! | 0         | 1, 2       | 1.5  | 4, 5       | 4.5  | −1.5     | −4.5     |
//! | 50        | 3, 4       | 3.5  | 6, 7       | 6.5  | −3.5     | −6.5     |
//! | 100       | −2, −1     | −1.5 | 0, 1       | 0.5  | 1.5      | −0.5     |
//! | 150       | −5, −4     | −4.5 | −3, −2     | −2.5 | 4.5      | 2.5      |
//! | 200       | 0, 1       | 0.5  | 2, 3       | 2.5  | −0.5     | −2.5     |
//!
//! The means are computed here by hand (ISO 230-2:2014 3.3.1, x̄ = Σx/n) and handed to the
//! profile; the workflow test `compensate_table_iso230_2.rs` takes them from the run file.

use mtec_comp::table::bidirectional::BidirectionalProfile;
use mtec_comp::table::{beckhoff, fanuc, heidenhain, linuxcnc, sinumerik, Axis, TableError};

const TARGETS: [f64; 5] = [0.0, 50.0, 100.0, 150.0, 200.0];
const UP: [[f64; 2]; 5] = [
    [1.0, 2.0],
    [3.0, 4.0],
    [-2.0, -1.0],
    [-5.0, -4.0],
    [0.0, 1.0],
];
const DOWN: [[f64; 2]; 5] = [[4.0, 5.0], [6.0, 7.0], [0.0, 1.0], [-3.0, -2.0], [2.0, 3.0]];

fn profile() -> BidirectionalProfile {
    let mean = |r: &[[f64; 2]; 5]| -> Vec<f64> { r.iter().map(|v| (v[0] + v[1]) / 2.0).collect() };
    let (up, down) = (mean(&UP), mean(&DOWN));
    assert_eq!(up, [1.5, 3.5, -1.5, -4.5, 0.5]);
    assert_eq!(down, [4.5, 6.5, 0.5, -2.5, 2.5]);
    BidirectionalProfile::from_mean_deviations(Axis::X, TARGETS.to_vec(), &up, &down, 500.0)
        .unwrap()
}

#[test]
fn linuxcnc_type_1_trims_and_type_0_actual_positions() {
    // type 1 (ini-config, [JOINT_n] COMP_FILE_TYPE): `nominal forward-trim reverse-trim`, the
    // trims c↑, c↓ in mm (control.c adds fwd_trim while moving +, rev_trim while moving −)
    assert_eq!(
        linuxcnc::write_bidirectional(&profile(), 1).unwrap(),
        "0.000000 -0.001500 -0.004500\n\
         50.000000 -0.003500 -0.006500\n\
         100.000000 0.001500 -0.000500\n\
         150.000000 0.004500 0.002500\n\
         200.000000 -0.000500 -0.002500\n"
    );
    // type 0: the actual positions reached, nominal + x̄ (LinuxCNC trims nominal − actual)
    assert_eq!(
        linuxcnc::write_bidirectional(&profile(), 0).unwrap(),
        "0.000000 0.001500 0.004500\n\
         50.000000 50.003500 50.006500\n\
         100.000000 99.998500 100.000500\n\
         150.000000 149.995500 149.997500\n\
         200.000000 200.000500 200.002500\n"
    );
}

#[test]
fn linuxcnc_reader_rules_are_enforced() {
    // 257 targets: one more than EMCMOT_COMP_SIZE (256)
    let n = 257;
    let p = BidirectionalProfile::from_mean_deviations(
        Axis::X,
        (0..n).map(|i| i as f64).collect(),
        &vec![0.0; n],
        &vec![1.0; n],
        500.0,
    )
    .unwrap();
    let e = linuxcnc::write_bidirectional(&p, 1)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("257 targets") && e.contains("at most 256"),
        "{e}"
    );
    // 256 are accepted
    let p256 = BidirectionalProfile::from_mean_deviations(
        Axis::X,
        (0..256).map(|i| i as f64).collect(),
        &[0.0; 256],
        &[1.0; 256],
        500.0,
    )
    .unwrap();
    assert_eq!(
        linuxcnc::write_bidirectional(&p256, 1)
            .unwrap()
            .lines()
            .count(),
        256
    );
    // two targets 0.1 nm apart: increasing as numbers, equal at the file's 6 decimals
    let p = BidirectionalProfile::from_mean_deviations(
        Axis::X,
        vec![1.0000001, 1.0000002, 2.0],
        &[0.0; 3],
        &[0.0; 3],
        500.0,
    )
    .unwrap();
    let e = linuxcnc::write_bidirectional(&p, 1).unwrap_err();
    assert!(
        matches!(&e, TableError::Constraint { line: Some(2), message, .. } if message.contains("does not increase")),
        "{e}"
    );
    // and the checker on a hand-made file
    assert!(linuxcnc::check("0 0 0\n10 0 0\n10 0 0\n").is_err());
    assert!(linuxcnc::check("0 0 0\n10 0 0\n5 0 0\n").is_err());
    // a correction beyond the bound is refused, naming the target
    let e = linuxcnc::write_bidirectional(&profile().with_max_correction_um(6.0), 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("X = 50 mm") && e.contains("-6.500 um"), "{e}");
}

#[test]
fn sinumerik_cec_two_tables_one_per_direction() {
    // K3 4.4: $AN_CEC_DIRECTION 1 = positive traversing direction only, -1 = negative only;
    // basic axis = compensation axis; values added to the setpoint (c), mm
    let expect = "%_N_NC_CEC_INI\nCHANDATA(1)\n\
        ; table 0: travel in + (_DIRECTION 1), table 1: travel in - (_DIRECTION -1)\n\
        $AN_CEC[0,0]=-0.0015\n$AN_CEC[0,1]=-0.0035\n$AN_CEC[0,2]=0.0015\n\
        $AN_CEC[0,3]=0.0045\n$AN_CEC[0,4]=-0.0005\n\
        $AN_CEC_INPUT_AXIS[0]=(AX1)\n$AN_CEC_OUTPUT_AXIS[0]=(AX1)\n\
        $AN_CEC_STEP[0]=50.0\n$AN_CEC_MIN[0]=0.0\n$AN_CEC_MAX[0]=200.0\n\
        $AN_CEC_DIRECTION[0]=1\n$AN_CEC_MULT_BY_TABLE[0]=0\n$AN_CEC_IS_MODULO[0]=0\n\
        $AN_CEC[1,0]=-0.0045\n$AN_CEC[1,1]=-0.0065\n$AN_CEC[1,2]=-0.0005\n\
        $AN_CEC[1,3]=0.0025\n$AN_CEC[1,4]=-0.0025\n\
        $AN_CEC_INPUT_AXIS[1]=(AX1)\n$AN_CEC_OUTPUT_AXIS[1]=(AX1)\n\
        $AN_CEC_STEP[1]=50.0\n$AN_CEC_MIN[1]=0.0\n$AN_CEC_MAX[1]=200.0\n\
        $AN_CEC_DIRECTION[1]=-1\n$AN_CEC_MULT_BY_TABLE[1]=0\n$AN_CEC_IS_MODULO[1]=0\n\
        M17\n";
    assert_eq!(
        sinumerik::write_cec_bidirectional(&profile(), &Default::default()).unwrap(),
        expect
    );
    // MD18342 configured for 4 points: refused
    let opts = sinumerik::CecOptions {
        max_points: Some(4),
        ..Default::default()
    };
    assert!(sinumerik::write_cec_bidirectional(&profile(), &opts).is_err());
}

#[test]
fn sinumerik_lec_refuses_a_reversal_it_cannot_hold() {
    let e = sinumerik::write_lec_bidirectional(&profile(), &Default::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("at 0 mm") && e.contains("sinumerik-cec"), "{e}");
    // no reversal: the one table (LEC holds e = −c)
    let same = BidirectionalProfile::from_mean_deviations(
        Axis::X,
        TARGETS.to_vec(),
        &[1.5, 3.5, -1.5, -4.5, 0.5],
        &[1.5, 3.5, -1.5, -4.5, 0.5],
        500.0,
    )
    .unwrap();
    let t = sinumerik::write_lec_bidirectional(&same, &Default::default()).unwrap();
    assert!(
        t.contains("$AA_ENC_COMP[0,0,X1]=0.0015\n$AA_ENC_COMP[0,1,X1]=0.0035\n"),
        "{t}"
    );
}

#[test]
fn fanuc_bidirectional_tape() {
    // reference at 0 mm = point 0 (3620), interval 50 mm = 50000 detection units of 1 um.
    // + direction, relative to c↑(0) = −1.5: C = 0, −2, 3, 6, 1 → increments (point 0 = the
    //   interval before the table, 0) 0, −2, 5, 3, −5 on points 0..4
    // − direction: 3626 = 5 (after the + points), 3627 = c↓(0) − c↑(0) = −4.5 + 1.5 = −3;
    //   C↓ = c↓ − c↓(0) = 0, −2, 4, 7, 2 → increments 0, −2, 6, 3, −5 on points 5..9
    // check: at 200 mm moving −: 3627 + Σ = −3 + 2 = −1 = c↓(200) − c↑(0) = −2.5 + 1.5
    let expect = "%\nN03620A1P0\nN03621A1P0\nN03622A1P4\nN03623A1P1\nN03624A1P50000\n\
        N03626A1P5\nN03627A1P-3\n\
        N10000P0\nN10001P-2\nN10002P5\nN10003P3\nN10004P-5\n\
        N10005P0\nN10006P-2\nN10007P6\nN10008P3\nN10009P-5\n%\n";
    assert_eq!(
        fanuc::write_bidirectional(&profile(), &Default::default()).unwrap(),
        expect
    );
    // the increment limit still holds: ±5 per point at most refuses the 6
    let opts = fanuc::FanucOptions {
        max_increment: 5,
        ..Default::default()
    };
    let e = fanuc::write_bidirectional(&profile(), &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("value 6 exceeds ±5"), "{e}");
    // negative points overlapping the positive ones are refused
    let opts = fanuc::FanucOptions {
        reverse_first_number: Some(3),
        ..Default::default()
    };
    assert!(fanuc::write_bidirectional(&profile(), &opts).is_err());
    // unequal spacing cannot be a FANUC table
    let uneven = BidirectionalProfile::from_mean_deviations(
        Axis::X,
        vec![0.0, 50.0, 120.0],
        &[0.0; 3],
        &[0.0; 3],
        500.0,
    )
    .unwrap();
    assert!(fanuc::write_bidirectional(&uneven, &Default::default()).is_err());
}

#[test]
fn heidenhain_com_with_backlash_column() {
    // AXISPOS, the axis column = error measured moving + (x̄↑), BACKLASH = error measured
    // moving − (x̄↓), mm with 4 decimals
    let t = heidenhain::write_bidirectional(&profile(), "X.COM", "config.cma").unwrap();
    let expect = "BEGIN X.COM MM\n\
        NR          AXISPOS          X   BACKLASH\n\
        0           +0.0000    +0.0015    +0.0045\n\
        1          +50.0000    +0.0035    +0.0065\n\
        2         +100.0000    -0.0015    +0.0005\n\
        3         +150.0000    -0.0045    -0.0025\n\
        4         +200.0000    +0.0005    +0.0025\n\
        [END]\n";
    assert_eq!(t.com, expect);
    assert!(t.cma.contains("X.COM"));
}

#[test]
fn beckhoff_bilateral_leadscrew_list() {
    // TF5200 "Example of a compensation value list": interval 0 (setpoints given), unit 1,
    // bilateral 1, positions and values in 0.1 um; value = actual − setpoint (the manual's
    // point: 19856.5 − 19866.7 um = −102), i.e. pos = 10·x̄↑, neg = 10·x̄↓
    let t = beckhoff::ssfk::write(&profile(), 1, 1500).unwrap();
    let pairs: Vec<(String, String)> = t
        .lines()
        .map(|l| {
            let mut f = l.split_whitespace();
            (f.next().unwrap().into(), f.next().unwrap().into())
        })
        .collect();
    let mut expect: Vec<(String, String)> = [
        ("kopf.log_achs_nr", "1"),
        ("kopf.log_achs_name", "X"),
        ("kw.ssfk.interval", "0"),
        ("kw.ssfk.kw_startpos", "0"),
        ("kw.ssfk.kw_nr_max", "5"),
        ("kw.ssfk.unit", "1"),
        ("kw.ssfk.bilateral", "1"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    for (field, values) in [
        ("setpoint", ["0", "500000", "1000000", "1500000", "2000000"]),
        ("pos", ["15", "35", "-15", "-45", "5"]),
        ("neg", ["45", "65", "5", "-25", "25"]),
    ] {
        for (i, v) in values.iter().enumerate() {
            expect.push((format!("kw.ssfk.table[{i}].{field}"), v.to_string()));
        }
    }
    assert_eq!(pairs, expect);
    assert!(beckhoff::ssfk::write(&profile(), 1, 4).is_err());
    // a target that is not a whole 0.1 um
    let odd = BidirectionalProfile::from_mean_deviations(
        Axis::X,
        vec![0.0, 50.00005],
        &[0.0; 2],
        &[0.0; 2],
        500.0,
    )
    .unwrap();
    assert!(beckhoff::ssfk::write(&odd, 1, 1500).is_err());
}
