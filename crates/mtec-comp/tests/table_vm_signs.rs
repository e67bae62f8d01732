//! Sign conventions end to end, against the virtual machine: tables written from a map of the
//! `volumetric-grid` scenario are applied the way each controller documents (LinuxCNC adds the
//! trim to the joint command; a positive Siemens LEC value moves the axis negative; a CEC value
//! is added to the compensation axis; FANUC adds the accumulated increments from the reference
//! point), and must remove most of the true error along the table's line. A sign slip in any
//! writer turns the compensation rate negative.

use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_comp::table::{self, axis_profile, Axis};
use mtec_io::Table;
use mtec_model::{Machine, VolumetricModel};
use mtec_sim::instruments::exact_error_um;
use mtec_sim::truth::geometric_truth;
use std::path::Path;

const SEED: u64 = 5;

struct Setup {
    map: GridMap,
    vm: VolumetricModel,
    x_range: (f64, f64),
    at: [f64; 3],
}

fn setup() -> Setup {
    let out = mtec_sim::run_scenario("volumetric-grid", SEED).unwrap();
    let f = out.files.iter().find(|f| f.name == "grid.csv").unwrap();
    let t = Table::parse(Path::new("grid.csv"), &f.contents).unwrap();
    let map = GridMap::from_table(&t, &GridLimits::default(), Outside::Clamp).unwrap();
    let machine = Machine::vmc_xyfz(100.0);
    let vm = VolumetricModel::new(&machine, &geometric_truth(&machine, SEED));
    let ax = map.axes_mm().clone();
    let mid = |k: usize| ax[k][ax[k].len() / 2]; // a grid line through the middle
    Setup {
        x_range: (ax[0][0], ax[0][ax[0].len() - 1]),
        at: [mid(0), mid(1), mid(2)],
        map,
        vm,
    }
}

/// Linear interpolation in a table of (position, value) pairs (what the controllers do).
fn lerp(table: &[(f64, f64)], x: f64) -> f64 {
    let i = table
        .windows(2)
        .position(|w| x <= w[1].0)
        .unwrap_or(table.len() - 2);
    let (a, b) = (table[i], table[i + 1]);
    a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0)
}

/// Compensation rate of `axis_out`'s error along X when the command of `axis_out` is moved by
/// `shift_mm(x)`.
fn rate(s: &Setup, axis_out: usize, shift_mm: impl Fn(f64) -> f64) -> f64 {
    let (mut ss0, mut ss1) = (0.0, 0.0);
    for k in 0..=97 {
        let x = s.x_range.0 + (s.x_range.1 - s.x_range.0) * k as f64 / 97.0;
        let t = [x, s.at[1], s.at[2]];
        let before = exact_error_um(&s.vm, &t)[axis_out];
        let mut q = t;
        q[axis_out] += shift_mm(x);
        let after = (q[axis_out] - t[axis_out]) * 1e3 + exact_error_um(&s.vm, &q)[axis_out];
        ss0 += before * before;
        ss1 += after * after;
    }
    1.0 - (ss1 / ss0).sqrt()
}

fn numbers(line: &str) -> Vec<f64> {
    line.split_whitespace()
        .map(|f| f.parse().unwrap())
        .collect()
}

fn step(s: &Setup) -> f64 {
    let ax = &s.map.axes_mm()[0];
    ax[1] - ax[0]
}

#[test]
fn linuxcnc_trims_and_actual_positions_compensate() {
    let s = setup();
    let p = axis_profile(
        &s.map,
        Axis::X,
        Axis::X,
        s.x_range.0,
        s.x_range.1,
        step(&s),
        s.at,
    )
    .unwrap();
    // type 1: trim added to the joint command
    let t1: Vec<(f64, f64)> = table::linuxcnc::write(&p, 1)
        .unwrap()
        .lines()
        .map(|l| {
            let v = numbers(l);
            (v[0], v[1])
        })
        .collect();
    let r1 = rate(&s, 0, |x| lerp(&t1, x));
    // type 0: LinuxCNC converts to trims as nominal − actual (usrmotLoadComp)
    let t0: Vec<(f64, f64)> = table::linuxcnc::write(&p, 0)
        .unwrap()
        .lines()
        .map(|l| {
            let v = numbers(l);
            (v[0], v[0] - v[1])
        })
        .collect();
    let r0 = rate(&s, 0, |x| lerp(&t0, x));
    eprintln!("LinuxCNC type 1 rate {r1:.3}, type 0 rate {r0:.3}");
    assert!(r1 > 0.8 && r0 > 0.8, "{r1} {r0}");
}

