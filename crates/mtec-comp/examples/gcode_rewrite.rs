//! The mtec side of `bench/gcode.sh`: rewrites a G-code program held in memory with a model
//! file (or `zero`, the model that is zero everywhere: every line passes through) and reports
//! the throughput of `mtec_comp::gcode::rewrite` alone (no file reading or writing timed).
//!
//! `gcode_rewrite MODEL|zero IN.ngc OUT.ngc [REPEATS]`: prints one line: lines, the best of
//! REPEATS (default 3) runs as thread CPU time and wall time in seconds, and M lines/s by each.
//! OUT.ngc receives the rewritten program.

use mtec_comp::gcode::{rewrite, RewriteOptions};
use mtec_comp::ErrorModel;
use std::time::Instant;

mod support;
use support::thread_cpu_ns;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: gcode_rewrite MODEL|zero IN.ngc OUT.ngc [REPEATS]");
        std::process::exit(2);
    }
    let model: Box<dyn ErrorModel> = if args[1] == "zero" {
        Box::new(mtec_comp::hand::ZeroModel::new("zero"))
    } else {
        mtec_comp::load_error_model(std::path::Path::new(&args[1]))
            .unwrap_or_else(|e| panic!("{e}"))
    };
    let input = std::fs::read(&args[2]).expect("input program");
    let lines = input.iter().filter(|&&b| b == b'\n').count();
    let repeats: usize = args.get(4).map_or(3, |r| r.parse().expect("REPEATS"));
    let opts = RewriteOptions::default();
    let mut out = Vec::with_capacity(input.len() * 2);
    let (mut cpu, mut wall) = (u64::MAX, f64::INFINITY);
    for _ in 0..repeats.max(1) {
        out.clear();
        let (c0, w0) = (thread_cpu_ns(), Instant::now());
        rewrite(&input[..], &mut out, model.as_ref(), &opts).unwrap_or_else(|e| panic!("{e}"));
        wall = wall.min(w0.elapsed().as_secs_f64());
        cpu = cpu.min(thread_cpu_ns() - c0);
    }
    std::fs::write(&args[3], &out).expect("output program");
    let cpu = cpu as f64 * 1e-9;
    println!(
        "{lines} {cpu:.4} {wall:.4} {:.3} {:.3}",
        lines as f64 / cpu * 1e-6,
        lines as f64 / wall * 1e-6
    );
}
