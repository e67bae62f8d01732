//! Recovery of the virtual machine's truth from its `vmc-9line` measurements
//! (issue 3, Done-when: volumetric prediction and per-element 3σ checks).

use crate::support;

use mtec_identify::lines::model::Block;
use mtec_identify::lines::{
    identify, identify_with, solve::polynomial_in_q, Degree, Layout, LineData, DEFAULT_DEGREE,
};
use mtec_io::Table;
use mtec_model::{
    ErrorElement, ErrorFunction, ErrorSet, Formalism, Machine, Order, VolumetricModel,
};
use nalgebra::{DMatrix, DVector};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::path::Path;

const L_MM: f64 = mtec_sim::vmc_9line::TOOL_LENGTH_MM;

fn scenario(seed: u64) -> (Machine, LineData, ErrorSet) {
    support::vmc_9line(seed)
}

/// RMS over 1000 random workspace points of |E_identified − E_truth| (µm), exact kinematics,
/// both at the measured tool offset.
fn volumetric_rms(machine: &Machine, truth: &ErrorSet, ident: &ErrorSet) -> f64 {
    let vt = VolumetricModel::new(machine, truth);
    let vi = VolumetricModel::new(machine, ident);
    let mut rng = StdRng::seed_from_u64(99);
    let mut ss = 0.0;
    for _ in 0..1000 {
        let q: Vec<f64> = machine
            .axes
            .iter()
            .map(|a| {
                let [lo, hi] = machine.travel(*a);
                rng.random_range(lo..hi)
            })
            .collect();
        let et = vt.error(&q, Formalism::Htm, Order::Exact).position_um;
        let ei = vi.error(&q, Formalism::Htm, Order::Exact).position_um;
        ss += (0..3).map(|i| (et[i] - ei[i]).powi(2)).sum::<f64>();
    }
    (ss / 1000.0).sqrt()
}

/// Least-squares coefficients of `f` on the functions `basis(q)` over the travel (400 points).
fn project(f: &dyn Fn(f64) -> f64, travel: [f64; 2], basis: &dyn Fn(f64) -> Vec<f64>) -> Vec<f64> {
    let n = 400;
    let q = |i: usize| travel[0] + (travel[1] - travel[0]) * (i as f64 + 0.5) / n as f64;
    let k = basis(travel[0]).len();
    let a = DMatrix::from_fn(n, k, |i, j| basis(q(i))[j]);
    let y = DVector::from_fn(n, |i, _| f(q(i)));
    a.svd(true, true)
        .solve(&y, 1e-12)
        .unwrap()
        .iter()
        .copied()
        .collect()
}

/// The identification's parameter blocks (basis functions) at a degree.
fn blocks(m: &Machine, degree: usize) -> Vec<Block> {
    let empty = LineData {
        source: String::new(),
        path: None,
        point_column: 0,
        channels: vec![],
    };
    Layout::new(m, degree, &empty).unwrap().blocks
}

fn el(n: &str) -> ErrorElement {
    ErrorElement::parse(n).unwrap()
}

/// The truth of a vmc-9line seed with its short-period ripple removed: each function projected
/// on the identification's cubic basis (straightness from its least-squares reference line),
/// squareness unchanged.
fn smooth(machine: &Machine, rough: &ErrorSet) -> ErrorSet {
    let mut out = ErrorSet::new("smooth truth");
    for b in blocks(machine, 3) {
        let f = rough.get(&b.element).unwrap();
        if b.element.location {
            out.insert(b.element, f.clone());
            continue;
        }
        let c = project(&|q| f.value(q), b.travel, &|q| b.basis(q).collect());
        let terms = b.power_terms(&c);
        out.insert(
            b.element,
            ErrorFunction::polynomial(polynomial_in_q(&terms, b.travel)),
        );
    }
    out
}

/// The observation model and its solution are exact up to second-order kinematics: on a truth
/// the polynomials can represent, with no noise, the identified model predicts the volumetric
/// error to within 0.15 µm (what remains: y·ECY(y), absorbed into EXY, is quartic at degree 3).
#[test]
fn noise_free_smooth_truth_is_recovered_exactly() {
    use mtec_sim::instruments::LaserInterferometer;
    let m = Machine::vmc_xyfz(L_MM);
    let lines = mtec_model::line_preset("nine-line", &m, 20, 10.0).unwrap();
    for seed in [2u64, 8] {
        let truth = smooth(&m, &mtec_sim::truth::geometric_truth(&m, seed));
        let laser = LaserInterferometer {
            noise_um: 0.0,
            straightness_noise_um: 0.0,
            alignment_urad: 20.0,
        };
        let (csv, _) = mtec_sim::vmc_9line::measure_lines(&m, &truth, &lines, &laser, seed);
        let data = LineData::from_table(&Table::parse(Path::new("x.csv"), &csv).unwrap()).unwrap();
        let id = identify(&m, &data, 3).unwrap();
        let r = volumetric_rms(&m, &truth, &id.errors);
        assert!(r < 0.15, "seed {seed}: {r} µm");
    }
}

