//! Bounded property tests (issue 10): random text fed to the CSV table reader and the TOML
//! parser must give a value or a located `InputError` naming the file — never a panic. This is
//! the CI-sized companion of the cargo-fuzz targets `csv_table` and `machine_toml` in `fuzz/`
//! (which run for minutes on nightly); each property here runs a few hundred cases in about a
//! second.

use mtec_io::{parse_toml, Table};
use proptest::prelude::*;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Text that looks like mtec's CSV often enough to get past the header: unit-suffixed names,
/// numbers in several spellings (NaN, inf, exponents, signs), separators, comments, quotes,
/// BOMs and line ends of every kind, plus arbitrary characters.
fn csvish() -> impl Strategy<Value = String> {
    let token = prop_oneof![
        Just("x_mm".to_string()),
        Just("ex_um".to_string()),
        Just("run".to_string()),
        Just("direction".to_string()),
        Just("NaN".to_string()),
        Just("-inf".to_string()),
        Just("1e308".to_string()),
        Just("9223372036854775808".to_string()),
        Just("+".to_string()),
        Just(",".to_string()),
        Just(";".to_string()),
        Just("\t".to_string()),
        Just("\"".to_string()),
        Just("#".to_string()),
        Just("\n".to_string()),
        Just("\r\n".to_string()),
        Just("\r".to_string()),
        Just("\u{feff}".to_string()),
        Just(" ".to_string()),
        (-1e6f64..1e6).prop_map(|v| format!("{v}")),
        any::<i64>().prop_map(|v| v.to_string()),
        any::<char>().prop_map(|c| c.to_string()),
    ];
    prop::collection::vec(token, 0..60).prop_map(|v| v.concat())
}

/// Text built from TOML's own pieces (keys of a machine file, brackets, strings, numbers,
/// inf/nan, dates) and arbitrary characters.
fn tomlish() -> impl Strategy<Value = String> {
    let token = prop_oneof![
        Just("chain".to_string()),
        Just("axes".to_string()),
        Just("travel".to_string()),
        Just("[axes.X]".to_string()),
        Just("[[mode]]".to_string()),
        Just(" = ".to_string()),
        Just("\"WXYFZT\"".to_string()),
        Just("'''".to_string()),
        Just("[".to_string()),
        Just("]".to_string()),
        Just("{".to_string()),
        Just("}".to_string()),
        Just(", ".to_string()),
        Just("nan".to_string()),
        Just("-inf".to_string()),
        Just("1979-05-27T07:32:00Z".to_string()),
        Just("\n".to_string()),
        Just("\r\n".to_string()),
        Just("#".to_string()),
        (-1e6f64..1e6).prop_map(|v| format!("{v:?}")),
        any::<char>().prop_map(|c| c.to_string()),
    ];
    prop::collection::vec(token, 0..60).prop_map(|v| v.concat())
}

/// A machine-like document: the shape `mtec_model::MachineSpec` has (that crate depends on this
/// one, so the fuzz target `machine_toml` checks the real type).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct MachineLike {
    chain: String,
    axes: BTreeMap<String, AxisLike>,
    #[serde(default)]
    tool_offset_mm: [f64; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
struct AxisLike {
    travel: [f64; 2],
    #[serde(default)]
    centre_mm: [f64; 3],
}

fn check_table(text: &str) {
    match Table::parse(Path::new("t.csv"), text) {
        Ok(t) => {
            assert!(!t.rows.is_empty(), "a table without data rows was accepted");
            for r in &t.rows {
                assert_eq!(r.fields.len(), t.header.len(), "ragged row accepted");
                assert!(r.line > t.header_line);
            }
            for name in t.header.clone() {
                if let Err(e) = t.f64_column(&name) {
                    assert!(e.to_string().starts_with("t.csv:"), "{e}");
                }
                let _ = t.i64_column(&name);
                let _ = t.str_column(&name);
            }
        }
        Err(e) => assert!(e.to_string().starts_with("t.csv"), "unlocated error: {e}"),
    }
}

fn check_toml(text: &str) {
    if let Err(e) = parse_toml::<MachineLike>(Path::new("m.toml"), text) {
        assert!(e.to_string().starts_with("m.toml"), "unlocated error: {e}");
    }
    if let Err(e) = parse_toml::<toml::Value>(Path::new("m.toml"), text) {
        assert!(e.to_string().starts_with("m.toml"), "unlocated error: {e}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn table_parse_never_panics_on_csv_like_text(text in csvish()) {
        check_table(&text);
    }

    #[test]
    fn table_parse_never_panics_on_any_text(text in any::<String>()) {
        check_table(&text);
    }

    #[test]
    fn parse_toml_never_panics_on_toml_like_text(text in tomlish()) {
        check_toml(&text);
    }

    #[test]
    fn parse_toml_never_panics_on_any_text(text in any::<String>()) {
        check_toml(&text);
    }
}

/// Inputs the fuzzers and this file found interesting, kept as plain regression cases.
#[test]
fn table_parse_edge_cases_give_located_errors() {
    for text in [
        "",
        "\u{feff}",
        "\u{feff}\r\n",
        "a_mm\r\n",
        "#only a comment\n",
        "a_mm,a_mm\n1,2\n",
        "a_mm\n\"1\n",
        "a_mm;b_mm\n1;2\n",
        "\r",
        "a_mm\r1\r",
    ] {
        check_table(text);
    }
}

/// serde_json reports column 0 at the end of a line or file; mtec's columns are 1-based.
#[test]
fn json_errors_at_end_of_file_have_column_one() {
    let dir = tempfile::tempdir().unwrap();
    for (text, line) in [("", 1), ("{\"a\": [1,\n", 2)] {
        let p = dir.path().join("m.json");
        std::fs::write(&p, text).unwrap();
        let e = mtec_io::read_json::<serde_json::Value>(&p).unwrap_err();
        assert_eq!((e.line, e.column), (Some(line), Some(1)), "{e}");
        assert!(
            e.to_string().contains(&format!("m.json:{line}:1: EOF")),
            "{e}"
        );
    }
}
