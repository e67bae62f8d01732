//! `mtec iso230-2 --standard` (issue 20): each implemented standard's axis values from one run,
//! against values worked by hand here from the cited definitions (docs/methods.md §2.2), the
//! default report unchanged byte for byte, and the standards whose definitions are not
//! established refused as usage errors.
//!
//! The run (tests/data/iso230_2_standards/run.csv): 3 targets × 5 runs each way, in µm.
//!
//! | target | runs ↑           | x̄↑  | s↑ | runs ↓            | x̄↓  | s↓ |
//! |--------|------------------|-----|----|-------------------|-----|----|
//! | 0 mm   | 0, 2, 1, 0, 2    |  1  | 1  | −7 ×5             | −7  | 0  |
//! | 100 mm | 3, 7, 5, 7, 3    |  5  | 2  | 3, 5, 4, 5, 3     |  4  | 1  |
//! | 200 mm | −2 ×5            | −2  | 0  | −6, −2, −4, −2, −6| −4  | 2  |
//!
//! s = sqrt(Σ(x − x̄)²/(n − 1)), n = 5: offsets (−1, −1, 0, 1, 1)·k give Σ = 4k², s = k.
//!
//! ISO 230-2:2014 (clause 3; the definitions as `crates/mtec-measure/src/iso230_2.rs` cites them):
//! - B_i = x̄↑ − x̄↓ = (8, 1, 2); B = max |B_i| = 8.
//! - x̄_i = (x̄↑ + x̄↓)/2 = (−3, 4.5, −3); M = 4.5 − (−3) = 7.5.
//! - E = max(1, 5, −2, −7, 4, −4) − min(same) = 5 − (−7) = 12.
//! - R_i = max(2s↑ + 2s↓ + |B_i|; 4s↑; 4s↓) = (max(10, 4, 0), max(7, 8, 4), max(6, 0, 8))
//!   = (10, 8, 8); R = 10.
//! - A = max(x̄↑ + 2s↑; x̄↓ + 2s↓) − min(x̄↑ − 2s↑; x̄↓ − 2s↓)
//!   = max(3, 9, −2, −7, 6, 0) − min(−1, 1, −2, −7, 2, −8) = 9 − (−8) = 17.
//!
//! VDI/DGQ 3441 (docs/methods.md §2):
//! - s̄_j = (s↑ + s↓)/2 = (0.5, 1.5, 1); Ps = max 6 s̄_j = 9.
//! - U = max |x̄↑ − x̄↓| = 8; Pa = max x̄_j − min x̄_j = 7.5.
//! - P = max(x̄_j + (U_j + Ps_j)/2) − min(x̄_j − (U_j + Ps_j)/2), (U_j + Ps_j)/2 = (5.5, 5, 4):
//!   max(2.5, 9.5, 1) − min(−8.5, −0.5, −7) = 9.5 + 8.5 = 18.

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/iso230_2_standards")
}

/// Runs `mtec iso230-2 run.csv ARGS` in the data folder (so the report names `run.csv`).
fn iso(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mtec"))
        .current_dir(data_dir())
        .arg("iso230-2")
        .arg("run.csv")
        .args(args)
        .output()
        .expect("mtec runs")
}

fn ok(o: &Output) -> String {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout.clone()).unwrap()
}

/// Exact to rounding: every hand value is a small integer or half-integer.
const TOL_UM: f64 = 1e-12;

fn close(got: f64, want: f64, what: &str) {
    assert!((got - want).abs() < TOL_UM, "{what}: {got} vs {want}");
}

#[test]
fn default_report_is_byte_for_byte_what_it_was() {
    // default.txt and default.json were written by `mtec iso230-2 run.csv [--json]` before
    // --standard existed (commit 8af4d65).
    let want_txt = std::fs::read_to_string(data_dir().join("default.txt")).unwrap();
    let want_json = std::fs::read_to_string(data_dir().join("default.json")).unwrap();
    for args in [&[][..], &["--standard", "iso230-2:2014"][..]] {
        assert_eq!(ok(&iso(args)), want_txt, "{args:?}");
        let mut j = args.to_vec();
        j.push("--json");
        assert_eq!(ok(&iso(&j)), want_json, "{j:?}");
    }
}

#[test]
fn standard_all_reports_each_standard_with_its_hand_worked_values() {
    let j: Value = serde_json::from_str(&ok(&iso(&["--standard", "all", "--json"]))).unwrap();
    let st = j["standards"].as_array().expect("standards side by side");
    assert_eq!(st.len(), 2);
    // (name, accuracy, repeatability, reversal, systematic, range of means), worked above
    let want = [
        ("iso230-2:2014", 17.0, 10.0, 8.0, Some(12.0), 7.5),
        ("vdi-3441", 18.0, 9.0, 8.0, None, 7.5),
    ];
    for (s, w) in st.iter().zip(want) {
        assert_eq!(s["standard"], w.0);
        close(s["accuracy_um"].as_f64().unwrap(), w.1, "accuracy");
        close(
            s["repeatability_um"].as_f64().unwrap(),
            w.2,
            "repeatability",
        );
        close(s["reversal_um"].as_f64().unwrap(), w.3, "reversal");
        match w.4 {
            Some(e) => close(s["systematic_um"].as_f64().unwrap(), e, "E"),
            None => assert!(s["systematic_um"].is_null(), "{s}"),
        }
        close(s["mean_range_um"].as_f64().unwrap(), w.5, "range of means");
    }
    // the ISO 230-2:2014 column is the same evaluation as the axis values
    close(j["A_um"].as_f64().unwrap(), 17.0, "A_um");
    close(j["M_um"].as_f64().unwrap(), 7.5, "M_um");

    let txt = ok(&iso(&["--standard", "all"]));
    let default = std::fs::read_to_string(data_dir().join("default.txt")).unwrap();
    assert!(
        txt.starts_with(&default),
        "the full report comes first:\n{txt}"
    );
    for line in [
        "standards side by side (um)    iso230-2:2014       vdi-3441",
        "  accuracy (A; P)                     17.000         18.000",
        "  repeatability (R; Ps)               10.000          9.000",
        "  reversal (B; U)                      8.000          8.000",
        "  systematic (E)                      12.000              -",
        "  range of means (M; Pa)               7.500          7.500",
        "not reported (definitions not established, docs/methods.md 2.2): iso230-2:1997, \
         iso230-2:2006, gb-t-17421.2, jis-b-6190-2, asme-b5.54",
    ] {
        assert!(txt.contains(line), "missing `{line}` in\n{txt}");
    }
    let vdi = ok(&iso(&["--standard", "vdi-3441"]));
    assert!(
        vdi.contains("standards side by side (um)         vdi-3441\n"),
        "{vdi}"
    );
    assert!(!vdi.contains("iso230-2:2014  "), "{vdi}");
}

#[test]
fn standards_without_established_definitions_and_unknown_values_are_usage_errors() {
    for (value, says) in [
        ("asme-b5.54", "not implemented"),
        ("jis-b-6190-2", "not implemented"),
        ("gb-t-17421.2", "not implemented"),
        ("iso230-2:1997", "not implemented"),
        ("iso230-2:2006", "not implemented"),
        ("iso230-2:2015", "not a standard mtec knows"),
        ("", "not a standard mtec knows"),
    ] {
        let o = iso(&["--standard", value]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{value}: {err}");
        assert!(
            err.contains(says) && err.contains("iso230-2:2014"),
            "{value}: {err}"
        );
        assert!(
            o.stdout.is_empty(),
            "{value}: nothing printed on a usage error"
        );
    }
}
