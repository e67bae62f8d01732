//! Confidence intervals of every index: they cover what they claim at the stated rate over
//! repeated seeds, and they shrink as the design grows. (Agreement with SALib's own intervals on
//! SALib's resampling: `salib_fixtures.rs`.)

use mtec_sensitivity::testfns::{Ishigami, TestFunction};
use mtec_sensitivity::{efast, evaluate, morris, sobol, Bootstrap};

/// Share of the (estimate, half width, target) triples whose interval contains the target.
fn coverage(hits: usize, trials: usize) -> f64 {
    hits as f64 / trials as f64
}

/// Sobol: the bootstrap intervals at 95 % cover the analytic Ishigami S1 and ST in at least
/// 93 % of 60 seeds × 6 indices (binomial sd at 95 %: 1.1 %). On the scrambled Sobol sequence
/// the bootstrap, which treats the points as independent, is conservative: 97–100 % measured
/// (docs/methods.md), so only the lower bound is a claim.
#[test]
fn sobol_intervals_cover_the_analytic_ishigami_indices() {
    let f = Ishigami::default();
    let p = f.problem();
    let (a1, at) = (f.analytic_s1(), f.analytic_st());
    let (mut hits, mut trials) = (0, 0);
    for seed in 0..60 {
        let x = sobol::sample(&p, 256, seed).unwrap();
        let y = evaluate(&f, &x).remove(0);
        let b = Bootstrap {
            resamples: 100,
            confidence: 0.95,
            seed,
        };
        let ix = sobol::analyze(&p.names, &y, &b).unwrap().indices;
        let (c1, ct) = (ix.s1_conf.unwrap(), ix.st_conf.unwrap());
        for i in 0..3 {
            hits += ((ix.s1[i] - a1[i]).abs() <= c1[i]) as usize;
            hits += ((ix.st[i] - at[i]).abs() <= ct[i]) as usize;
            trials += 2;
        }
    }
    let c = coverage(hits, trials);
    eprintln!("sobol N=256 coverage of the analytic indices {c:.3}");
    assert!(c >= 0.93, "coverage {c}");
}

/// EFAST: the Student-t interval of the mean of R = 10 random-phase replicates covers the
/// expectation of the EFAST estimator (the mean of 400 independent replicates) at the stated
/// 95 %: within [0.90, 0.985] over 100 seeds × 6 indices (binomial sd 0.9 %; 0.932 measured;
/// an interval without the 1/√R would cover nearly always). It does not cover
/// the analytic indices: EFAST's interference bias with M = 4 (ST of x2 0.470 for 0.442) is
/// deterministic, far above the phase spread, and no replicate interval contains it — the
/// documented limitation of the method (docs/methods.md).
#[test]
fn efast_replicate_intervals_cover_the_estimators_expectation() {
    let f = Ishigami::default();
    let p = f.problem();
    let (n, m) = (300, 4);
    let design = |resamples| efast::EfastSettings {
        n,
        m,
        resamples,
        confidence: 0.95,
    };
    let run = |resamples, seed| {
        let x = efast::sample(&p, &design(resamples), seed).unwrap();
        let y = evaluate(&f, &x).remove(0);
        efast::analyze(&p.names, &y, m, resamples, 0.95).unwrap()
    };
    let reference = run(400, 999);
    let (mut hits, mut trials) = (0, 0);
    for seed in 0..100 {
        let ix = run(10, seed);
        let (c1, ct) = (ix.s1_conf.unwrap(), ix.st_conf.unwrap());
        for i in 0..3 {
            hits += ((ix.s1[i] - reference.s1[i]).abs() <= c1[i]) as usize;
            hits += ((ix.st[i] - reference.st[i]).abs() <= ct[i]) as usize;
            trials += 2;
        }
    }
    let c = coverage(hits, trials);
    eprintln!(
        "efast N={n} M={m} R=10 coverage of E[estimate] {c:.3}; E[S1] {:?} E[ST] {:?}",
        reference.s1, reference.st
    );
    assert!((0.90..=0.985).contains(&c), "coverage {c}");
    // the bias the interval does not contain, stated: |E[ST2] − 0.4424| ≈ 0.027
    let bias = (reference.st[1] - f.analytic_st()[1]).abs();
    assert!(bias > 0.01 && bias < 0.04, "ST2 bias {bias}");
}

/// Sum of the half widths of S1 and ST.
fn total(ix: &mtec_sensitivity::Indices) -> f64 {
    ix.s1_conf.as_ref().unwrap().iter().sum::<f64>()
        + ix.st_conf.as_ref().unwrap().iter().sum::<f64>()
}

/// The bootstrap intervals shrink as 1/√N: 16× the base points (Sobol) or trajectories
/// (Morris) give a quarter of the width (accepted 0.15–0.40); 4× the EFAST replicates give
/// about half (√4 and t_{39}/t_{9}: 0.45, accepted 0.25–0.75 for the spread of an sd from 10).
#[test]
fn intervals_shrink_as_the_design_grows() {
    let f = Ishigami::default();
    let p = f.problem();
    let b = Bootstrap::default();
    let sobol_at = |n| {
        let x = sobol::sample(&p, n, 3).unwrap();
        let y = evaluate(&f, &x).remove(0);
        total(&sobol::analyze(&p.names, &y, &b).unwrap().indices)
    };
    let r = sobol_at(4096) / sobol_at(256);
    assert!((0.15..=0.40).contains(&r), "sobol width ratio {r}");

    let morris_at = |t| {
        let s = morris::MorrisSettings {
            trajectories: t,
            levels: 4,
            bootstrap: b,
        };
        let d = morris::sample(&p, &s, 3).unwrap();
        let y = evaluate(&f, &d.samples).remove(0);
        let ix = morris::analyze(&p.names, &d, &y, &b).unwrap();
        ix.mu_star_conf.unwrap().iter().sum::<f64>()
    };
    let r = morris_at(800) / morris_at(50);
    assert!((0.15..=0.40).contains(&r), "morris width ratio {r}");

    let efast_at = |resamples| {
        let s = efast::EfastSettings {
            n: 1000,
            m: 4,
            resamples,
            confidence: 0.95,
        };
        let x = efast::sample(&p, &s, 3).unwrap();
        let y = evaluate(&f, &x).remove(0);
        total(&efast::analyze(&p.names, &y, 4, resamples, 0.95).unwrap())
    };
    let r = efast_at(40) / efast_at(10);
    assert!((0.25..=0.75).contains(&r), "efast width ratio {r}");
}

/// A confidence level outside (0, 1) is refused by every method, not silently used.
#[test]
fn confidence_level_outside_0_1_is_refused() {
    let f = Ishigami::default();
    let p = f.problem();
    let x = sobol::sample(&p, 64, 1).unwrap();
    let y = evaluate(&f, &x).remove(0);
    for c in [0.0, 1.0, 1.5, f64::NAN] {
        let b = Bootstrap {
            confidence: c,
            ..Bootstrap::default()
        };
        assert!(sobol::analyze(&p.names, &y, &b).is_err(), "{c}");
    }
    let s = efast::EfastSettings::default();
    let x = efast::sample(&p, &s, 1).unwrap();
    let y = evaluate(&f, &x).remove(0);
    assert!(efast::analyze(&p.names, &y, 4, 10, 1.0).is_err());
}
