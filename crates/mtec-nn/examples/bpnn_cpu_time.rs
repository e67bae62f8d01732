//! CPU time of BPNN 3-10-3 evaluations, for a loaded machine where criterion's wall-clock
//! numbers are dominated by waiting for a core: run under `/usr/bin/time -v` and divide the
//! user time by the printed number of evaluations.
//!
//!     cargo build --release -p mtec-nn --example bpnn_cpu_time
//!     /usr/bin/time -v target/release/examples/bpnn_cpu_time

use mtec_nn::bpnn::{Affine, Bpnn};
use mtec_nn::Activation;
use std::hint::black_box;

fn main() {
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
    let net = Bpnn::from_params(3, 10, 3, Activation::Sigmoid, &inorm, &onorm, &theta);
    let n = 20_000_000u64;
    let start = std::time::Instant::now();
    let mut acc = 0.0;
    for k in 0..n {
        let f = (k % 1000) as f64;
        let e = net.error_um(black_box([f * 0.6, f * 0.8, f * 0.3]));
        acc += e[0] + e[1] + e[2];
    }
    let wall = start.elapsed().as_secs_f64();
    println!(
        "{n} evaluations, wall {:.1} ns each (checksum {acc:.3})",
        wall * 1e9 / n as f64
    );
}
