//! Cost of the sensitivity methods: EFAST on Ishigami (N = 10000, M = 4) and on the 18-element
//! first-order error model of the XYFZ machine (N = 1200, the source's sample size), and the
//! Sobol analysis with bootstrap. The peer comparison with SALib is `bench/sensitivity.sh`.

use criterion::{criterion_group, criterion_main, Criterion};
use mtec_model::Machine;
use mtec_sensitivity::efast::{self, EfastSettings};
use mtec_sensitivity::error_model::{analyze, ErrorModelProblem, ErrorStatistics, Method};
use mtec_sensitivity::evaluate;
use mtec_sensitivity::sobol::{self, Bootstrap};
use mtec_sensitivity::testfns::{Ishigami, TestFunction};
use std::hint::black_box;

fn ishigami_efast(c: &mut Criterion) {
    let f = Ishigami::default();
    let problem = f.problem();
    let s = EfastSettings {
        n: 10_000,
        m: 4,
        resamples: 1,
        confidence: 0.95,
    };
    c.bench_function(
        "efast ishigami N=10000 M=4 (sample+evaluate+analyze)",
        |b| {
            b.iter(|| {
                let x = efast::sample(&problem, &s, 1).unwrap();
                let y = evaluate(&f, &x).remove(0);
                black_box(efast::analyze(&problem.names, &y, 4, 1, 0.95).unwrap())
            })
        },
    );
}

fn error_model_efast(c: &mut Criterion) {
    let m = Machine::vmc_xyfz(150.0);
    let truth = mtec_sim::truth::geometric_truth(&m, 1);
    let stats = ErrorStatistics::from_error_set(&truth, &m, 601);
    let emp = ErrorModelProblem::new(&m, &stats, &[vec![300.0, 400.0, 150.0]]).unwrap();
    let method = Method::Efast(EfastSettings {
        n: 1200,
        m: 4,
        resamples: 1,
        confidence: 0.95,
    });
    c.bench_function("efast error model 18 elements N=1200, 4 outputs", |b| {
        b.iter(|| black_box(analyze(&emp, &method, 1, 25.0, 2.0).unwrap()))
    });
}

fn sobol_bootstrap(c: &mut Criterion) {
    let f = Ishigami::default();
    let problem = f.problem();
    let x = sobol::sample(&problem, 4096, 1).unwrap();
    let y = evaluate(&f, &x).remove(0);
    c.bench_function("sobol analyze ishigami N=4096, 100 bootstrap", |b| {
        b.iter(|| black_box(sobol::analyze(&problem.names, &y, &Bootstrap::default()).unwrap()))
    });
}

criterion_group!(benches, ishigami_efast, error_model_efast, sobol_bootstrap);
criterion_main!(benches);
