//! Cost of the two evaluations on the scenario files: ISO 230-2 (11 targets × 5 runs × 2) and a
//! circular test (1800 samples per direction: ISO 230-4 values and the full diagnostic fit with
//! the cyclic-pitch scan).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mtec_io::{CsvReader, Table};
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
    // The reader (issue 20): a 4 MB run file (201 targets x 2 x 500 runs) from memory, streamed
    // into PositioningData and, for comparison, read whole into a Table first.
    let mut run = String::from("target_mm,run,direction,deviation_um\n");
    for r in 1..=500 {
        for (dir, off) in [("+", 0.0), ("-", 2.0)] {
            for i in 0..=200 {
                let t = 5.0 * i as f64;
                let x = 5.0 * (t / 100.0).sin() + off + 1e-3 * ((i * 7 + r * 13) % 1000) as f64;
                run.push_str(&format!("{t:.1},{r},{dir},{x:.4}\n"));
            }
        }
    }
    let mut g = c.benchmark_group("iso230-2 reader");
    g.throughput(Throughput::Bytes(run.len() as u64));
    g.sample_size(10);
    g.bench_function("streaming (CsvReader -> PositioningData)", |b| {
        b.iter(|| {
            let r = CsvReader::new(Path::new("run.csv"), run.as_bytes()).unwrap();
            PositioningData::from_reader(r).unwrap()
        })
    });
    g.bench_function("whole table (Table -> PositioningData)", |b| {
        b.iter(|| {
            PositioningData::from_table(&Table::parse(Path::new("run.csv"), &run).unwrap()).unwrap()
        })
    });
    g.finish();

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
