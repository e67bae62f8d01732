//! The mtec side of `bench/interp.sh`: evaluates a model file at points with one
//! `ErrorModel::eval_batch` call and reports the cost per point.
//!
//! `map_batch MODEL POINTS.f64 OUT.f64 [REPEATS [THREADS]]`: POINTS.f64 holds N×3 little-endian
//! f64 (x, y, z in mm, row after row), OUT.f64 receives N×3 f64 (ex, ey, ez in µm). Prints one
//! line: the best of REPEATS (default 3) calls in ns per point, thread CPU time and wall time.
//! THREADS (default 1) > 1 evaluates through `mtec_comp::eval_batch_threads`; the CPU column
//! is then `-` (one thread's clock says nothing about the others) and only wall time counts.

use std::time::Instant;

mod support;
use support::thread_cpu_ns;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: map_batch MODEL POINTS.f64 OUT.f64 [REPEATS]");
        std::process::exit(2);
    }
    let model = mtec_comp::load_error_model(std::path::Path::new(&args[1]))
        .unwrap_or_else(|e| panic!("{e}"));
    let bytes = std::fs::read(&args[2]).expect("points file");
    let points: Vec<[f64; 3]> = bytes
        .chunks_exact(24)
        .map(|c| {
            let f = |i: usize| f64::from_le_bytes(c[8 * i..8 * i + 8].try_into().unwrap());
            [f(0), f(1), f(2)]
        })
        .collect();
    let repeats: usize = args.get(4).map_or(3, |r| r.parse().expect("REPEATS"));
    let threads: usize = args.get(5).map_or(1, |t| t.parse().expect("THREADS"));
    let mut out = vec![[0.0; 3]; points.len()];
    let (mut cpu, mut wall) = (u64::MAX, f64::INFINITY);
    for _ in 0..repeats.max(1) {
        let (c0, w0) = (thread_cpu_ns(), Instant::now());
        mtec_comp::eval_batch_threads(model.as_ref(), &points, &mut out, threads);
        wall = wall.min(w0.elapsed().as_secs_f64() * 1e9);
        cpu = cpu.min(thread_cpu_ns() - c0);
    }
    let bytes: Vec<u8> = out
        .as_flattened()
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(&args[3], bytes).expect("output file");
    let n = points.len() as f64;
    if threads > 1 {
        println!("- {:.3}", wall / n);
    } else {
        println!("{:.3} {:.3}", cpu as f64 / n, wall / n);
    }
}
