//! `mtec iso230-2` with environmental compensation (issue 20): the air-index and ISO 1
//! corrections scale the measured positions P_i + x_ij, so every per-target mean deviation must
//! become k (P_i + mean x) − P_i and every standard uncertainty k s, with k worked out here
//! independently of the CLI: from published refractive indices, and from the library equations.

mod support;

use mtec_measure::air::{self, Air, AirFormula};
use serde_json::Value;
use std::path::Path;

fn iso_json(run: &Path, extra: &[&str]) -> Value {
    let mut args = vec!["iso230-2", run.to_str().unwrap(), "--json"];
    args.extend_from_slice(extra);
    let out = support::mtec(&args);
    assert_eq!(out.status.code(), Some(0), "{}", support::stderr(&out));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn simulated_run(dir: &Path) -> std::path::PathBuf {
    support::write_scenario("iso230-2", 5, dir);
    dir.join("iso230-2.csv")
}

/// Checks every target of `corrected` against k applied to the positions of `plain`.
fn assert_scaled(plain: &Value, corrected: &Value, k: f64) {
    let (a, b) = (
        plain["targets"].as_array().unwrap(),
        corrected["targets"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    assert!(a.len() >= 5);
    for (t0, t1) in a.iter().zip(b) {
        let p_um = t0["target_mm"].as_f64().unwrap() * 1000.0;
        for key in ["mean_up_um", "mean_down_um", "mean_bidirectional_um"] {
            let x0 = t0[key].as_f64().unwrap();
            let want = k * (p_um + x0) - p_um;
            let got = t1[key].as_f64().unwrap();
            assert!(
                (got - want).abs() < 1e-9,
                "target {p_um} um {key}: {got} vs {want}"
            );
        }
        for key in ["s_up_um", "s_down_um"] {
            let want = k * t0[key].as_f64().unwrap();
            let got = t1[key].as_f64().unwrap();
            assert!((got - want).abs() < 1e-9, "{key}: {got} vs {want}");
        }
    }
    assert_eq!(
        corrected["corrections"]["scale_factor"].as_f64().unwrap(),
        k
    );
}

#[test]
fn air_correction_with_published_indices_shifts_each_deviation_by_the_hand_value() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let plain = iso_json(&run, &[]);
    assert!(plain["corrections"]["air"].is_null());
    assert_eq!(plain["corrections"]["scale_factor"].as_f64().unwrap(), 1.0);
    // Published Ciddor indices at 633.0 nm, 20 °C, 101 325 Pa, 450 ppm CO2 (README of the
    // `ref_index` package, pypi.org/project/ref-index, implementing the NIST toolbox equations):
    // 20 % RH → 1.0002716285340578 (the laser's index), 80 % RH → 1.0002711183472626 (actual).
    let n_laser = 1.000_271_628_534_057_8;
    let n_actual_published = 1.000_271_118_347_262_6;
    let corrected = iso_json(
        &run,
        &[
            "--wavelength-nm",
            "633",
            "--air-temp-c",
            "20",
            "--pressure-pa",
            "101325",
            "--humidity-pct",
            "80",
            "--laser-n",
            "1.0002716285340578",
        ],
    );
    let a = &corrected["corrections"]["air"];
    assert_eq!(a["formula"], "ciddor");
    assert!((a["n_laser"].as_f64().unwrap() - n_laser).abs() < 1e-15);
    let n_actual = a["n_actual"].as_f64().unwrap();
    assert!((n_actual - n_actual_published).abs() < 1e-8, "{n_actual}");
    let k = n_laser / n_actual;
    // the hand value from the two published indices: +0.51 ppm
    let k_published = n_laser / n_actual_published;
    assert!((k - k_published).abs() < 1e-8);
    assert!((a["correction_ppm"].as_f64().unwrap() - (k - 1.0) * 1e6).abs() < 1e-9);
    assert_scaled(&plain, &corrected, k);
    // at the last target (~537 mm) the deviation moves by (k − 1)·P: about 0.27 µm, equal to the
    // shift worked from the published indices alone to 1e-10·P (the library reproduces the
    // published 80 % RH index to 2e-11)
    let last = plain["targets"].as_array().unwrap().last().unwrap();
    let p_um = last["target_mm"].as_f64().unwrap() * 1000.0;
    let shift = corrected["targets"].as_array().unwrap().last().unwrap()["mean_up_um"]
        .as_f64()
        .unwrap()
        - last["mean_up_um"].as_f64().unwrap();
    let hand = (k_published - 1.0) * (p_um + last["mean_up_um"].as_f64().unwrap());
    assert!((0.2..0.3).contains(&hand), "{hand}");
    assert!((shift - hand).abs() < 1e-10 * p_um, "{shift} vs {hand}");
}

#[test]
fn air_and_material_corrections_match_the_library_equations() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let plain = iso_json(&run, &[]);
    for (formula, name) in [
        (AirFormula::Ciddor, "ciddor"),
        (AirFormula::Edlen, "edlen"),
        (AirFormula::BonschPotulski, "bonsch-potulski"),
    ] {
        let corrected = iso_json(
            &run,
            &[
                "--air-formula",
                name,
                "--air-temp-c",
                "23.5",
                "--pressure-pa",
                "98700",
                "--humidity-pct",
                "40",
                "--material-temp-c",
                "24",
                "--alpha-um-per-m-k",
                "11.5",
            ],
        );
        let actual = Air {
            temperature_c: 23.5,
            pressure_pa: 98_700.0,
            humidity_pct: 40.0,
            co2_ppm: 450.0,
        };
        let n_laser = air::refractive_index(formula, &air::STANDARD_AIR, 632.99);
        let n_actual = air::refractive_index(formula, &actual, 632.99);
        // ISO 1: positions divided by 1 + α (T − 20), α = 11.5e-6 /K, T = 24 °C
        let k = n_laser / n_actual / (1.0 + 11.5e-6 * 4.0);
        let c = &corrected["corrections"];
        assert_eq!(c["air"]["formula"], name);
        // (JSON keeps 17 significant digits: compare to the last one)
        assert!((c["air"]["n_laser"].as_f64().unwrap() - n_laser).abs() < 1e-15);
        assert!((c["air"]["n_actual"].as_f64().unwrap() - n_actual).abs() < 1e-15);
        let material_ppm = c["material"]["correction_ppm"].as_f64().unwrap();
        assert!((material_ppm - (1.0 / 1.000046 - 1.0) * 1e6).abs() < 1e-9);
        // warm, thin air: about +10 ppm; warm steel: about −46 ppm
        let air_ppm = c["air"]["correction_ppm"].as_f64().unwrap();
        assert!((9.5..11.0).contains(&air_ppm), "{name}: {air_ppm}");
        let got_k = c["scale_factor"].as_f64().unwrap();
        assert!((got_k - k).abs() < 1e-15, "{got_k} vs {k}");
        assert_scaled(&plain, &corrected, got_k);
    }
}

#[test]
fn the_text_report_states_the_corrections() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let out = support::mtec(&[
        "iso230-2",
        run.to_str().unwrap(),
        "--air-temp-c",
        "20",
        "--pressure-pa",
        "101325",
        "--humidity-pct",
        "50",
        "--material-temp-c",
        "20",
        "--alpha-um-per-m-k",
        "11.5",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", support::stderr(&out));
    let text = support::text(&out);
    assert!(
        text.contains("corrected for air (ciddor, 632.99 nm)"),
        "{text}"
    );
    assert!(text.contains("correction +0.000 ppm"), "{text}");
    assert!(
        text.contains("corrected for material (ISO 1, to 20 °C)"),
        "{text}"
    );
    assert!(
        text.contains("measured positions scaled by 1.000000000000"),
        "{text}"
    );
}

#[test]
fn out_of_range_or_incomplete_environment_is_refused_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let run = simulated_run(dir.path());
    let air3 = |t: &'static str, p: &'static str, h: &'static str| {
        vec!["--air-temp-c", t, "--pressure-pa", p, "--humidity-pct", h]
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (air3("60.5", "101325", "50"), "air temperature is 60.5"),
        (air3("-41", "101325", "50"), "air temperature is -41"),
        (air3("20", "49999", "50"), "air pressure is 49999"),
        (air3("20", "120001", "50"), "air pressure is 120001"),
        (air3("20", "101325", "101"), "relative humidity is 101"),
        (air3("20", "101325", "-1"), "relative humidity is -1"),
        (air3("20", "NaN", "50"), "air pressure is NaN"),
        (vec!["--air-temp-c", "20"], "needs all of"),
        (vec!["--laser-n", "1.00027"], "--laser-n needs"),
        (
            [air3("20", "101325", "50"), vec!["--laser-n", "1.5"]].concat(),
            "--laser-n is 1.5",
        ),
        (
            [
                air3("20", "101325", "50"),
                vec!["--air-formula", "edlen", "--wavelength-nm", "1064"],
            ]
            .concat(),
            "wavelength",
        ),
        (
            vec!["--material-temp-c", "24", "--alpha-um-per-m-k", "51"],
            "expansion coefficient is 51",
        ),
        (
            vec!["--material-temp-c", "24", "--alpha-um-per-m-k", "-1"],
            "expansion coefficient is -1",
        ),
        (
            vec!["--material-temp-c", "61", "--alpha-um-per-m-k", "11.5"],
            "material temperature is 61",
        ),
        (vec!["--material-temp-c", "24"], "needs both"),
    ];
    for (extra, msg) in cases {
        let mut args = vec!["iso230-2", run.to_str().unwrap()];
        args.extend_from_slice(&extra);
        let out = support::mtec(&args);
        let err = support::stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(msg), "{extra:?}: {err}");
    }
}
