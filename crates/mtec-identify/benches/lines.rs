//! Identification of the 21 elements of the XYFZ machine from the vmc-9line data: one run
//! (9 lines × 21 points, 27 channels, the size) and the scenario's 3 runs. Parse
//! excluded; design + identifiability + solve included. Issue 3 goal: < 5 ms for one run.

use criterion::{criterion_group, criterion_main, Criterion};
use mtec_identify::lines::{identify, LineData};
use mtec_io::Table;
use mtec_model::Machine;
use std::path::Path;

/// The scenario's line data, all runs.
fn scenario_data() -> LineData {
    let out = mtec_sim::run_scenario("vmc-9line", 1).expect("scenario");
    let csv = &out
        .files
        .iter()
        .find(|f| f.name == "lines.csv")
        .expect("lines")
        .contents;
    LineData::from_table(&Table::parse(Path::new("lines.csv"), csv).expect("csv")).expect("data")
}

/// Run 1 only: 9 lines × 21 points.
fn one_run(all: &LineData) -> LineData {
    LineData {
        channels: all
            .channels
            .iter()
            .filter(|c| c.run == 1)
            .cloned()
            .collect(),
        ..all.clone()
    }
}

fn bench(c: &mut Criterion) {
    let all = scenario_data();
    let data = one_run(&all);
    let m = Machine::vmc_xyfz(100.0);
    // one fit at a fixed degree (the former default): `--degree auto` runs 29–49 choices × 3
    // folds of it (ARCHITECTURE.md, budgets)
    c.bench_function("identify_lines_nine_line_21_points", |b| {
        b.iter(|| identify(&m, &data, 3).expect("identifies"))
    });
    c.bench_function("identify_lines_nine_line_21_points_3_runs", |b| {
        b.iter(|| identify(&m, &all, 3).expect("identifies"))
    });
}

fn stages(c: &mut Criterion) {
    let data = one_run(&scenario_data());
    let m = Machine::vmc_xyfz(100.0);
    let layout = mtec_identify::lines::Layout::new(&m, 3, &data).unwrap();
    c.bench_function("stage_design", |b| {
        b.iter(|| mtec_identify::lines::model::design_matrix(&m, &layout, &data))
    });
    let (a, y) = mtec_identify::lines::model::design_matrix(&m, &layout, &data);
    c.bench_function("stage_analyse", |b| {
        b.iter(|| mtec_identify::lines::identifiability::analyse(&a, &y, &layout))
    });
    c.bench_function("stage_qr", |b| b.iter(|| a.clone().qr()));
}

criterion_group!(benches, bench);
criterion_group!(stage_benches, stages);
criterion_main!(benches, stage_benches);
