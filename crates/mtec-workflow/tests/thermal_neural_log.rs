//! A network fitted on a log of one target (`ops::thermal::neural_log`) reports every training's
//! epochs to the observer, the forward folds' and the final one, and stops when the observer
//! asks: the file is still written, with the best epoch so far and a warning that says so.
#![cfg(feature = "neural")]

use mtec_nn::thermal_log::{NnFitOptions, NnKind};
use mtec_thermal::model_file::SplitBy;
use mtec_workflow::ops::thermal::{neural_log, FitOptions};
use mtec_workflow::Observer;

/// Heat steps through two bodies; the drift follows the slow one. 200 rows at 2 min.
fn log(dir: &std::path::Path) -> std::path::PathBuf {
    let mut csv = String::from("time_min,T1_c,T2_c,T3_c,ez_um\n");
    let (mut a, mut b, mut c) = (20.0, 20.0, 20.0);
    for k in 0..200 {
        let q = [0.0, 8.0, 2.0, 10.0, 4.0][k / 40];
        a += 0.2 * (20.0 + q - a);
        b += 0.05 * (a - b);
        c += 0.02 * (b - c);
        let ez = 2.0 * (a - 20.0) + 4.0 * (b - 20.0);
        csv.push_str(&format!("{},{a:.4},{b:.4},{c:.4},{ez:.4}\n", 2 * k));
    }
    let p = dir.join("log.csv");
    std::fs::write(&p, csv).unwrap();
    p
}

/// Counts the epochs it is told of and asks to stop after `stop_after` of them.
struct StopAfter {
    epochs: usize,
    stop_after: usize,
    warnings: Vec<String>,
}

impl Observer for StopAfter {
    fn progress(&mut self, what: &str) {
        if what.contains(" epoch ") && what.contains(" loss ") {
            self.epochs += 1;
        }
    }
    fn warning(&mut self, what: &str) {
        self.warnings.push(what.into());
    }
    fn stop_requested(&self) -> bool {
        self.epochs >= self.stop_after
    }
}

fn options(dir: &std::path::Path) -> (FitOptions, NnFitOptions) {
    let opts = FitOptions {
        data: log(dir),
        target: "ez_um".into(),
        model: "bpnn".into(),
        fit: mtec_thermal::FitOptions {
            block_min: Some(60.0),
            ..Default::default()
        },
        split: SplitBy::Until(300.0),
        output: dir.join("m.json"),
    };
    let mut nn = NnFitOptions::new(NnKind::Bpnn);
    (nn.hidden, nn.epochs, nn.patience) = (Some(3), Some(40), Some(1000));
    (opts, nn)
}

#[test]
fn every_training_reports_its_epochs_to_the_observer() {
    let dir = tempfile::tempdir().unwrap();
    let (opts, nn) = options(dir.path());
    let mut obs = StopAfter {
        epochs: 0,
        stop_after: usize::MAX,
        warnings: vec![],
    };
    let out = neural_log::fit(&opts, &nn, &mut obs).unwrap();
    let folds = out.validation.as_ref().unwrap().folds.len();
    assert!(folds >= 2, "{folds} folds (blocks of 60 min in 300 min)");
    // one training per fold and the final one, each at least one epoch
    assert!(
        obs.epochs > folds,
        "{} epochs for {} trainings",
        obs.epochs,
        folds + 1
    );
    assert!(obs.warnings.is_empty(), "{:?}", obs.warnings);
}

#[test]
fn a_stop_request_ends_the_trainings_and_the_file_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (opts, nn) = options(dir.path());
    let mut obs = StopAfter {
        epochs: 0,
        stop_after: 2,
        warnings: vec![],
    };
    let out = neural_log::fit(&opts, &nn, &mut obs).unwrap();
    assert!(
        matches!(out.training.stop_reason(), mtec_nn::StopReason::User { .. }),
        "{}",
        out.training.stop_reason()
    );
    // every later training stopped after its first epoch: far fewer than 40 per training
    let folds = out.validation.as_ref().unwrap().folds.len();
    assert!(obs.epochs <= 2 + folds + 1, "{} epochs", obs.epochs);
    assert!(
        obs.warnings
            .iter()
            .any(|w| w.contains("stopped by the user")),
        "{:?}",
        obs.warnings
    );
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&opts.output).unwrap()).unwrap();
    assert!(
        file["provenance"]["stop_reason"]
            .as_str()
            .unwrap()
            .contains("stop"),
        "{}",
        file["provenance"]["stop_reason"]
    );
}
