//! Study (issue 19): what limits the compensation rate after 9-line identification on the
//! realistic truth. For 5 seeds it measures the scenario's design on the truth with one part
//! removed at a time (bump, waviness) and prints the prediction RMS and compensation rate per
//! axis at 1000 random points (the definition of `tests/lines_realistic.rs`).
//!
//! Run: `cargo run -p mtec-identify --example lines_floor [NOISE_UM]`; `ALL_ONLY=1` only the
//! whole truth, `SPLINES=1` with cubic splines among the cross-validated candidates, `SMOOTH=1`
//! smoothing splines (penalty chosen by the same cross-validation), `HYBRID=1` the better of
//! the two per kind (`--degree smooth`), `PER_ELEMENT=1` / `LEGENDRE_PER_ELEMENT=1` the penalty
//! / degree refined per element, `GCV=1` the penalty by generalised cross-validation, `STEPS=N` N intervals per line instead of the scenario's 20,
//! `ORACLE=1` the rate of a compensation that knows the truth but its waviness' oscillation (and
//! bump): the ceiling no identification can pass; `SEED=S` one seed; `SCENARIO=vmc-9line` a
//! whole scenario against degree 3; `CURVE=EZZ` an element's truth and identification every
//! mm; `DIAG=1` the prediction with each element replaced by the truth; `COND=1` the
//! least-determined direction of the kept design.

use mtec_comp::kinematic::KinematicModel;
use mtec_comp::{command_for_target, CorrectionOptions};
use mtec_identify::lines::select::Family;
use mtec_identify::lines::{identify_family, LineData};
use mtec_io::Table;
use mtec_model::{line_preset, ErrorSet, Formalism, Machine, Order, VolumetricModel};
use mtec_sim::instruments::LaserInterferometer;
use mtec_sim::realistic_truth::{realistic_truth_with, Mix};
use mtec_sim::vmc_9line::{machine_with_leads, measure_runs, RUNS};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::path::Path;

fn evaluate(machine: &Machine, truth: &ErrorSet, ident: &ErrorSet, seed: u64) -> [[f64; 3]; 3] {
    let vt = VolumetricModel::new(machine, truth);
    let vi = VolumetricModel::new(machine, ident);
    let model = KinematicModel::new(machine, ident, "identified").unwrap();
    let mut rng = StdRng::seed_from_u64(seed ^ 0xc0de);
    let (mut pred, mut before, mut after) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    let n = 1000;
    for _ in 0..n {
        let t: [f64; 3] = [0, 1, 2].map(|i| {
            let [lo, hi] = machine.travel(machine.axes[i]);
            rng.random_range(lo + 5.0..hi - 5.0)
        });
        let et = vt.error(&t, Formalism::Htm, Order::Exact).position_um;
        let ei = vi.error(&t, Formalism::Htm, Order::Exact).position_um;
        let p = command_for_target(&model, t, &CorrectionOptions::default()).unwrap();
        let e1 = vt.error(&p, Formalism::Htm, Order::Exact).position_um;
        for i in 0..3 {
            pred[i] += (et[i] - ei[i]).powi(2);
            before[i] += et[i].powi(2);
            after[i] += ((p[i] - t[i]) * 1e3 + e1[i]).powi(2);
        }
    }
    let rms = |v: f64| (v / n as f64).sqrt();
    [pred.map(rms), before.map(rms), after.map(rms)]
}

/// `known` plus the 50 mm moving average of the waviness (`all` − `no_ripple`): the ripple's
/// offset (it starts at zero, so it is a sinusoid about a constant) and fade-in are smooth and
/// learnable from points 14–39 mm apart; its oscillation (period 8–25 mm) is not.
fn with_local_mean_of_ripple(
    all: &ErrorSet,
    no_ripple: &ErrorSet,
    mut known: ErrorSet,
) -> ErrorSet {
    use mtec_model::function::Shape;
    for (e, f) in known.elements.iter_mut() {
        let Shape::Table { positions, values } = &mut f.shape else {
            continue;
        };
        let ripple: Vec<f64> = positions
            .iter()
            .map(|&q| all.value(e, q) - no_ripple.value(e, q))
            .collect();
        for (i, v) in values.iter_mut().enumerate() {
            let near: Vec<f64> = (0..ripple.len())
                .filter(|&j| (positions[j] - positions[i]).abs() <= 25.0)
                .map(|j| ripple[j])
                .collect();
            *v += near.iter().sum::<f64>() / near.len() as f64;
        }
    }
    known
}

