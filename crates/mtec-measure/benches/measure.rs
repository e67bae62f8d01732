//! Cost of the two evaluations on the scenario files: ISO 230-2 (11 targets × 5 runs × 2) and a
//! circular test (1800 samples per direction: ISO 230-4 values and the full diagnostic fit with
//! the cyclic-pitch scan).

use criterion::{criterion_group, criterion_main, Criterion};
use mtec_io::Table;
use mtec_measure::circular::{diagnose, evaluate, CircularTrace, DiagnosticsConfig, TraceOptions};
use mtec_measure::{evaluate_iso230_2, PositioningData};
use std::path::Path;

fn file(scenario: &str, name: &str) -> Table {
    let out = mtec_sim::run_scenario(scenario, 1).unwrap();
    let f = out.files.iter().find(|f| f.name == name).unwrap();
    Table::parse(Path::new(name), &f.contents).unwrap()
}

fn bench(c: &mut Criterion) {
    let t = file("iso230-2", "iso230-2.csv");
    c.bench_function("iso230-2 read+evaluate", |b| {
        b.iter(|| evaluate_iso230_2(&PositioningData::from_table(&t).unwrap()))
    });
    let t = file("circular-test", "circular.csv");
    let trace = CircularTrace::from_table(&t, &TraceOptions::default()).unwrap();
    c.bench_function("iso230-4 values (2 x 1800 samples)", |b| {
        b.iter(|| evaluate(&trace))
    });
    let cfg = DiagnosticsConfig::default();
    let mut g = c.benchmark_group("diagnostics");
    g.sample_size(10);
    g.bench_function("ballbar diagnostics (2 x 1800 samples)", |b| {
        b.iter(|| diagnose(&trace, &cfg).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
