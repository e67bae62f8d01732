//! In-process timing of EFAST on the Ishigami function for `bench/sensitivity.sh`: the whole
//! analysis (sampling, evaluation, analysis with intervals), repeated, and the median time.
//!
//!   cargo run --release -p mtec-sensitivity --example bench_efast -- N M R REPS
//!
//! Prints one JSON line: `median_s`, `min_s`, the indices and their half widths. Threads: set
//! `RAYON_NUM_THREADS` (the bench script runs 1 and 2).

use mtec_sensitivity::efast::{self, EfastSettings};
use mtec_sensitivity::evaluate;
use mtec_sensitivity::testfns::{Ishigami, TestFunction};
use std::time::Instant;

fn main() {
    let a: Vec<usize> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("N M R REPS: whole numbers"))
        .collect();
    let [n, m, r, reps] = a[..] else {
        eprintln!("usage: bench_efast N M R REPS");
        std::process::exit(2);
    };
    let f = Ishigami::default();
    let problem = f.problem();
    let s = EfastSettings {
        n,
        m,
        resamples: r,
        confidence: 0.95,
    };
    let run = || {
        let x = efast::sample(&problem, &s, 1).unwrap();
        let y = evaluate(&f, &x).remove(0);
        efast::analyze(&problem.names, &y, m, r, 0.95).unwrap()
    };
    let mut last = run(); // warm-up (thread pool, FFT plans, page faults)
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        last = std::hint::black_box(run());
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let out = serde_json::json!({
        "median_s": times[times.len() / 2],
        "min_s": times[0],
        "S1": last.s1, "ST": last.st, "S1_conf": last.s1_conf, "ST_conf": last.st_conf,
    });
    println!("{out}");
}