fn main() {
    let machine = machine_with_leads();
    // intervals per line (the scenario's 20 unless STEPS says)
    let steps = std::env::var("STEPS").map_or(20, |s| s.parse().unwrap());
    let lines = line_preset("nine-line", &machine, steps, 10.0).unwrap();
    let one = |b: f64, r: f64| Mix {
        bump: b,
        ripple: r,
        ..Mix::default()
    };
    let noise = std::env::args()
        .nth(1)
        .map(|s| s.parse::<f64>().unwrap())
        .unwrap_or(0.1);
    let laser = LaserInterferometer {
        noise_um: noise,
        straightness_noise_um: noise,
        alignment_urad: 20.0,
    };
    let family = if std::env::var_os("GCV").is_some() {
        Family::SmoothingGcv
    } else if std::env::var_os("LEGENDRE_PER_ELEMENT").is_some() {
        Family::LegendrePerElement
    } else if std::env::var_os("PER_ELEMENT").is_some() {
        Family::SmoothingPerElement
    } else if std::env::var_os("HYBRID").is_some() {
        Family::Hybrid
    } else if std::env::var_os("SMOOTH").is_some() {
        Family::Smoothing
    } else if std::env::var_os("SPLINES").is_some() {
        Family::WithSplines
    } else {
        Family::Legendre
    };
    for seed in std::env::var("SEED").map_or(1..=5u64, |s| {
        let v = s.parse().unwrap();
        v..=v
    }) {
        if let Ok(scenario) = std::env::var("SCENARIO") {
            // a whole scenario as the tests read it (e.g. the nearly cubic `vmc-9line`), with
            // the family asked and at degree 3
            let out = mtec_sim::run_scenario(&scenario, seed).unwrap();
            let file = |n: &str| &out.files.iter().find(|f| f.name == n).unwrap().contents;
            let data = LineData::from_table(
                &Table::parse(Path::new("lines.csv"), file("lines.csv")).unwrap(),
            )
            .unwrap();
            let spec: mtec_model::MachineSpec = toml::from_str(file("machine.toml")).unwrap();
            let truth: ErrorSet = serde_json::from_value(out.truth["errors"].clone()).unwrap();
            let m = Machine::from_spec(spec).unwrap();
            let t0 = std::time::Instant::now();
            let id = identify_family(&m, &data, family).unwrap();
            let took = t0.elapsed();
            let three = mtec_identify::lines::identify(&m, &data, 3).unwrap();
            for (name, set) in [("chosen", &id.errors), ("degree 3", &three.errors)] {
                let [p, b, a] = evaluate(&m, &truth, set, seed);
                println!(
                    "{scenario} seed {seed} {name:>8}: pred {p:.3?} rate {:.1?} {:?} ({took:.2?})",
                    [0, 1, 2].map(|i| 100.0 * (1.0 - a[i] / b[i])),
                    id.report.selection.as_ref().map(|s| s.chosen)
                );
            }
            continue;
        }
        if std::env::var_os("ORACLE").is_some() {
            // the best any identification could do if it knew everything but the waviness
            // (resp. neither the waviness nor the bump): compensate with that part of the truth
            let truth = realistic_truth_with(&machine, seed, Mix::default());
            for (name, mix) in [("no ripple", one(1.0, 0.0)), ("neither", one(0.0, 0.0))] {
                let known = with_local_mean_of_ripple(
                    &truth,
                    &realistic_truth_with(&machine, seed, one(1.0, 0.0)),
                    realistic_truth_with(&machine, seed, mix),
                );
                let [p, b, a] = evaluate(&machine, &truth, &known, seed);
                println!(
                    "seed {seed} oracle knowing all but {name:>9}: pred {p:.3?} rate {:.1?}",
                    [0, 1, 2].map(|i| 100.0 * (1.0 - a[i] / b[i]))
                );
            }
            continue;
        }
        let mixes = [
            ("all", Mix::default()),
            ("no bump", one(0.0, 1.0)),
            ("no ripple", one(1.0, 0.0)),
            ("neither", one(0.0, 0.0)),
        ];
        let parts = if std::env::var_os("ALL_ONLY").is_some() {
            1
        } else {
            4
        };
        for (name, mix) in mixes.into_iter().take(parts) {
            let truth = realistic_truth_with(&machine, seed, mix);
            let (csv, _) = measure_runs(&machine, &truth, &lines, &laser, seed, RUNS);
            let data =
                LineData::from_table(&Table::parse(Path::new("lines.csv"), &csv).unwrap()).unwrap();
            let t0 = std::time::Instant::now();
            let id = identify_family(&machine, &data, family).unwrap();
            let took = t0.elapsed();
            let [p, b, a] = evaluate(&machine, &truth, &id.errors, seed);
            if let Ok(name) = std::env::var("CURVE") {
                let e = *truth.elements.keys().find(|e| e.name() == name).unwrap();
                let [lo, hi] = machine.travel(e.axis);
                let mut q = lo;
                while q <= hi {
                    println!(
                        "{q:.1} {:.4} {:.4}",
                        truth.value(&e, q),
                        id.errors.value(&e, q)
                    );
                    q += 1.0;
                }
            }
            if std::env::var_os("COND").is_some() {
                // the least-determined direction of the kept design: which columns it moves
                let svd = id.analysis.kept_r.clone().svd(false, true);
                let v_t = svd.v_t.unwrap();
                let (imin, smin) = svd
                    .singular_values
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.total_cmp(b.1))
                    .unwrap();
                println!(
                    "  smallest singular value {smin:.3e} (largest {:.3e})",
                    svd.singular_values.max()
                );
                for (j, &c) in id.analysis.active.iter().enumerate() {
                    let w = v_t[(imin, j)];
                    if w.abs() > 0.05 {
                        let owner = id
                            .layout
                            .blocks
                            .iter()
                            .find(|b| b.cols().contains(&c))
                            .map_or("slope".to_string(), |b| b.element.name());
                        println!("    col {c} ({owner}): {w:.3}");
                    }
                }
            }
            if std::env::var_os("DIAG").is_some() {
                // what each element costs: the prediction with it replaced by the truth
                for (e, f) in &truth.elements {
                    let mut fixed = id.errors.clone();
                    fixed.insert(*e, f.clone());
                    let [pf, _, _] = evaluate(&machine, &truth, &fixed, seed);
                    println!("  {}: pred {pf:.3?}", e.name());
                }
            }
            let c = id
                .report
                .selection
                .as_ref()
                .map(|s| (s.chosen, s.per_element.clone()));
            println!(
                "seed {seed} {name:>9}: pred {p:.3?} before {b:.2?} after {a:.3?} rate {:.1?} {c:?} ({took:.2?})",
                [0, 1, 2].map(|i| 100.0 * (1.0 - a[i] / b[i]))
            );
        }
    }
}