/// Issue 3: the identified model predicts the volumetric error at 1000 random workspace points
/// to within 1 µm RMS of the truth, on every one of 12 seeds (3 runs of each line), at the
/// default degree 3 and at degree 4 (the degree of the 3σ element check below, so that one
/// identification meets both of the conditions).
/// Measured: degree 3 median 0.28 µm, worst 0.49 µm; degree 4 median 0.30, worst 0.44 µm.
/// Before the straightness basis followed ISO 230-1's least-squares reference line the median
/// was 0.84 µm and the worst 1.53 µm (degree 3, one run): see `mtec_identify::lines::model`.
#[test]
fn vmc_9line_predicts_the_volumetric_error() {
    let runs: Vec<_> = (1..=12).map(scenario).collect();
    for degree in [DEFAULT_DEGREE, Degree::Fixed(4)] {
        let mut r: Vec<f64> = runs
            .iter()
            .map(|(m, data, truth)| {
                volumetric_rms(m, truth, &identify_with(m, data, degree).unwrap().errors)
            })
            .collect();
        println!("degree {degree}: volumetric RMS per seed {r:.3?} µm");
        r.sort_by(f64::total_cmp);
        let median = 0.5 * (r[5] + r[6]);
        println!(
            "degree {degree}: median {median:.3} µm, worst {:.3} µm",
            r[11]
        );
        assert!(r[11] < 1.0, "degree {degree}: worst seed {} µm", r[11]);
    }
}

/// The truth combination each identified element estimates, as coefficients on its basis.
/// Confounded elements are absorbed as the exact kinematics says (checked below):
///   Ex ∋ −EXY(y) + y·ECY(y) − y·EC0Y    → EXY* + y·EC0Y* = EXY − y·ECY + y·EC0Y
///   Ex ∋ EXZ(z) + L·EBZ(z) + z·EB0Z     → EXZ* + z·EB0Z* = that
///   Ey ∋ EYZ(z) − L·EAZ(z) − z·EA0Z     → EYZ* − z·EA0Z* = that
/// each split by the basis: the least-squares slope goes to the squareness, the rest to the
/// straightness (its basis has no least-squares slope). (µm, mm, µrad: an angle times a length
/// in mm is ×1e-3 µm.) Every function is projected on the identification's basis over the
/// travel (the estimand of a polynomial model).
fn truth_combination(m: &Machine, truth: &ErrorSet, b: &Block, degree: usize) -> Vec<f64> {
    let v = |n: &str, q: f64| truth.value(&el(n), q);
    let e = b.element;
    let name = e.name();
    let basis = |q: f64| b.basis(q).collect::<Vec<f64>>();
    // a straightness block with a linear term in front: the linear part is the squareness's
    let partner = |n: &str| blocks(m, degree).into_iter().find(|x| x.element == el(n));
    let with_linear = |f: &dyn Fn(f64) -> f64, straight: &str| {
        let sb = partner(straight).unwrap();
        let len = sb.travel[1] - sb.travel[0];
        project(f, sb.travel, &|q| {
            std::iter::once((q - sb.travel[0]) / len)
                .chain(sb.basis(q))
                .collect()
        })
    };
    let split = |c: Vec<f64>, sign: f64, len: f64| {
        if e.location {
            vec![sign * c[0] / len * 1e3]
        } else {
            c[1..].to_vec()
        }
    };
    let (ylen, zlen) = (
        m.travel(mtec_model::Axis::Y)[1] - m.travel(mtec_model::Axis::Y)[0],
        m.travel(mtec_model::Axis::Z)[1] - m.travel(mtec_model::Axis::Z)[0],
    );
    match name.as_str() {
        "EXY" | "EC0Y" => split(
            with_linear(
                &|y| v("EXY", y) - y * v("ECY", y) * 1e-3 + y * v("EC0Y", y) * 1e-3,
                "EXY",
            ),
            1.0,
            ylen,
        ),
        "EXZ" | "EB0Z" => split(
            with_linear(
                &|z| v("EXZ", z) + L_MM * v("EBZ", z) * 1e-3 + z * v("EB0Z", z) * 1e-3,
                "EXZ",
            ),
            1.0,
            zlen,
        ),
        "EYZ" | "EA0Z" => split(
            with_linear(
                &|z| v("EYZ", z) - L_MM * v("EAZ", z) * 1e-3 - z * v("EA0Z", z) * 1e-3,
                "EYZ",
            ),
            -1.0,
            zlen,
        ),
        _ if e.location => vec![truth.value(&e, 0.0)],
        _ => project(&|q| truth.value(&e, q), b.travel, &basis),
    }
}

