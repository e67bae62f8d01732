//! An independent exact forward model of the 9-line measurement (issue 19), written from the
//! equations of docs/methods.md §1 and §3 with its own 3-vector arithmetic: nothing of
//! `mtec-model`'s kinematics (HTM, POE, Jacobian) is used, only the truth's function values.
//! If a sign or an order convention were wrong in `mtec-model`, the simulator (which reads the
//! machine through it) and the identification (which linearises it) could agree with each
//! other and both be wrong; this model would not agree with them.
//!
//! The XYFZ machine (chain WXYFZT; X carries the workpiece on Y on the frame; Z carries the
//! tool), moving error frame, carriage reference points at the machine zero, tool offset
//! t = (0, 0, L). Conventions (docs/methods.md §1, written down by issue 19):
//! - ideal motion: the table axes move the workpiece by −x·x̂ and −y·d_Y, the tool-side Z moves
//!   the tool by +z·d_Z, with d_Y = Rz(EC0Y)·ŷ and d_Z = Ry(EB0Z)·Rx(EA0Z)·ẑ (the A rotation first,
//!   then B): to first order d_Z = (EB0Z, −EA0Z, 1), so EB0Z > 0 leans Z toward +X and
//!   EA0Z > 0 leans it toward −Y;
//! - each carriage's error motion after its ideal motion: E = Trans(δ)·Rz(εz)·Ry(εy)·Rx(εx);
//! - tool tip relative to the workpiece: P = A_X⁻¹·A_Y⁻¹·A_Z·t, A⁻¹p = Rᵀ(M⁻¹p − δ);
//! - readings at the tool tip *including* the tool offset L (the laser's retro-reflector sits
//!   at the tool point), relative to the line's first point: r_k = u·(E(q_k) − E(q_0));
//! - every line has a displacement channel and both straightness channels.

use mtec_model::{line_preset, ErrorElement, ErrorSet, Machine};
use mtec_sim::instruments::LaserInterferometer;
use mtec_sim::realistic_truth::realistic_truth;
use mtec_sim::vmc_9line::{machine_with_leads, measure_lines, TOOL_LENGTH_MM};

type V = [f64; 3];
type M = [[f64; 3]; 3];

fn mul(a: &M, v: V) -> V {
    [0, 1, 2].map(|i| a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2])
}
fn mt(a: &M, v: V) -> V {
    [0, 1, 2].map(|i| a[0][i] * v[0] + a[1][i] * v[1] + a[2][i] * v[2])
}
fn mm(a: &M, b: &M) -> M {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}
fn rx(t: f64) -> M {
    let (s, c) = t.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}
fn ry(t: f64) -> M {
    let (s, c) = t.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}
fn rz(t: f64) -> M {
    let (s, c) = t.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V, s: f64) -> V {
    a.map(|v| v * s)
}

/// (δ in mm, R) of an axis' error motion at position q.
fn error_motion(t: &ErrorSet, axis: char, q: f64) -> (V, M) {
    let v = |d: char| t.value(&ErrorElement::parse(&format!("E{d}{axis}")).unwrap(), q);
    let delta = [v('X'), v('Y'), v('Z')].map(|u| u * 1e-3);
    let (a, b, c) = (v('A') * 1e-6, v('B') * 1e-6, v('C') * 1e-6);
    (delta, mm(&rz(c), &mm(&ry(b), &rx(a))))
}

/// Exact tool-tip error (µm) at commanded (x, y, z).
fn error_um(t: &ErrorSet, l: f64, p: V) -> V {
    let sq = |n: &str| t.value(&ErrorElement::parse(n).unwrap(), 0.0) * 1e-6;
    let d_y = mul(&rz(sq("EC0Y")), [0.0, 1.0, 0.0]);
    let d_z = mul(&mm(&ry(sq("EB0Z")), &rx(sq("EA0Z"))), [0.0, 0.0, 1.0]);
    let [x, y, z] = p;
    // Z on the frame: A_Z·t = z·d_Z + δ_Z + R_Z·t
    let (dz, r_z) = error_motion(t, 'Z', z);
    let mut q = add(add(scale(d_z, z), dz), mul(&r_z, [0.0, 0.0, l]));
    // A_Y⁻¹: M_Y = Trans(−y·d_Y), so M_Y⁻¹p = p + y·d_Y; then E_Y⁻¹
    let (dy, r_y) = error_motion(t, 'Y', y);
    q = mt(&r_y, sub(add(q, scale(d_y, y)), dy));
    let (dx, r_x) = error_motion(t, 'X', x);
    q = mt(&r_x, sub(add(q, [x, 0.0, 0.0]), dx));
    let ideal = [x, y, z + l];
    sub(q, ideal).map(|v| v * 1e3)
}

