//! Recovery of the virtual machine's truth from its `vmc-9line` measurements.

use mtec_identify::lines::{identify, LineData};
use mtec_io::Table;
use mtec_model::{ErrorSet, Formalism, Machine, Order, VolumetricModel};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::path::Path;

fn scenario(seed: u64) -> (Machine, LineData, ErrorSet) {
    let out = mtec_sim::run_scenario("vmc-9line", seed).unwrap();
    let csv = &out.files.iter().find(|f| f.name == "lines.csv").unwrap().contents;
    let table = Table::parse(Path::new("lines.csv"), csv).unwrap();
    let data = LineData::from_table(&table).unwrap();
    let machine = Machine::vmc_xyfz(mtec_sim::vmc_9line::TOOL_LENGTH_MM);
    let truth: ErrorSet = serde_json::from_value(out.truth["errors"].clone()).unwrap();
    (machine, data, truth)
}

/// RMS over 1000 random workspace points of |E_identified − E_truth| (µm), exact kinematics.
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

#[test]
fn explore() {
    for seed in 1..=12 {
        let (m, data, truth) = scenario(seed);
        for degree in [3] {
            let id = identify(&m, &data, degree).unwrap();
            println!("seed {seed} degree {degree}: volumetric RMS {:.3} um", volumetric_rms(&m, &truth, &id.errors));
        }
    }
}

#[test]
fn explore_noise_free() {
    use mtec_sim::instruments::LaserInterferometer;
    let m = Machine::vmc_xyfz(100.0);
    let truth = mtec_sim::truth::geometric_truth(&m, 1);
    let lines = mtec_model::line_preset("nine-line", &m, 20, 10.0).unwrap();
    for noise in [0.0, 0.15] {
        let laser = LaserInterferometer { noise_um: noise, straightness_noise_um: noise, alignment_urad: 20.0 };
        let (csv, _) = mtec_sim::vmc_9line::measure_lines(&m, &truth, &lines, &laser, 1);
        let data = LineData::from_table(&Table::parse(Path::new("x.csv"), &csv).unwrap()).unwrap();
        for degree in [3, 4, 5, 6] {
            let id = identify(&m, &data, degree).unwrap();
            println!("noise {noise} degree {degree}: volumetric RMS {:.3} um, resid {:.3}", volumetric_rms(&m, &truth, &id.errors), id.report.residual_rms_um);
        }
    }
}

#[test]
fn explore_designs() {
    use mtec_sim::instruments::LaserInterferometer;
    let m = Machine::vmc_xyfz(100.0);
    let nine = mtec_model::line_preset("nine-line", &m, 20, 10.0).unwrap();
    let nine40 = mtec_model::line_preset("nine-line", &m, 40, 10.0).unwrap();
    let fifteen = mtec_model::line_preset("fifteen-line", &m, 20, 10.0).unwrap();
    let mut ten = nine.clone();
    let mut xy2 = nine.iter().find(|l| l.name == "XY").unwrap().clone();
    xy2.name = "XYtop".into();
    xy2.start_mm[2] = 290.0;
    xy2.end_mm[2] = 290.0;
    ten.push(xy2);
    for (name, lines) in [("nine", &nine), ("nine40", &nine40), ("fifteen", &fifteen)] {
        for degree in [3, 4, 5] {
            let mut worst: f64 = 0.0;
            let mut sum = 0.0;
            for seed in 1..=12 {
                let truth = mtec_sim::truth::geometric_truth(&m, seed);
                let laser = LaserInterferometer::default();
                let (csv, _) = mtec_sim::vmc_9line::measure_lines(&m, &truth, lines, &laser, seed);
                let data = LineData::from_table(&Table::parse(Path::new("x.csv"), &csv).unwrap()).unwrap();
                let id = identify(&m, &data, degree).unwrap();
                let r = volumetric_rms(&m, &truth, &id.errors);
                worst = worst.max(r);
                sum += r;
            }
            println!("{name} degree {degree}: mean {:.3} worst {:.3}", sum / 12.0, worst);
        }
    }
}

#[test]
fn explore_contrib() {
    use mtec_sim::instruments::LaserInterferometer;
    let m = Machine::vmc_xyfz(100.0);
    let lines = mtec_model::line_preset("nine-line", &m, 20, 10.0).unwrap();
    let truth = mtec_sim::truth::geometric_truth(&m, 2);
    for noise in [0.0, 0.15] {
        let laser = LaserInterferometer { noise_um: noise, straightness_noise_um: noise * 1.6, alignment_urad: 20.0 };
        let (csv, _) = mtec_sim::vmc_9line::measure_lines(&m, &truth, &lines, &laser, 2);
        let data = LineData::from_table(&Table::parse(Path::new("x.csv"), &csv).unwrap()).unwrap();
        let id = identify(&m, &data, 5).unwrap();
        let groups: Vec<Vec<&str>> = vec![vec!["EXX"], vec!["EYX"], vec!["EZX"], vec!["EAX"], vec!["EBX"], vec!["ECX"], vec!["EXY", "ECY"], vec!["EYY"], vec!["EZY"], vec!["EAY"], vec!["EBY"], vec!["EXZ", "EBZ", "EB0Z"], vec!["EYZ", "EAZ", "EA0Z"], vec!["EZZ"], vec!["EC0Y"], vec!["ECZ"]];
        for g in groups {
            let mut t = ErrorSet::new("t");
            let mut i = ErrorSet::new("i");
            for n in &g {
                let e = mtec_model::ErrorElement::parse(n).unwrap();
                if let Some(f) = truth.get(&e) { t.insert(e, f.clone()); }
                if let Some(f) = id.errors.get(&e) { i.insert(e, f.clone()); }
            }
            println!("noise {noise} {:?}: {:.3}", g, volumetric_rms(&m, &t, &i));
        }
        println!("noise {noise} total {:.3}", volumetric_rms(&m, &truth, &id.errors));
    }
}

