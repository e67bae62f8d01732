//! Trilinear map evaluation and correction speed (issue 8 target: ≤ 100 ns per point).
//! The grid and points are the SciPy fixture's (tests/map_fixtures), so `bench/interp.sh` can
//! compare the same work with SciPy's RegularGridInterpolator.

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use mtec_comp::map::{GridLimits, GridMap, Outside};
use mtec_comp::ErrorModel;
use std::path::PathBuf;

fn grid_25() -> GridMap {
    // a controller-size grid: 25 points per axis over 600 × 400 × 300 mm
    let axis = |len: f64| (0..25).map(|i| len * i as f64 / 24.0).collect::<Vec<f64>>();
    let axes = [axis(600.0), axis(400.0), axis(300.0)];
    let mut values = Vec::new();
    for &x in &axes[0] {
        for &y in &axes[1] {
            for &z in &axes[2] {
                values.push([(x / 90.0).sin(), (y / 70.0).cos(), 1e-5 * x * y + z * 1e-3]);
            }
        }
    }
    GridMap::new(axes, values, Outside::Clamp, "bench").unwrap()
}

fn points(n: usize, box_mm: [f64; 3]) -> Vec<[f64; 3]> {
    let mut s = 0x9E3779B97F4A7C15u64;
    let mut u = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| [box_mm[0] * u(), box_mm[1] * u(), box_mm[2] * u()])
        .collect()
}

fn bench(c: &mut Criterion) {
    let map = grid_25();
    let pts = points(100_000, [600.0, 400.0, 300.0]);
    let mut g = c.benchmark_group("trilinear");
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("grid25_eval_100k_points", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for p in &pts {
                let e = map.error_um(black_box(*p));
                acc += e[0] + e[1] + e[2];
            }
            acc
        })
    });
    let opts = mtec_comp::CorrectionOptions::default();
    g.bench_function("grid25_correction_100k_points", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for p in &pts {
                let q = mtec_comp::command_for_target(&map, black_box(*p), &opts).unwrap();
                acc += q[0];
            }
            acc
        })
    });
    // the SciPy comparison grid (tests/map_fixtures/grid.csv, 6×5×4 nodes)
    let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/map_fixtures/grid.csv");
    let small = GridMap::read_csv(&fixture, &GridLimits::default(), Outside::Extrapolate).unwrap();
    let pts2: Vec<[f64; 3]> = points(100_000, [500.0, 500.0, 300.0])
        .into_iter()
        .map(|p| [p[0], p[1] - 200.0, p[2] - 300.0])
        .collect();
    g.bench_function("fixture_grid_eval_100k_points", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for p in &pts2 {
                let e = small.error_um(black_box(*p));
                acc += e[0];
            }
            acc
        })
    });
    g.finish();
    // the threaded batch (issue 22 "each at its best"): wall time, as threads are the point
    let pts = points(1_000_000, [600.0, 400.0, 300.0]);
    let mut out = vec![[0.0; 3]; pts.len()];
    let mut g = c.benchmark_group("trilinear_batch_wall");
    g.sample_size(20);
    g.throughput(Throughput::Elements(pts.len() as u64));
    for threads in [1, 2] {
        g.bench_function(
            format!("grid25_eval_batch_1m_points_{threads}_threads"),
            |b| {
                b.iter(|| {
                    mtec_comp::eval_batch_threads(&map, black_box(&pts), &mut out, threads);
                    out[0][0]
                })
            },
        );
    }
    g.finish();
}

/// CPU time of the benchmarking thread (Linux `/proc/thread-self/schedstat`, ns on CPU), so that
/// results stay meaningful on a machine shared with other jobs, where wall time counts the time
/// the thread waited for a core.
struct ThreadCpu;

fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

static WALL: WallTime = WallTime;

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = u64;
    fn start(&self) -> u64 {
        thread_cpu_ns()
    }
    fn end(&self, i: u64) -> u64 {
        thread_cpu_ns().saturating_sub(i)
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, v: &u64) -> f64 {
        *v as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        WALL.formatter()
    }
}

fn bench_cpu(c: &mut Criterion<ThreadCpu>) {
    let map = grid_25();
    let pts = points(100_000, [600.0, 400.0, 300.0]);
    let mut g = c.benchmark_group("trilinear_cpu");
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("grid25_eval_100k_points", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for p in &pts {
                let e = map.error_um(black_box(*p));
                acc += e[0] + e[1] + e[2];
            }
            acc
        })
    });
    let opts = mtec_comp::CorrectionOptions::default();
    g.bench_function("grid25_correction_100k_points", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for p in &pts {
                let q = mtec_comp::command_for_target(&map, black_box(*p), &opts).unwrap();
                acc += q[0];
            }
            acc
        })
    });
    g.finish();
    // the batch API on 1 M points (issue 22: ≤ 10 ms), and the per-point loop on the same points
    let pts = points(1_000_000, [600.0, 400.0, 300.0]);
    let mut out = vec![[0.0; 3]; pts.len()];
    let model: &dyn ErrorModel = &map;
    let mut g = c.benchmark_group("trilinear_batch_cpu");
    g.sample_size(20);
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("grid25_eval_batch_1m_points", |b| {
        b.iter(|| {
            model.eval_batch(black_box(&pts), &mut out);
            out[0][0]
        })
    });
    g.bench_function("grid25_error_um_loop_1m_points", |b| {
        b.iter(|| {
            for (o, p) in out.iter_mut().zip(black_box(&pts)) {
                *o = model.error_um(*p);
            }
            out[0][0]
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_group! {
    name = cpu;
    config = Criterion::default().with_measurement(ThreadCpu);
    targets = bench_cpu
}
criterion_main!(benches, cpu);