#[test]
fn simulator_readings_equal_the_independent_model() {
    let m: Machine = machine_with_leads();
    let truth = realistic_truth(&m, 4);
    let lines = line_preset("nine-line", &m, 20, 10.0).unwrap();
    for l in &lines {
        // every axial line has its displacement and both straightness channels
        if l.direction().iter().filter(|v| v.abs() > 1e-9).count() == 1 {
            assert_eq!(l.channels.len(), 3, "line {}", l.name);
        }
    }
    let laser = LaserInterferometer {
        noise_um: 0.0,
        straightness_noise_um: 0.0,
        alignment_urad: 0.0,
    };
    let (csv, _) = measure_lines(&m, &truth, &lines, &laser, 4);
    let mut worst: f64 = 0.0;
    let mut worst_without_tool: f64 = 0.0;
    let mut n = 0;
    let mut first: std::collections::HashMap<String, (V, V)> = Default::default();
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let v: Vec<f64> = f[2..].iter().map(|s| s.parse().unwrap()).collect();
        let (p, u, reading) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]], v[6]);
        let e = error_um(&truth, TOOL_LENGTH_MM, p);
        let e_no_tool = error_um(&truth, 0.0, p);
        let (e0, e0n) = *first.entry(f[0].to_string()).or_insert((e, e_no_tool));
        let dot = |a: V| u[0] * a[0] + u[1] * a[1] + u[2] * a[2];
        worst = worst.max((dot(sub(e, e0)) - reading).abs());
        worst_without_tool = worst_without_tool.max((dot(sub(e_no_tool, e0n)) - reading).abs());
        n += 1;
    }
    println!("{n} readings: worst difference {worst:.2e} um (without the tool offset: {worst_without_tool:.3} um)");
    // the CSV has 4 decimals
    assert!(worst < 1.5e-4, "{worst}");
    // and the check is sensitive: leaving out the tool offset is visible
    assert!(worst_without_tool > 0.05, "{worst_without_tool}");
}

/// Each squareness sign on its own, against the first-order reading it must give.
#[test]
fn squareness_signs_are_the_documented_ones() {
    let m = Machine::vmc_xyfz(TOOL_LENGTH_MM);
    for (name, axis_pt, expect) in [
        // Z leans toward +X by EB0Z: Ex = +EB0Z·z; toward −Y by EA0Z: Ey = −EA0Z·z
        ("EB0Z", [0.0, 0.0, 200.0], [10.0 * 200.0 * 1e-3, 0.0, 0.0]),
        ("EA0Z", [0.0, 0.0, 200.0], [0.0, -10.0 * 200.0 * 1e-3, 0.0]),
        // a table-carrying Y moves the workpiece by −y·d_Y, d_Y = (−EC0Y, 1, 0) to first
        // order: the tool relative to it goes +y·d_Y, Ex = −EC0Y·y (as for a tool-side Y)
        ("EC0Y", [0.0, 300.0, 0.0], [-10.0 * 300.0 * 1e-3, 0.0, 0.0]),
    ] {
        let mut t = ErrorSet::new("one squareness");
        t.insert(
            ErrorElement::parse(name).unwrap(),
            mtec_model::ErrorFunction::constant(10.0),
        );
        let ours = error_um(&t, TOOL_LENGTH_MM, axis_pt);
        let vm = mtec_model::VolumetricModel::new(&m, &t);
        let theirs = mtec_sim::instruments::exact_error_um(&vm, &axis_pt);
        for i in 0..3 {
            assert!(
                (ours[i] - expect[i]).abs() < 1e-3,
                "{name}: {ours:?} vs {expect:?}"
            );
            assert!(
                (theirs[i] - ours[i]).abs() < 1e-9,
                "{name}: mtec-model {theirs:?}"
            );
        }
    }
}
