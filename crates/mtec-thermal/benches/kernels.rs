//! Cost of the thermal kernels of issue 22 on the fl-thermal training record: the ridge trace
//! (standardisation, blocked QR, SVD of the 16 × 16 R, 100 values of k) and the VIF table (blocked
//! QR of the centred design, R⁻¹). The peer comparison with numpy and scikit-learn is
//! `bench/thermal.sh`. Data: `$MTEC_SHARED_DIR/data/fl-thermal/train.csv` (15 s sampling, 7709
//! rows) when present, else `shared/` beside the checkout, else the 1-min copy in `examples/`.

use criterion::{criterion_group, criterion_main, Criterion};
use mtec_io::Table;
use mtec_thermal::linear::{vif, RidgeProblem};
use mtec_thermal::select::{k_grid, RidgeTrace};
use mtec_thermal::ThermalData;
use std::hint::black_box;
use std::path::PathBuf;

fn data_file() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let shared = std::env::var_os("MTEC_SHARED_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("../shared"));
    let full = shared.join("data/fl-thermal/train.csv");
    if full.is_file() {
        full
    } else {
        root.join("examples/fl-thermal/train_1min.csv")
    }
}

fn thermal_kernels(c: &mut Criterion) {
    let path = data_file();
    let table = Table::read(&path).expect("readable thermal log");
    let d = ThermalData::from_table(&table, Some("ch1_um"), true).expect("thermal columns");
    let y = d.target_um().unwrap().to_vec();
    let ks = k_grid();
    let what = format!("{} rows x {} sensors", d.len(), d.sensor_names.len());
    c.bench_function(&format!("ridge trace 100 k, {what}"), |b| {
        b.iter(|| {
            let p = RidgeProblem::new(&d.temps_c, &y, &d.sensor_names).unwrap();
            black_box(RidgeTrace::compute(&p, &d.sensor_names, &ks))
        })
    });
    c.bench_function(&format!("VIF, {what}"), |b| {
        b.iter(|| black_box(vif(&d.temps_c, &d.sensor_names).unwrap()))
    });
}

criterion_group!(benches, thermal_kernels);
criterion_main!(benches);
