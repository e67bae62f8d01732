//! The analysis steps fed with designs and outputs produced by SALib agree with SALib's own
//! analysis to 1e-9. Fixtures: `tests/fixtures/`, made by `make_salib_fixtures.py` (SALib 1.5.1,
//! numpy 2.4.6; version recorded in `salib_expected.json`).

use mtec_io::Table;
use mtec_sensitivity::interval::bootstrap_half_widths;
use mtec_sensitivity::{efast, morris, sobol};
use serde_json::Value;
use std::path::PathBuf;

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn load_y(file: &str) -> Vec<f64> {
    Table::read(&fixtures().join(file))
        .unwrap()
        .f64_column("y")
        .unwrap()
}

fn cases(method: &str) -> Vec<Value> {
    let text = std::fs::read_to_string(fixtures().join("salib_expected.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["salib_version"], "1.5.1");
    v["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["method"] == method)
        .cloned()
        .collect()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn names(c: &Value) -> Vec<String> {
    c["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect()
}

fn assert_agree(file: &str, what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g - w).abs() < 1e-9,
            "{file} {what}: mtec {got:?}\nSALib {want:?}"
        );
    }
}

#[test]
fn efast_analysis_agrees_with_salib_fast_analyze() {
    let cs = cases("fast");
    assert_eq!(cs.len(), 3);
    for c in cs {
        let file = c["file"].as_str().unwrap();
        let y = load_y(file);
        let m = c["M"].as_u64().unwrap() as usize;
        let ix = efast::analyze(&names(&c), &y, m, 1, 0.95).unwrap();
        assert_agree(file, "S1", &ix.s1, &floats(&c["S1"]));
        assert_agree(file, "ST", &ix.st, &floats(&c["ST"]));
    }
}

#[test]
fn efast_frequencies_reproduce_salib_designs() {
    // The fixtures' sample matrices were drawn by SALib's fast_sampler: on curve i, input j
    // follows the triangle wave ½ + arcsin(sin(ω_j s + φ))/π, which turns 2ω_j times over the
    // curve. Counting the turns of every uniform column checks `efast::frequencies` (both its
    // linspace and its modulo branch) against SALib's choice.
    for c in cases("fast") {
        let file = c["file"].as_str().unwrap();
        let table = Table::read(&fixtures().join(file)).unwrap();
        let d = names(&c).len();
        let n = c["N"].as_u64().unwrap() as usize;
        let m = c["M"].as_u64().unwrap() as usize;
        let (w_max, others) = efast::frequencies(n, m, d);
        // Uniform columns: all of Ishigami; x1, x2, x5 of the mixed case (x3, x4 are normal).
        let uniform: Vec<usize> = if d == 3 { vec![0, 1, 2] } else { vec![0, 1, 4] };
        for i in 0..d {
            let mut omega = others.clone();
            omega.insert(i, w_max);
            for &j in &uniform {
                let x = table.f64_column(&format!("x{}", j + 1)).unwrap();
                let g = &x[i * n..(i + 1) * n];
                let turns = (1..n - 1)
                    .filter(|&k| (g[k] - g[k - 1]) * (g[k + 1] - g[k]) < 0.0)
                    .count() as i64;
                assert!(
                    (turns - 2 * omega[j] as i64).abs() <= 1,
                    "{file} curve {i} input {j}: {turns} turns, ω = {}",
                    omega[j]
                );
            }
        }
    }
}

#[test]
fn sobol_analysis_agrees_with_salib_sobol_analyze() {
    let cs = cases("sobol");
    assert_eq!(cs.len(), 2);
    for c in cs {
        let file = c["file"].as_str().unwrap();
        let y = load_y(file);
        let r = sobol::analyze(
            &names(&c),
            &y,
            &sobol::Bootstrap {
                resamples: 0,
                ..Default::default()
            },
        )
        .unwrap();
        assert_agree(file, "S1", &r.indices.s1, &floats(&c["S1"]));
        assert_agree(file, "ST", &r.indices.st, &floats(&c["ST"]));
    }
}

/// SALib's bootstrap resampling (recorded by `make_salib_interval_fixtures.py`, which checks
/// that the recorded indices reproduce SALib's own intervals) fed to mtec's estimators gives
/// SALib's S1_conf, ST_conf (Sobol) and mu_star_conf (Morris) to 1e-9: the same estimators on
/// the same replicates, and the same z·sd half width.
#[test]
fn bootstrap_intervals_agree_with_salib_on_salibs_resampling() {
    let text = std::fs::read_to_string(fixtures().join("salib_intervals.json")).unwrap();
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["salib_version"], "1.5.1");
    let conf = v["conf_level"].as_f64().unwrap();
    let rows = |r: &Value| -> Vec<Vec<usize>> {
        r.as_array()
            .unwrap()
            .iter()
            .map(|k| {
                k.as_array()
                    .unwrap()
                    .iter()
                    .map(|i| i.as_u64().unwrap() as usize)
                    .collect()
            })
            .collect()
    };
    let cases = v["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 3);
    for c in cases {
        let file = c["file"].as_str().unwrap();
        let n = names(c);
        let y = load_y(file);
        if c["method"] == "sobol" {
            let reps = sobol::replicates_on(&y, n.len(), &rows(&c["rows"]));
            assert_eq!(reps.s1.len(), 100);
            let (c1, ct) = (
                bootstrap_half_widths(&reps.s1, conf),
                bootstrap_half_widths(&reps.st, conf),
            );
            assert_agree(file, "S1_conf", &c1, &floats(&c["S1_conf"]));
            assert_agree(file, "ST_conf", &ct, &floats(&c["ST_conf"]));
            // and mtec's own bootstrap (its own resampling) is the same size: within the
            // Monte-Carlo spread of a standard deviation from 100 replicates (±14 % at 2σ)
            // plus the difference of two independent ones, 30 %
            let own = sobol::analyze(&n, &y, &sobol::Bootstrap::default()).unwrap();
            for (what, mine, salib) in [
                ("S1", own.indices.s1_conf.unwrap(), floats(&c["S1_conf"])),
                ("ST", own.indices.st_conf.unwrap(), floats(&c["ST_conf"])),
            ] {
                for (m, s) in mine.iter().zip(&salib) {
                    assert!(
                        (m / s - 1.0).abs() < 0.3,
                        "{file} {what}_conf: mtec {mine:?} SALib {salib:?}"
                    );
                }
            }
        } else {
            // SALib's Morris design as an mtec design: each step changes one input by ±Δ
            let table = Table::read(&fixtures().join(file)).unwrap();
            let d = n.len();
            let cols: Vec<Vec<f64>> = (1..=d)
                .map(|j| table.f64_column(&format!("x{j}")).unwrap())
                .collect();
            let r = y.len() / (d + 1);
            let data: Vec<f64> = (0..y.len())
                .flat_map(|row| cols.iter().map(move |c| c[row]))
                .collect();
            let mut steps = Vec::new();
            for t in 0..r {
                for k in 0..d {
                    let row = t * (d + 1) + k;
                    let i = (0..d).find(|&j| cols[j][row + 1] != cols[j][row]).unwrap();
                    steps.push((i, cols[i][row + 1] - cols[i][row]));
                }
            }
            let design = morris::MorrisDesign {
                samples: mtec_sensitivity::SampleMatrix::from_rows(d, data).unwrap(),
                steps,
            };
            let ix = morris::analyze(&n, &design, &y, &Default::default()).unwrap();
            assert_agree(file, "mu", &ix.mu, &floats(&c["mu"]));
            assert_agree(file, "mu_star", &ix.mu_star, &floats(&c["mu_star"]));
            assert_agree(file, "sigma", &ix.sigma, &floats(&c["sigma"]));
            let ee = morris::elementary_effects(&n, &design, &y).unwrap();
            let conf_salib: Vec<f64> = (0..d)
                .map(|j| {
                    let reps: Vec<Vec<f64>> =
                        morris::mu_star_replicates_on(&ee[j], &rows(&c["rows"][j]))
                            .into_iter()
                            .map(|m| vec![m])
                            .collect();
                    bootstrap_half_widths(&reps, conf)[0]
                })
                .collect();
            assert_agree(
                file,
                "mu_star_conf",
                &conf_salib,
                &floats(&c["mu_star_conf"]),
            );
            let own = ix.mu_star_conf.unwrap();
            for (m, s) in own.iter().zip(floats(&c["mu_star_conf"])) {
                assert!((m / s - 1.0).abs() < 0.3, "mu_star_conf {own:?} vs SALib");
            }
        }
    }
}
