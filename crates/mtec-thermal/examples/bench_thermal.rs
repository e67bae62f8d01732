//! Timing of the ridge trace (100 values of k) and of the VIF table on a thermal log, for
//! `bench/thermal.sh` (which times scikit-learn and statsmodels on the same file and prints the
//! ratio). Prints `ridge_trace_s=<seconds>` and `vif_s=<seconds>` (best of repeated runs), then
//! `outputs=<JSON>`: the k grid, the standardised trace coefficients and the VIFs.
//!
//! Run: cargo run --release -p mtec-thermal --example bench_thermal -- FILE.csv TARGET

use mtec_io::Table;
use mtec_thermal::linear::{vif, RidgeProblem};
use mtec_thermal::select::{k_grid, RidgeTrace};
use mtec_thermal::ThermalData;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

fn best_of<F: FnMut()>(mut f: F) -> f64 {
    let mut best = f64::INFINITY;
    let start = Instant::now();
    let mut reps = 0;
    while reps < 3 || (start.elapsed().as_secs_f64() < 2.0 && reps < 1000) {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
        reps += 1;
    }
    best
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(args.next().expect("usage: bench_thermal FILE.csv TARGET"));
    let target = args.next().unwrap_or_else(|| "ch1_um".into());
    let table = Table::read(&path).expect("readable thermal log");
    let d = ThermalData::from_table(&table, Some(&target), true).expect("thermal columns");
    let y = d.target_um().unwrap().to_vec();
    let ks = k_grid();
    let trace_s = best_of(|| {
        let p = RidgeProblem::new(&d.temps_c, &y, &d.sensor_names).unwrap();
        black_box(RidgeTrace::compute(&p, &d.sensor_names, &ks));
    });
    let vif_s = best_of(|| {
        black_box(vif(&d.temps_c, &d.sensor_names).unwrap());
    });
    println!("rows={} sensors={}", d.len(), d.sensor_names.len());
    println!("ridge_trace_s={trace_s:.6e}");
    println!("vif_s={vif_s:.6e}");
    // the outputs, for the bench script's agreement check with its Python peers
    let p = RidgeProblem::new(&d.temps_c, &y, &d.sensor_names).unwrap();
    let trace = RidgeTrace::compute(&p, &d.sensor_names, &ks);
    let v = vif(&d.temps_c, &d.sensor_names).unwrap();
    println!(
        "outputs={}",
        serde_json::json!({"k": ks, "trace": trace.coefficients, "vif": v})
    );
}