#[test]
fn explore_report() {
    let (m, data, _truth) = scenario(2);
    let id = identify(&m, &data, 3).unwrap();
    println!("{}", id.report.to_text());
    // correlations of EC0Y
    let b = id.layout.block(&mtec_model::ErrorElement::parse("EC0Y").unwrap()).unwrap();
    let an = &id.analysis;
    let j = an.active.iter().position(|&c| c == b.first_col).unwrap();
    let cov = &id.fit.cov;
    let mut corr: Vec<(f64, usize)> = (0..an.active.len()).map(|k| (cov[(j, k)] / (cov[(j, j)] * cov[(k, k)]).sqrt(), an.active[k])).collect();
    corr.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
    for (c, col) in corr.iter().take(8) {
        let name = id.layout.blocks.iter().find(|b| b.cols().contains(col)).map(|b| format!("{} p{}", b.element, b.powers[col - b.first_col])).unwrap_or(format!("slope col {col}"));
        println!("corr {c:.3} {name}");
    }
}

#[test]
fn explore_variance() {
    let (m, data, _truth) = scenario(2);
    for degree in [3, 5] {
        let id = identify(&m, &data, degree).unwrap();
        let vm = VolumetricModel::new(&m, &ErrorSet::new("x"));
        let an = &id.analysis;
        let k = an.active.len();
        let mut rng = StdRng::seed_from_u64(5);
        let mut contrib = vec![0.0; id.layout.blocks.len()];
        let mut total = 0.0;
        for _ in 0..300 {
            let q: Vec<f64> = m.axes.iter().map(|a| { let [lo, hi] = m.travel(*a); rng.random_range(lo..hi) }).collect();
            let jac = vm.first_order_jacobian(&q);
            for comp in 0..3 {
                let mut g = nalgebra::DVector::<f64>::zeros(k);
                for b in &id.layout.blocks {
                    let j = jac.iter().find(|(e, _)| *e == b.element).map_or(0.0, |x| x.1[comp]);
                    for (c, bv) in b.cols().zip(b.basis(q[b.pose_index])) {
                        if let Some(p) = an.active.iter().position(|&x| x == c) { g[p] = j * bv; }
                    }
                }
                total += (g.transpose() * &id.fit.cov * &g)[0];
                for (bi, b) in id.layout.blocks.iter().enumerate() {
                    let mut gb = g.clone();
                    for p in 0..k { if !b.cols().contains(&an.active[p]) { gb[p] = 0.0; } }
                    // contribution of the block: g_B Cov g  (sums to total)
                    contrib[bi] += (gb.transpose() * &id.fit.cov * &g)[0];
                }
            }
        }
        println!("degree {degree}: predicted volumetric RMS sigma {:.3}", (total / 300.0).sqrt());
        for (bi, b) in id.layout.blocks.iter().enumerate() {
            if contrib[bi].abs() / total > 0.03 { println!("  {} share {:.2}", b.element, contrib[bi] / total); }
        }
    }
}

#[test]
fn explore_smooth_truth() {
    use mtec_sim::instruments::LaserInterferometer;
    let m = Machine::vmc_xyfz(100.0);
    for seed in [2u64, 8, 9] {
        let rough = mtec_sim::truth::geometric_truth(&m, seed);
        // the truth with its ripple removed: cubic least-squares fit through the origin
        let mut smooth = ErrorSet::new("smooth");
        for (e, f) in &rough.elements {
            if e.location { smooth.insert(*e, f.clone()); continue; }
            let [lo, hi] = m.travel(e.axis);
            let n = 200;
            let straight = !e.is_angular() && e.direction != e.axis;
            let powers: Vec<i32> = if straight { vec![2, 3] } else { vec![1, 2, 3] };
            let a = nalgebra::DMatrix::from_fn(n, powers.len(), |i, j| ((i as f64 + 0.5) / n as f64).powi(powers[j]));
            let y = nalgebra::DVector::from_fn(n, |i, _| f.value(lo + (hi - lo) * (i as f64 + 0.5) / n as f64));
            let c = a.clone().svd(true, true).solve(&y, 1e-12).unwrap();
            let coeffs: Vec<(i32, f64)> = powers.iter().zip(c.iter()).map(|(p, c)| (*p, *c)).collect();
            smooth.insert(*e, mtec_model::ErrorFunction::polynomial(mtec_identify::lines::solve::polynomial_in_q(&coeffs, [lo, hi])));
        }
        let lines = mtec_model::line_preset("nine-line", &m, 20, 10.0).unwrap();
        for (label, truth) in [("rough", &rough), ("smooth", &smooth)] {
            for noise in [0.0, 1.0] {
                let laser = LaserInterferometer { noise_um: 0.15 * noise, straightness_noise_um: 0.25 * noise, alignment_urad: 20.0 };
                let (csv, _) = mtec_sim::vmc_9line::measure_lines(&m, truth, &lines, &laser, seed);
                let data = LineData::from_table(&Table::parse(Path::new("x.csv"), &csv).unwrap()).unwrap();
                let id = identify(&m, &data, 3).unwrap();
                println!("seed {seed} {label} noise {noise}: {:.3}", volumetric_rms(&m, truth, &id.errors));
            }
        }
    }
}
