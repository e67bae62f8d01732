//! Kinematics tests: the two formalisms against each other, the first-order model against the
//! exact one, and hand-worked cases.

use mtec_model::*;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::collections::BTreeMap;

fn machine(chain: &str, frame: ErrorFrame, tool: [f64; 3]) -> Machine {
    let mut axes = BTreeMap::new();
    for c in chain.chars().filter(|c| "XYZABC".contains(*c)) {
        let rotary = "ABC".contains(c);
        axes.insert(
            c.to_string(),
            AxisSpec {
                travel: if rotary {
                    [-180.0, 180.0]
                } else {
                    [0.0, 500.0]
                },
                centre_mm: if rotary {
                    [30.0, -20.0, 10.0]
                } else {
                    [5.0, 7.0, -3.0]
                },
                period_mm: None,
            },
        );
    }
    Machine::from_spec(MachineSpec {
        name: chain.into(),
        chain: chain.into(),
        axes,
        tool_offset_mm: tool,
        workpiece_origin_mm: [12.0, -8.0, 4.0],
        error_frame: frame,
    })
    .unwrap()
}

/// Random error functions of realistic size (scaled by `scale`) for every element of the chain.
fn random_errors(m: &Machine, rng: &mut StdRng) -> ErrorSet {
    let mut set = ErrorSet::new("random test set");
    for &a in &m.axes {
        let mut els: Vec<ErrorElement> = motion_elements(a).to_vec();
        els.extend(location_elements(a));
        for e in els {
            let mag = if e.is_angular() { 30.0 } else { 10.0 };
            let f = if a.is_rotary() && !e.location {
                ErrorFunction::fourier(
                    rng.random_range(-mag..mag),
                    vec![rng.random_range(-mag..mag); 2],
                    vec![rng.random_range(-mag..mag); 3],
                )
            } else if e.location {
                ErrorFunction::constant(rng.random_range(-mag..mag))
            } else {
                ErrorFunction::polynomial(vec![
                    0.0,
                    rng.random_range(-mag..mag) / 500.0,
                    rng.random_range(-mag..mag) / 250_000.0,
                ])
            };
            set.insert(e, f);
        }
    }
    set
}

fn random_pose(m: &Machine, rng: &mut StdRng) -> Vec<f64> {
    m.axes
        .iter()
        .map(|&a| {
            let t = m.travel(a);
            rng.random_range(t[0]..t[1])
        })
        .collect()
}

const CHAINS: [&str; 4] = ["WXYFZT", "WCFT", "WCAYFXZT", "WFXYZT"];

