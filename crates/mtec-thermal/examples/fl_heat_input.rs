//! Nested leave-one-block-out of the `heat-input` model on the real fl-thermal record.
//!
//! Run: cargo run --release -p mtec-thermal --example fl_heat_input [-- PATH/train_1min.csv [OUT_DIR]]
//! Outer folds: the eight 4-h run and rest blocks; in each, the heat-input fitter chooses α, the τ
//! bank, k and the ambient sensors by leave-one-block-out on the seven training blocks only
//! (nested), then predicts the left-out block. Prints the pooled RMSE (µm) next to all-sensor MLR
//! on the same folds. With OUT_DIR, fits each channel on all blocks and writes the model files.

use mtec_io::Table;
use mtec_thermal::heat_input::with_input;
use mtec_thermal::validate::{block_cv, time_blocks};
use mtec_thermal::{Fit, HeatInput, Mlr, Predict, ThermalData, MODEL_FORMAT};
use mtec_thermal::{ModelFile, Split, ThermalModel};
use std::path::PathBuf;

const BLOCK_MIN: f64 = 240.0;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/fl-thermal/train_1min.csv")
    });
    let out = args.next().map(PathBuf::from);
    let table = Table::read(&path).expect("readable file");
    let rpm = table.f64_column("spindle_rpm").expect("spindle_rpm column");
    // MTEC_REST_FACTORS=1 reproduces the model without rest time constants (before/after)
    let rest_factors: Vec<f64> = std::env::var("MTEC_REST_FACTORS")
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.parse().ok()).collect())
        .unwrap_or_else(|| HeatInput::default().rest_factors);
    let fitter = HeatInput {
        block_min: Some(BLOCK_MIN),
        rest_factors,
        ..Default::default()
    };
    println!("nested leave-one-block-out RMSE (um), 8 blocks of {BLOCK_MIN} min");
    println!(
        "{:<4} {:>8} {:>10}  chosen on all blocks",
        "ch", "MLR-16", "heat-input"
    );
    for ch in 1..=5 {
        let d0 = ThermalData::from_table(&table, Some(&format!("ch{ch}_um")), true).unwrap();
        let d = with_input(&d0, "spindle_rpm", &rpm).unwrap();
        let blocks = time_blocks(&d0, BLOCK_MIN);
        let mlr = block_cv(&Mlr::default(), &d0, &blocks)
            .unwrap()
            .pooled_rmse_um;
        let hi = block_cv(&fitter, &d, &blocks).unwrap().pooled_rmse_um;
        let m = fitter.fit(&d).unwrap();
        println!(
            "ch{ch}  {mlr:>8.3} {hi:>10.3}  α={} τ={:?} rest×{} k={} ambient={:?} lag {:?}",
            m.alpha, m.taus_min, m.rest_tau_factor, m.k, m.ambient_sensors, m.ambient_lag_min
        );
        if let Some(dir) = &out {
            let train_metrics = m.evaluate(&d).unwrap();
            let model = ThermalModel::HeatInput(m);
            let all: Vec<usize> = (0..d.len()).collect();
            let file = ModelFile {
                format: MODEL_FORMAT.into(),
                target: format!("ch{ch}_um"),
                envelope: mtec_thermal::guard::envelope(&model, &d, &all),
                warnings: model.warnings(),
                model,
                validation: None,
                candidates: Vec::new(),
                split: Split {
                    train_experiments: d.experiments(),
                    train_rows: d.len(),
                    ..Default::default()
                },
                train_metrics,
                test_metrics: None,
            };
            let p = dir.join(format!("ch{ch}_heat_input.json"));
            std::fs::write(&p, serde_json::to_string_pretty(&file).unwrap()).unwrap();
        }
    }
}
