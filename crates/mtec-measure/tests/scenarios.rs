//! The measurement statistics checked against the virtual machine's truth.

use mtec_io::Table;
use mtec_measure::circular::{diagnose, evaluate, CircularTrace, DiagnosticsConfig, TraceOptions};
use mtec_measure::{evaluate_iso230_2, PositioningData};
use std::path::Path;

fn file<'a>(out: &'a mtec_sim::ScenarioOutput, name: &str) -> &'a str {
    &out.files
        .iter()
        .find(|f| f.name == name)
        .expect(name)
        .contents
}

fn arr(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// ISO 230-2 statistics of simulated laser runs match the values the truth implies, within
/// bounds derived from the noise: σ = 0.2 µm, n = 5 runs, so a mean is off by σ/√5 = 0.09 µm
/// (bound: 5σ/√5); s pools 11 × 2 × 4 degrees of freedom (bound: ±25 %, > 3 standard errors).
#[test]
fn iso230_2_statistics_match_truth() {
    for seed in [1, 2, 3] {
        let out = mtec_sim::run_scenario("iso230-2", seed).unwrap();
        let table = Table::parse(Path::new("iso230-2.csv"), file(&out, "iso230-2.csv")).unwrap();
        let data = PositioningData::from_table(&table).unwrap();
        assert!(data.warnings.is_empty(), "{:?}", data.warnings);
        let r = evaluate_iso230_2(&data);
        let t = &out.truth;
        let sigma = t["s_um"].as_f64().unwrap();
        let up = arr(&t["mean_up_um"]);
        let down = arr(&t["mean_down_um"]);
        let b = t["reversal_um"].as_f64().unwrap();
        let mean_tol = 5.0 * sigma / 5f64.sqrt();
        for (i, s) in r.targets.iter().enumerate() {
            assert!(
                (s.mean_up_um - up[i]).abs() < mean_tol,
                "seed {seed} target {i}"
            );
            assert!(
                (s.mean_down_um - down[i]).abs() < mean_tol,
                "seed {seed} target {i}"
            );
            assert!((s.reversal_um - b).abs() < 2.0 * mean_tol);
        }
        let pooled = (r
            .targets
            .iter()
            .map(|s| s.s_up_um.powi(2) + s.s_down_um.powi(2))
            .sum::<f64>()
            / (2 * r.targets.len()) as f64)
            .sqrt();
        assert!((pooled / sigma - 1.0).abs() < 0.25, "pooled s {pooled}");
        // truth-implied axis values
        let all: Vec<f64> = up.iter().chain(down.iter()).copied().collect();
        let range = |v: &[f64]| {
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
        };
        let bidir: Vec<f64> = up.iter().zip(&down).map(|(u, d)| (u + d) / 2.0).collect();
        let a = &r.axis;
        assert!(
            (a.e_um - range(&all)).abs() < 2.0 * mean_tol,
            "E {} vs {}",
            a.e_um,
            range(&all)
        );
        assert!((a.e_up_um - range(&up)).abs() < 2.0 * mean_tol);
        assert!((a.e_down_um - range(&down)).abs() < 2.0 * mean_tol);
        assert!((a.m_um - range(&bidir)).abs() < 2.0 * mean_tol);
        assert!((a.b_um - b.abs()).abs() < 2.0 * mean_tol);
        assert!((a.mean_b_um - b).abs() < mean_tol);
        // A = E + 4σ when s is the same everywhere; R_i = |B| + 4σ (the 2s+2s+|B| branch)
        let a_true = range(&all) + 4.0 * sigma;
        assert!(
            (a.a_um - a_true).abs() < 2.0 * mean_tol + 4.0 * sigma * 0.6,
            "A {}",
            a.a_um
        );
        let r_true = b.abs() + 4.0 * sigma;
        assert!(
            a.r_um > r_true - 2.0 * mean_tol && a.r_um < r_true + 2.0 * mean_tol + 4.0 * sigma,
            "R {}",
            a.r_um
        );
    }
}

fn analyse(
    text: &str,
) -> (
    mtec_measure::circular::Iso230_4,
    mtec_measure::circular::Diagnostics,
) {
    let table = Table::parse(Path::new("circular.csv"), text).unwrap();
    let trace = CircularTrace::from_table(&table, &TraceOptions::default()).unwrap();
    (
        evaluate(&trace),
        diagnose(&trace, &DiagnosticsConfig::default()).unwrap(),
    )
}

/// µm of peak effect on the trace per unit of each diagnostic at R = 100 mm, feed 1000 mm/min:
/// used to turn the "0.5 µm" of the acceptance rule into each diagnostic's unit.
fn um_per_unit(id: &str) -> f64 {
    let r_um = 100_000.0;
    if id == "scale_mismatch" || id == "squareness" {
        r_um * 1e-6 / 2.0
    } else if id == "servo_mismatch" {
        1000.0 / 60.0 / 2.0
    } else {
        1.0
    }
}

/// Every injected fault of `circular-test` is recovered within 10 % or 0.5 µm (of effect on the
/// trace), every fault not injected is absent, and the fault-free run reports none.
#[test]
fn circular_test_faults_are_recovered() {
    for seed in [7, 8] {
        circular_recovery(seed);
    }
}

fn circular_recovery(seed: u64) {
    let out = mtec_sim::run_scenario("circular-test", seed).unwrap();
    let truth = &out.truth["diagnostics"];
    let (iso, diag) = analyse(file(&out, "circular.csv"));
    for d in &diag.faults {
        eprintln!(
            "{:22} {:?} ± {:?} {:5} contrib {:6.3} {} {:?}",
            d.id, d.value, d.std_error, d.unit, d.contribution_um, d.present, d.pitch_mm
        );
    }
    eprintln!(
        "residual rms {:.4}, G(b) {:.3}, H {:.3}",
        diag.residual_rms_um, iso.g_bidirectional_um, iso.h_um
    );
    for (id, want) in truth.as_object().unwrap() {
        if id.ends_with("_pitch_mm") {
            continue;
        }
        let want = want.as_f64().unwrap();
        let got = diag.get(id).unwrap_or_else(|| panic!("no diagnostic {id}"));
        let tol = (0.1 * want.abs()).max(0.5 / um_per_unit(id));
        let value = got.value.expect("a full circle determines every fault");
        assert!(
            (value - want).abs() <= tol,
            "{id}: fitted {value} vs injected {want} (tolerance {tol})"
        );
        assert_eq!(
            got.present,
            want.abs() * um_per_unit(id) >= 0.5,
            "{id} presence"
        );
    }
    let pitch = diag.get("cyclic_X").unwrap().pitch_mm.unwrap();
    let want_pitch = truth["cyclic_X_pitch_mm"].as_f64().unwrap();
    assert!(
        (pitch - want_pitch).abs() < 0.1 * want_pitch,
        "pitch {pitch}"
    );
    // what the model leaves: noise (0.15 µm) plus the few samples where the servo lag shifts
    // the backlash step by ωτ ≈ 0.15° from the commanded reversal angle
    let noise = out.truth["noise_um"].as_f64().unwrap();
    assert!(
        diag.residual_rms_um < 2.0 * noise,
        "residual {}",
        diag.residual_rms_um
    );

    let (_, clean) = analyse(file(&out, "circular-fault-free.csv"));
    for d in &clean.faults {
        eprintln!(
            "fault-free {:22} {:?} ± {:?} contrib {:6.3} {}",
            d.id, d.value, d.std_error, d.contribution_um, d.present
        );
    }
    assert!(
        clean.residual_rms_um < 1.2 * noise,
        "residual {}",
        clean.residual_rms_um
    );
    let present: Vec<&str> = clean
        .present()
        .filter(|d| !d.id.starts_with("centre_offset"))
        .map(|d| d.id.as_str())
        .collect();
    assert!(present.is_empty(), "fault-free run reports {present:?}");
}

/// The same faults in the ZX plane (axis 1 = Z, axis 2 = X) are named after those axes.
#[test]
fn plane_names_the_axes() {
    let out = mtec_sim::run_scenario("circular-test", 3).unwrap();
    let text = file(&out, "circular.csv").replace("# plane = XY", "# plane = ZX");
    let table = Table::parse(Path::new("zx.csv"), &text).unwrap();
    let trace = CircularTrace::from_table(&table, &TraceOptions::default()).unwrap();
    let d = diagnose(&trace, &DiagnosticsConfig::default()).unwrap();
    let b = d.get("backlash_Z_pos").expect("axis 1 is Z");
    assert!((b.value.unwrap() - 6.0).abs() < 0.6, "{b:?}");
    assert!(d.get("backlash_X_neg").unwrap().present);
    assert!(d.get("cyclic_Z").unwrap().present);
}
