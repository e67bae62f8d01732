//! `auto` on the real fl-thermal record with the forward protocol of issue 17: fit on the first
//! 24 h (every choice made by rolling forward folds inside them), score the last 8 h.
//!
//! Run: cargo run --release -p mtec-thermal --example fl_auto [-- PATH/train.csv [HOURS]]
//! Prints, per channel, every candidate's inner forward score (mean fold RMSE ± standard error,
//! worst fold against no compensation), the chosen family, its test RMSE on the held-out hours
//! and the RMS of the raw drift there.

use mtec_io::Table;
use mtec_thermal::auto::Auto;
use mtec_thermal::heat_input::with_input;
use mtec_thermal::metrics::rms;
use mtec_thermal::validate::split_at_time;
use mtec_thermal::{Predict, ThermalData};
use std::path::PathBuf;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/fl-thermal/train_1min.csv")
    });
    let hours: f64 = args.next().and_then(|h| h.parse().ok()).unwrap_or(24.0);
    let table = Table::read(&path).expect("readable file");
    let rpm = table.f64_column("spindle_rpm").expect("spindle_rpm column");
    let channels: Vec<String> = std::env::var("MTEC_CHANNELS")
        .map(|s| s.split(',').map(String::from).collect())
        .unwrap_or_else(|_| (1..=5).map(|c| format!("ch{c}_um")).collect());
    for ch in channels {
        let d = ThermalData::from_table(&table, Some(&ch), true).expect("data");
        let d = with_input(&d, "spindle_rpm", &rpm).expect("input");
        let (train, test) = split_at_time(&d, hours * 60.0);
        let t0 = std::time::Instant::now();
        let fit = Auto::default().fit_auto(&d, &train).expect("auto");
        let pred = fit.predict(&d).expect("predict");
        let y = d.target_um().unwrap();
        let e: Vec<f64> = test.iter().map(|&i| y[i] - pred[i]).collect();
        let raw: Vec<f64> = test.iter().map(|&i| y[i]).collect();
        println!(
            "{ch}: chosen {} — test RMSE {:.2} µm (raw drift {:.2} µm), {:.0} s",
            fit.family,
            rms(&e),
            rms(&raw),
            t0.elapsed().as_secs_f64()
        );
        for c in &fit.candidates {
            match &c.forward {
                Some(f) => println!(
                    "   {:<13} mean {:.2} ± {:.2}  pooled {:.2}  folds [{}] / no comp [{}]{}{}",
                    c.family,
                    f.mean_rmse_um(),
                    f.rmse_std_error_um,
                    f.pooled_rmse_um,
                    f.folds
                        .iter()
                        .map(|x| format!("{:.2}", x.metrics.rmse_um))
                        .collect::<Vec<_>>()
                        .join(" "),
                    f.folds
                        .iter()
                        .map(|x| format!("{:.1}", x.uncompensated_rmse_um))
                        .collect::<Vec<_>>()
                        .join(" "),
                    if c.worse_than_uncompensated.is_empty() {
                        ""
                    } else {
                        "  WORSE THAN NONE"
                    },
                    if c.chosen { "  <- chosen" } else { "" }
                ),
                None => println!(
                    "   {:<13} failed: {}",
                    c.family,
                    c.error.clone().unwrap_or_default()
                ),
            }
        }
        if let mtec_thermal::ThermalModel::Linear(m) = &fit.model {
            let names: Vec<String> = m.features.iter().map(|f| f.name()).collect();
            println!("   features: {}", names.join(", "));
        }
        for w in fit.model.warnings() {
            println!("   warning: {w}");
        }
    }
}
