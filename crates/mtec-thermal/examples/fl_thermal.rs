//! Block cross-validation of thermal models on the real fl-thermal record (examples/fl-thermal).
//!
//! Run: cargo run --release -p mtec-thermal --example fl_thermal [-- PATH/train_1min.csv]
//! Blocks: the eight 4-h run and rest blocks (runs at 1250, 2500, 3750, 5000 rpm, each followed by
//! a rest; the 7 min of the 3500 rpm run at the end join the last rest). Each block is predicted by
//! a model fitted on the other seven. Prints the pooled RMSE (µm) of every model on every
//! displacement channel:
//! - MLR on all 16 sensors (the baseline);
//! - ridge-select (the source method: ridge-trace sensor elimination);
//! - lag-select, nested: the sensors, lags and time constants chosen inside each fold by
//!   leave-one-block-out on its seven training blocks (fully honest, and noisy);
//! - lag-select structure: sensors and time constants chosen once on all eight blocks, the
//!   coefficients refitted in each fold (the model one would ship; its CV is optimistic about the
//!   choice of sensors, not about the coefficients).

use mtec_io::Table;
use mtec_thermal::lag_select::OlsOnFeatures;
use mtec_thermal::validate::{block_cv, time_blocks};
use mtec_thermal::{Fit, LagSelect, Mlr, RidgeSelect, ThermalData};
use std::path::PathBuf;

const BLOCK_MIN: f64 = 240.0;

fn main() {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../examples/fl-thermal/train_1min.csv")
        });
    let table = Table::read(&path).expect("readable file");
    let sel = |d: &ThermalData| {
        LagSelect {
            block_min: Some(BLOCK_MIN),
            max_sensors: 3,
            ..Default::default()
        }
        .fit(d)
        .expect("selection")
    };
    let mut rows: Vec<(String, Vec<f64>)> = vec![
        ("MLR all 16 sensors".into(), vec![]),
        ("ridge-select".into(), vec![]),
        ("lag-select, nested".into(), vec![]),
        ("lag-select structure".into(), vec![]),
    ];
    let mut structures = Vec::new();
    for ch in 1..=5 {
        let d = ThermalData::from_table(&table, Some(&format!("ch{ch}_um")), true).unwrap();
        rows[0].1.push(cv(&Mlr::default(), &d));
        rows[1].1.push(cv(&RidgeSelect::default(), &d));
        rows[2].1.push(cv(
            &LagSelect {
                block_min: Some(BLOCK_MIN),
                ..Default::default()
            },
            &d,
        ));
        let m = sel(&d);
        rows[3].1.push(cv(
            &OlsOnFeatures {
                features: m.features.clone(),
            },
            &d,
        ));
        structures.push((ch, m.features.iter().map(|f| f.name()).collect::<Vec<_>>()));
    }
    println!("leave-one-block-out RMSE (um), 8 blocks of {BLOCK_MIN} min");
    print!("{:<24}", "model");
    for ch in 1..=5 {
        print!(" {:>7}", format!("ch{ch}"));
    }
    println!();
    for (name, v) in &rows {
        print!("{name:<24}");
        for x in v {
            print!(" {x:>7.3}");
        }
        println!();
    }
    for (ch, f) in structures {
        println!("ch{ch}: {}", f.join(" + "));
    }
}

fn cv<F: Fit>(f: &F, d: &ThermalData) -> f64 {
    let blocks = time_blocks(d, BLOCK_MIN);
    match block_cv(f, d, &blocks) {
        Ok(r) => r.pooled_rmse_um,
        Err(e) => {
            eprintln!("{e}");
            f64::NAN
        }
    }
}
