//! Cost of one volumetric evaluation of the XYFZ machine with its 21 elements (goal: first
//! order < 200 ns).

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use mtec_model::*;

fn set() -> ErrorSet {
    let mut s = ErrorSet::new("bench");
    for (i, e) in three_axis_elements().into_iter().enumerate() {
        let f = if e.location {
            ErrorFunction::constant(20.0)
        } else {
            ErrorFunction::polynomial(vec![0.0, 1e-2 * (i as f64 + 1.0), 1e-5, -1e-8])
        };
        s.insert(e, f);
    }
    s
}

fn bench(c: &mut Criterion) {
    let m = Machine::vmc_xyfz(100.0);
    let vm = VolumetricModel::new(&m, &set());
    let q = [312.0, 456.0, 123.0];
    c.bench_function("volumetric first-order HTM (XYFZ, 21 elements)", |b| {
        b.iter(|| vm.error(black_box(&q), Formalism::Htm, Order::FirstOrder))
    });
    c.bench_function("volumetric first-order POE (XYFZ, 21 elements)", |b| {
        b.iter(|| vm.error(black_box(&q), Formalism::Poe, Order::FirstOrder))
    });
    c.bench_function("volumetric exact HTM (XYFZ, 21 elements)", |b| {
        b.iter(|| vm.error(black_box(&q), Formalism::Htm, Order::Exact))
    });
    c.bench_function("volumetric exact POE (XYFZ, 21 elements)", |b| {
        b.iter(|| vm.error(black_box(&q), Formalism::Poe, Order::Exact))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
