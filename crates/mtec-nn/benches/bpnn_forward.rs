//! Cost of one BPNN 3-10-3 evaluation (goal ≤ 200 ns per point): the plain-Rust forward pass
//! that compensation calls per interpolation cycle.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use mtec_nn::bpnn::{Affine, Bpnn};
use mtec_nn::Activation;

fn net() -> Bpnn {
    let inorm = Affine {
        offset: vec![300.0, 400.0, 150.0],
        scale: vec![300.0, 400.0, 150.0],
    };
    let onorm = Affine {
        offset: vec![5.0, 4.0, 3.0],
        scale: vec![4.0, 3.0, 2.0],
    };
    let theta: Vec<f64> = (0..73)
        .map(|k| ((k * 37 % 17) as f64 - 8.0) / 8.0)
        .collect();
    Bpnn::from_params(3, 10, 3, Activation::Sigmoid, &inorm, &onorm, &theta)
}

fn bench(c: &mut Criterion) {
    let n = net();
    let pts: Vec<[f64; 3]> = (0..1000)
        .map(|k| [k as f64 * 0.6, k as f64 * 0.8, k as f64 * 0.3])
        .collect();
    c.bench_function("bpnn_3_10_3_error_um_per_point", |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) % pts.len();
            black_box(n.error_um(black_box(pts[i])))
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