#[test]
fn htm_and_poe_agree_exactly() {
    let mut rng = StdRng::seed_from_u64(1);
    for chain in CHAINS {
        for frame in [ErrorFrame::Moving, ErrorFrame::Reference] {
            let m = machine(chain, frame, [20.0, -10.0, 150.0]);
            // large errors (×100) so that the exact forms differ from the linear ones a lot
            let errors = random_errors(&m, &mut rng).scaled(100.0);
            let vm = VolumetricModel::new(&m, &errors);
            for _ in 0..50 {
                let q = random_pose(&m, &mut rng);
                let h = vm.error(&q, Formalism::Htm, Order::Exact);
                let p = vm.error(&q, Formalism::Poe, Order::Exact);
                for i in 0..3 {
                    // 1e-9 mm = 1e-6 µm
                    assert!(
                        (h.position_um[i] - p.position_um[i]).abs() < 1e-6,
                        "{chain} {frame:?} {q:?}: {h:?} vs {p:?}"
                    );
                    assert!((h.orientation_urad[i] - p.orientation_urad[i]).abs() < 1e-6);
                }
                let h1 = vm.error(&q, Formalism::Htm, Order::FirstOrder);
                let p1 = vm.error(&q, Formalism::Poe, Order::FirstOrder);
                for i in 0..3 {
                    assert!(
                        (h1.position_um[i] - p1.position_um[i]).abs() < 1e-6,
                        "{chain} first order: {h1:?} vs {p1:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn first_order_error_shrinks_quadratically() {
    let mut rng = StdRng::seed_from_u64(2);
    for chain in CHAINS {
        let m = machine(chain, ErrorFrame::Moving, [20.0, -10.0, 150.0]);
        let base = random_errors(&m, &mut rng).scaled(50.0);
        let q = random_pose(&m, &mut rng);
        let gap = |s: f64| {
            let vm = VolumetricModel::new(&m, &base.scaled(s));
            let e = vm.error(&q, Formalism::Htm, Order::Exact).position_um;
            let f = vm.error(&q, Formalism::Htm, Order::FirstOrder).position_um;
            ((e[0] - f[0]).powi(2) + (e[1] - f[1]).powi(2) + (e[2] - f[2]).powi(2)).sqrt()
        };
        let (g1, g2) = (gap(1.0), gap(0.1));
        let ratio = g1 / g2;
        // second-order remainder: scaling the errors by 1/10 scales the gap by 1/100
        assert!(
            (ratio - 100.0).abs() < 5.0,
            "{chain}: gap {g1} → {g2}, ratio {ratio}"
        );
        assert!(
            g1 > 1e-4,
            "{chain}: the test must see a real second-order gap ({g1} µm)"
        );
    }
}

#[test]
fn hand_worked_yaw_of_the_x_table_with_a_tool_offset() {
    // XYFZ: the table (X on Y) yaws by ε = ECX about Z at its reference point (machine zero,
    // moving with the table). The tool tip expressed in the X carriage is r = (x + tx, y + ty, z + tz);
    // the table turned by +ε, so in the workpiece frame the tip is Rz(−ε)·r:
    //   Ex = r_x cos ε + r_y sin ε − r_x,   Ey = −r_x sin ε + r_y cos ε − r_y.
    let mut axes = BTreeMap::new();
    for (k, t) in [("X", 600.0), ("Y", 800.0), ("Z", 300.0)] {
        axes.insert(
            k.to_string(),
            AxisSpec {
                travel: [0.0, t],
                centre_mm: [0.0; 3],
                period_mm: None,
            },
        );
    }
    let (tx, ty, tz) = (50.0, 0.0, 100.0);
    let m = Machine::from_spec(MachineSpec {
        name: "xyfz".into(),
        chain: "WXYFZT".into(),
        axes,
        tool_offset_mm: [tx, ty, tz],
        workpiece_origin_mm: [0.0; 3],
        error_frame: ErrorFrame::Moving,
    })
    .unwrap();
    let eps_urad = 20.0;
    let mut e = ErrorSet::new("yaw");
    e.insert(
        ErrorElement::parse("ECX").unwrap(),
        ErrorFunction::constant(eps_urad),
    );
    let vm = VolumetricModel::new(&m, &e);
    let (x, y, z) = (400.0, 300.0, 100.0);
    let v = vm.error(&[x, y, z], Formalism::Htm, Order::Exact);
    let eps = eps_urad * 1e-6;
    let (rx, ry) = (x + tx, y + ty);
    let ex = (rx * eps.cos() + ry * eps.sin() - rx) * 1e3;
    let ey = (-rx * eps.sin() + ry * eps.cos() - ry) * 1e3;
    assert!(
        (v.position_um[0] - ex).abs() < 1e-9 && (v.position_um[1] - ey).abs() < 1e-9,
        "{v:?} vs ({ex}, {ey})"
    );
    // to first order: Ex = ε·(y + ty) = 6 µm, Ey = −ε·(x + tx) = −9 µm
    assert!((ex - 6.0).abs() < 1e-3 && (ey + 9.0).abs() < 1e-3);
    assert_eq!(v.position_um[2], 0.0);
}

#[test]
fn squareness_ec0y_gives_ex_proportional_to_y() {
    // ISO 230-1: EC0Y > 0 opens the angle between +X and +Y beyond 90°; Y moves along
    // (−sin e, cos e, 0), so the tool lands at Ex = −y·sin(EC0Y) for any position of X and Z.
    let m = Machine::vmc_xyfz(100.0);
    let mut e = ErrorSet::new("squareness");
    e.insert(
        ErrorElement::parse("EC0Y").unwrap(),
        ErrorFunction::constant(50.0),
    );
    let vm = VolumetricModel::new(&m, &e);
    for (x, y, z) in [
        (0.0, 100.0, 0.0),
        (300.0, 400.0, 200.0),
        (600.0, 800.0, 50.0),
    ] {
        let v = vm.error(&[x, y, z], Formalism::Poe, Order::Exact);
        let expected = -y * (50e-6f64).sin() * 1e3;
        assert!((v.position_um[0] - expected).abs() < 1e-9, "y={y}: {v:?}");
        assert!(v.position_um[2].abs() < 1e-9);
    }
}

#[test]
fn error_frame_rule_moving_vs_reference() {
    // One tool-side linear axis X. E_ref(δr, ε)·M(q) = M(q)·E_mov(δr + (R(ε) − I)·q·x̂, ε): the two
    // orders describe the same machine when the moving-frame translation absorbs the lever arm.
    let mut rng = StdRng::seed_from_u64(3);
    let eps_urad = [40.0, -70.0, 90.0];
    let dr_um = [3.0, -2.0, 5.0];
    let r = Htm::error_exact(
        nalgebra::Vector3::zeros(),
        nalgebra::Vector3::from(eps_urad) * 1e-6,
    )
    .r;
    let lever = (r - nalgebra::Matrix3::identity()) * nalgebra::Vector3::x(); // per mm of q, in mm
    let mut reference = ErrorSet::new("reference frame");
    let mut moving = ErrorSet::new("moving frame");
    for (i, d) in [Axis::X, Axis::Y, Axis::Z].into_iter().enumerate() {
        reference.insert(
            ErrorElement::motion(d, Axis::X),
            ErrorFunction::constant(dr_um[i]),
        );
        moving.insert(
            ErrorElement::motion(d, Axis::X),
            ErrorFunction::polynomial(vec![dr_um[i], lever[i] * 1e3]),
        );
    }
    for (i, d) in [Axis::A, Axis::B, Axis::C].into_iter().enumerate() {
        reference.insert(
            ErrorElement::motion(d, Axis::X),
            ErrorFunction::constant(eps_urad[i]),
        );
        moving.insert(
            ErrorElement::motion(d, Axis::X),
            ErrorFunction::constant(eps_urad[i]),
        );
    }
    let mr = machine("WFXT", ErrorFrame::Reference, [0.0, 30.0, 120.0]);
    let mm = machine("WFXT", ErrorFrame::Moving, [0.0, 30.0, 120.0]);
    let (vr, vmv) = (
        VolumetricModel::new(&mr, &reference),
        VolumetricModel::new(&mm, &moving),
    );
    for _ in 0..20 {
        let q = [rng.random_range(0.0..500.0)];
        let a = vr.error(&q, Formalism::Htm, Order::Exact).position_um;
        let b = vmv.error(&q, Formalism::Htm, Order::Exact).position_um;
        for i in 0..3 {
            assert!((a[i] - b[i]).abs() < 1e-9, "q={q:?}: {a:?} vs {b:?}");
        }
        // and the orders really differ when the same numbers are used in both
        let c = VolumetricModel::new(&mm, &reference)
            .error(&q, Formalism::Htm, Order::Exact)
            .position_um;
        if q[0] > 10.0 {
            assert!((a[1] - c[1]).abs() > 1e-3);
        }
    }
}

#[test]
fn jacobian_reproduces_the_first_order_model() {
    let mut rng = StdRng::seed_from_u64(4);
    for chain in CHAINS {
        let m = machine(chain, ErrorFrame::Moving, [20.0, -10.0, 150.0]);
        let errors = random_errors(&m, &mut rng);
        let vm = VolumetricModel::new(&m, &errors);
        let q = random_pose(&m, &mut rng);
        let jac = vm.first_order_jacobian(&q);
        let mut sum = [0.0; 3];
        for (el, col) in &jac {
            let axis_q = q[m.axis_index(el.axis).unwrap()];
            let v = errors.value(el, axis_q);
            for i in 0..3 {
                sum[i] += col[i] * v;
            }
        }
        let f = vm.error(&q, Formalism::Htm, Order::FirstOrder).position_um;
        for i in 0..3 {
            assert!((sum[i] - f[i]).abs() < 1e-9, "{chain}: {sum:?} vs {f:?}");
        }
    }
}

/// Which of the 21 elements of the XYFZ machine reach Ex, Ey, Ez in the first-order model.
///
/// Worked by hand for WXYFZT with tool offset (0, 0, L) and carriage reference points at the
/// machine zero. The lever arm of an angular error is the tool tip seen from the carriage:
/// from the X table r = (x, y, z + L) (X rides on Y, so it sees both), from the Y carriage
/// r = (0, y, z + L) (the X motion is between the workpiece and Y), from the Z ram r = (0, 0, L).
/// δ + ε × r then gives
///   Ex: EXX EXY EXZ, EC0Y (−y), EB0Z (z), EBX·(z+L), EBY·(z+L), EBZ·L, ECX·y, ECY·y   → 10
///   Ey: EYX EYY EYZ, EA0Z (−z), EAX·(z+L), EAY·(z+L), EAZ·L, ECX·x                    → 8
///   Ez: EZX EZY EZZ, EAX·y, EAY·y, EBX·x                                              → 6
/// The source's POE model counts 8, 8 and 6: Ey and Ez agree; its Ex leaves out the two yaw
/// Abbe terms ECX·y and ECY·y, which a rigid-body model with carriage reference points at the
/// machine zero must keep (a yawing table moves a point y away from its reference sideways).
#[test]
fn elements_reaching_each_direction_of_the_xyfz_machine() {
    let m = Machine::vmc_xyfz(100.0);
    let vm = VolumetricModel::new(&m, &ErrorSet::new("none"));
    let mut reach: [std::collections::BTreeSet<String>; 3] = Default::default();
    let mut rng = StdRng::seed_from_u64(5);
    for _ in 0..20 {
        let q = random_pose(&m, &mut rng);
        for (el, col) in vm.first_order_jacobian(&q) {
            for i in 0..3 {
                if col[i].abs() > 1e-12 {
                    reach[i].insert(el.name());
                }
            }
        }
    }
    let set = |s: &str| {
        s.split_whitespace()
            .map(String::from)
            .collect::<std::collections::BTreeSet<_>>()
    };
    assert_eq!(reach[0], set("EXX EXY EXZ EC0Y EB0Z EBX EBY EBZ ECX ECY"));
    assert_eq!(reach[1], set("EYX EYY EYZ EA0Z EAX EAY EAZ ECX"));
    assert_eq!(reach[2], set("EZX EZY EZZ EAX EAY EBX"));
    // and the lever arms are the hand-worked ones, e.g. ∂Ex/∂EBX = (z + L)·1e-3 µm per µrad
    let q = [100.0, 200.0, 50.0];
    let jac = vm.first_order_jacobian(&q);
    let col = |n: &str| jac.iter().find(|(e, _)| e.name() == n).unwrap().1;
    // the table is on the workpiece side: its pitch tilts the workpiece, the tool sees −ε × r
    assert!(
        (col("EBX")[0] + (50.0 + 100.0) * 1e-3).abs() < 1e-12,
        "{:?}",
        col("EBX")
    );
    assert!(
        (col("EBZ")[0] - 100.0 * 1e-3).abs() < 1e-12,
        "{:?}",
        col("EBZ")
    );
    assert!(
        (col("EC0Y")[0] + 200.0 * 1e-3).abs() < 1e-12,
        "{:?}",
        col("EC0Y")
    );
    assert!((col("EXX")[0] + 1.0).abs() < 1e-12 && (col("EXZ")[0] - 1.0).abs() < 1e-12);
}

/// The tool frame with and without errors reproduces the exact volumetric error (its
/// translation difference) and the ideal tool point, and its rotation the orientation error.
#[test]
fn tool_frame_gives_the_exact_error_and_the_ideal_point() {
    let mut rng = StdRng::seed_from_u64(7);
    for chain in CHAINS {
        let m = machine(chain, ErrorFrame::Moving, [20.0, -10.0, 150.0]);
        let errors = random_errors(&m, &mut rng).scaled(10.0);
        let vm = VolumetricModel::new(&m, &errors);
        for _ in 0..20 {
            let q = random_pose(&m, &mut rng);
            let ideal = vm.tool_frame(&q, false);
            let actual = vm.tool_frame(&q, true);
            let exact = vm.error(&q, Formalism::Htm, Order::Exact);
            let p0 = vm.ideal_tool_point(&q);
            for (i, p0) in p0.iter().enumerate() {
                assert!((ideal.p[i] - p0).abs() < 1e-12, "{chain}");
                let d_um = (actual.p[i] - ideal.p[i]) * 1e3;
                assert!((d_um - exact.position_um[i]).abs() < 1e-9, "{chain}");
            }
            let w = mtec_model::htm::rotation_vector(&(actual.r * ideal.r.transpose())) * 1e6;
            for i in 0..3 {
                assert!((w[i] - exact.orientation_urad[i]).abs() < 1e-9, "{chain}");
            }
        }
    }
}
