//! G-code rewriting throughput on one core (issue 8 targets: pass-through ≥ 1 M lines/s,
//! with compensation ≥ 200 k lines/s).
//!
//! Input: a synthetic program of 200 000 short feed moves like contour.ngc's (0.05 mm steps
//! around a 50 mm circle in mm, with line numbers), rewritten into memory.
//! `cargo bench -p mtec-comp --bench gcode`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mtec_comp::gcode::{rewrite, RewriteOptions};
use mtec_comp::hand::ZeroModel;
use mtec_comp::ErrorModel;
use mtec_comp::{GridMap, Outside};
use std::hint::black_box;

/// The analytic test model (linear + quadratic), as in the tests.
struct Poly;
impl ErrorModel for Poly {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = p;
        [
            8.0 + 0.030 * x - 0.010 * y + 2e-4 * x * y + 1e-4 * z * z,
            -4.0 + 0.020 * y + 1e-4 * x * x - 0.005 * z,
            3.0 + 0.010 * z + 5e-5 * (x * x + y * y),
        ]
    }
    fn describe(&self) -> String {
        "poly".into()
    }
}

fn program(lines: usize) -> Vec<u8> {
    let mut s = String::from("G21 G90 G17\nG0 X50 Y0 Z1\nG1 Z-1 F1000\n");
    let r = 50.0;
    for i in 0..lines {
        let a = i as f64 * 0.001;
        s.push_str(&format!(
            "N{} G01 X{:.4} Y{:.4}\n",
            i + 10,
            r * a.cos(),
            r * a.sin()
        ));
    }
    s.into_bytes()
}

fn bench(c: &mut Criterion) {
    let n = 200_000;
    let input = program(n);
    let lines = input.iter().filter(|&&b| b == b'\n').count() as u64;
    let opts = RewriteOptions::default();
    let mut out = Vec::with_capacity(input.len() * 2);
    let mut g = c.benchmark_group("gcode");
    g.throughput(Throughput::Elements(lines));
    g.sample_size(10);
    let zero = ZeroModel::new("zero");
    g.bench_function("pass_through_zero_model", |b| {
        b.iter(|| {
            out.clear();
            rewrite(black_box(&input[..]), &mut out, &zero, &opts).unwrap();
        })
    });
    g.bench_function("compensate_poly_model", |b| {
        b.iter(|| {
            out.clear();
            rewrite(black_box(&input[..]), &mut out, &Poly, &opts).unwrap();
        })
    });
    // the controller-style case: a 25 × 25 × 3 trilinear map over the program (5 mm cells),
    // where each piece's path bound is solved exactly per cell crossed
    let xs: Vec<f64> = (0..25).map(|i| -60.0 + 5.0 * i as f64).collect();
    let zs = vec![-5.0, 0.0, 5.0];
    let mut values = Vec::new();
    for &x in &xs {
        for &y in &xs {
            for &z in &zs {
                values.push([
                    8.0 + 0.03 * x - 0.01 * y + 2e-4 * x * y,
                    -4.0 + 0.02 * y + 1e-4 * x * x,
                    3.0 + 0.01 * z,
                ]);
            }
        }
    }
    let map = GridMap::new([xs.clone(), xs, zs], values, Outside::Clamp, "bench").unwrap();
    g.bench_function("compensate_trilinear_map", |b| {
        b.iter(|| {
            out.clear();
            rewrite(black_box(&input[..]), &mut out, &map, &opts).unwrap();
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