#[test]
fn absorbed_combinations_follow_the_exact_kinematics() {
    let m = Machine::vmc_xyfz(L_MM);
    let truth = mtec_sim::truth::geometric_truth(&m, 3);
    let only = |names: &[&str]| {
        let mut s = ErrorSet::new("part");
        for n in names {
            s.insert(el(n), truth.get(&el(n)).unwrap().clone());
        }
        VolumetricModel::new(&m, &s)
    };
    let v = |n: &str, q: f64| truth.value(&el(n), q);
    for (x, y, z) in [(100.0, 700.0, 250.0), (500.0, 300.0, 40.0)] {
        let e = only(&["EXY", "ECY", "EC0Y"])
            .error(&[x, y, z], Formalism::Htm, Order::Exact)
            .position_um;
        let g = v("EXY", y) - y * v("ECY", y) * 1e-3 + y * v("EC0Y", y) * 1e-3;
        assert!((e[0] + g).abs() < 1e-3, "{e:?}");
        let e = only(&["EXZ", "EBZ", "EB0Z"])
            .error(&[x, y, z], Formalism::Htm, Order::Exact)
            .position_um;
        let g = v("EXZ", z) + L_MM * v("EBZ", z) * 1e-3 + z * v("EB0Z", z) * 1e-3;
        assert!((e[0] - g).abs() < 1e-3, "{e:?} vs {g}");
        let e = only(&["EYZ", "EAZ", "EA0Z"])
            .error(&[x, y, z], Formalism::Htm, Order::Exact)
            .position_um;
        let h = v("EYZ", z) - L_MM * v("EAZ", z) * 1e-3 - z * v("EA0Z", z) * 1e-3;
        assert!((e[1] - h).abs() < 1e-3, "{e:?} vs {h}");
    }
}

/// Issue 3: every identified element lies within 3σ (its reported uncertainty: the max over the
/// travel of the 1σ band) of the truth, compared as max over the travel of |f̂ − f*| with f* the
/// truth (combination) projected on the identification's basis (see `truth_combination`).
///
/// Run at degree 4 on 12 seeds (largest deviation measured: 2.8σ): the combination EXY − y·ECY
/// is quartic when ECY is cubic, so at degree 3 the polynomial cannot hold what EXY absorbs,
/// and that bias (not noise) moves EXY by many σ. At degree 4 the estimand is representable and
/// every element passes; the same degree-4 identification also meets the 1 µm volumetric
/// condition (see above). Degree 3 stays the default: it predicts the volumetric error as well
/// with fewer parameters.
#[test]
fn identified_elements_lie_within_three_sigma_of_the_truth() {
    let mut worst: (f64, String) = (0.0, String::new());
    let mut failures = Vec::new();
    for seed in 1..=12 {
        let (m, data, truth) = scenario(seed);
        let id = identify(&m, &data, 4).unwrap();
        for er in &id.report.elements {
            let e = el(&er.element);
            let b = id.layout.block(&e).unwrap();
            let c = truth_combination(&m, &truth, b, 4);
            let [lo, hi] = b.travel;
            let dev = (0..=100)
                .map(|i| {
                    let q = lo + (hi - lo) * i as f64 / 100.0;
                    let f_true: f64 = b.basis(q).zip(&c).map(|(bv, c)| bv * c).sum();
                    (id.value_sigma(&e, q).unwrap().0 - f_true).abs()
                })
                .fold(0.0f64, f64::max);
            let ratio = dev / er.uncertainty_1sigma;
            if ratio > worst.0 {
                worst = (ratio, format!("seed {seed} {}", er.element));
            }
            if ratio > 3.0 {
                failures.push(format!(
                    "seed {seed} {}: |dev| {dev:.3} > 3 × {:.3}",
                    er.element, er.uncertainty_1sigma
                ));
            }
        }
    }
    println!("largest deviation / σ: {:.2} ({})", worst.0, worst.1);
    assert!(failures.is_empty(), "{failures:#?}");
}