fn siemens_values(text: &str, prefix: &str) -> Vec<f64> {
    text.lines()
        .filter(|l| l.starts_with(prefix))
        .map(|l| l.split('=').nth(1).unwrap().parse().unwrap())
        .collect()
}

#[test]
fn siemens_lec_moves_negative_and_cec_adds() {
    let s = setup();
    let st = step(&s);
    let p = axis_profile(&s.map, Axis::X, Axis::X, s.x_range.0, s.x_range.1, st, s.at).unwrap();
    let lec = table::sinumerik::write_lec(&p, &Default::default()).unwrap();
    let v = siemens_values(&lec, "$AA_ENC_COMP[");
    let tab: Vec<(f64, f64)> = v
        .iter()
        .enumerate()
        .map(|(i, &c)| (p.position(i), c))
        .collect();
    // a positive value moves the axis negative
    let r_lec = rate(&s, 0, |x| -lerp(&tab, x));
    // CEC: Y error as a function of X, value added to Y
    let py = axis_profile(&s.map, Axis::X, Axis::Y, s.x_range.0, s.x_range.1, st, s.at).unwrap();
    let cec = table::sinumerik::write_cec(&py, &Default::default()).unwrap();
    let v = siemens_values(&cec, "$AN_CEC[");
    let tab: Vec<(f64, f64)> = v
        .iter()
        .enumerate()
        .map(|(i, &c)| (py.position(i), c))
        .collect();
    let r_cec = rate(&s, 1, |x| lerp(&tab, x));
    eprintln!("Siemens LEC rate {r_lec:.3}, CEC (Y = f(X)) rate {r_cec:.3}");
    assert!(r_lec > 0.8 && r_cec > 0.8, "{r_lec} {r_cec}");
}

#[test]
fn fanuc_increments_accumulate_to_the_compensation() {
    let s = setup();
    let st = step(&s);
    let p = axis_profile(&s.map, Axis::X, Axis::X, s.x_range.0, s.x_range.1, st, s.at).unwrap();
    let opts = table::fanuc::FanucOptions {
        reference_mm: p.start_mm,
        reference_number: 0,
        ..Default::default()
    };
    let tape = table::fanuc::write(&p, &opts).unwrap();
    // points 1..n hold the increments of the intervals after the reference (point 0 holds the
    // interval ending at it): the compensation at x_j is the sum of increments up to point j
    let mut incs: Vec<(i64, f64)> = tape
        .lines()
        .filter(|l| l.starts_with("N1"))
        .map(|l| {
            let (n, v) = l[1..].split_once('P').unwrap();
            (n.parse::<i64>().unwrap() - 10000, v.parse::<f64>().unwrap())
        })
        .collect();
    incs.sort_by_key(|x| x.0);
    let mut acc_um = 0.0;
    let mut tab = vec![(p.start_mm, 0.0)];
    for (n, v) in incs.iter().filter(|x| x.0 >= 1) {
        acc_um += v; // detection unit 1 µm, magnification 1
        tab.push((p.start_mm + st * *n as f64, acc_um * 1e-3));
    }
    // the controller compensates relative to the reference point: add the map's correction there
    let c_ref_mm = p.comp_um[0] * 1e-3;
    let r = rate(&s, 0, |x| lerp(&tab, x) + c_ref_mm);
    eprintln!("FANUC rate {r:.3} (1 um rounding)");
    assert!(r > 0.8, "{r}");
}
