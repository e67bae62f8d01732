//! Identification of the 21 elements of the XYFZ machine from the vmc-9line data
//! (9 lines × 21 points, 27 channels): parse excluded, design + identifiability + solve included.
//! Issue 3 goal: < 5 ms.

use criterion::{criterion_group, criterion_main, Criterion};
use mtec_identify::lines::{identify, LineData, DEFAULT_DEGREE};
use mtec_io::Table;
use mtec_model::Machine;
use std::path::Path;

fn bench(c: &mut Criterion) {
    let out = mtec_sim::run_scenario("vmc-9line", 1).expect("scenario");
    let csv = &out
        .files
        .iter()
        .find(|f| f.name == "lines.csv")
        .expect("lines")
        .contents;
    let data = LineData::from_table(&Table::parse(Path::new("lines.csv"), csv).expect("csv"))
        .expect("data");
    let m = Machine::vmc_xyfz(100.0);
    c.bench_function("identify_lines_nine_line_21_points", |b| {
        b.iter(|| identify(&m, &data, DEFAULT_DEGREE).expect("identifies"))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
