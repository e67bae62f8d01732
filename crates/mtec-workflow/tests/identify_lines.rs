//! `ops::identify_lines` in-process on the simulated 9-line measurement: the positioning error
//! of X against the simulator's truth, the three files the CLI writes, and a bad line file
//! located.

use mtec_workflow::ops::identify_lines::{self, Options};
use mtec_workflow::{Error, Silent};
use std::path::Path;

fn scenario(dir: &Path) -> serde_json::Value {
    let out = mtec_sim::run_scenario("vmc-9line", 1).unwrap();
    for f in out.files {
        std::fs::write(dir.join(&f.name), f.contents).unwrap();
    }
    serde_json::to_value(&out.truth).unwrap()
}

#[test]
fn positioning_matches_the_truth_and_the_three_files_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truth = scenario(d);
    let mut opts = Options::new(d.join("machine.toml"), d.join("lines.csv"));
    opts.output = Some(d.join("errors.json"));
    opts.kinematic_model = Some(d.join("km.json"));
    opts.stats = Some(d.join("stats.csv"));
    let o = identify_lines::run(&opts, &mut Silent).unwrap();
    // the positioning error of X, read straight by the X lines, against the simulator's truth
    // (a table over the travel): within 4 reported standard uncertainties, plus what a cubic
    // cannot follow of the truth's ripple (0.1 um)
    let truth_set: mtec_model::ErrorSet = serde_json::from_value(truth["errors"].clone()).unwrap();
    let exx = mtec_model::ErrorElement::parse("EXX").unwrap();
    let report = serde_json::to_value(&o.report).unwrap();
    let sigma = report["elements"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["element"] == "EXX")
        .unwrap()["uncertainty_1sigma"]
        .as_f64()
        .unwrap();
    for x in [10.0, 150.0, 300.0, 450.0, 590.0] {
        let (got, want) = (o.errors.value(&exx, x), truth_set.value(&exx, x));
        assert!(
            (got - want).abs() < 4.0 * sigma + 0.1,
            "EXX({x}): {got} vs truth {want}, sigma {sigma}"
        );
    }
    assert_eq!(
        o.written,
        [
            d.join("errors.json"),
            d.join("km.json"),
            d.join("stats.csv")
        ]
    );
    // the error set exactly as serialised (text: serde_json does not round-trip every float)
    assert_eq!(
        std::fs::read_to_string(d.join("errors.json")).unwrap(),
        serde_json::to_string_pretty(&o.errors).unwrap()
    );
    let km: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("km.json")).unwrap()).unwrap();
    assert_eq!(km["format"], "mtec.kinematic-model/1");
    let stats = std::fs::read_to_string(d.join("stats.csv")).unwrap();
    assert!(stats.contains("\nelement,mean,std,unit\nEXX,"), "{stats}");
    assert_eq!(report["format"], "mtec.identify-lines/1");
    assert!(o
        .to_string()
        .ends_with(&format!("Wrote {}\n", d.join("stats.csv").display())));
}

#[test]
fn a_bad_reading_is_located_and_outputs_without_data_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    scenario(d);
    let text = std::fs::read_to_string(d.join("lines.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    let row = header + 3;
    let cells: Vec<&str> = lines[row].split(',').collect();
    let reading = cells.len() - 1;
    let mut cells: Vec<String> = cells.iter().map(|s| s.to_string()).collect();
    cells[reading] = "abc".into();
    lines[row] = cells.join(",");
    std::fs::write(d.join("bad.csv"), lines.join("\n")).unwrap();
    match identify_lines::run(
        &Options::new(d.join("machine.toml"), d.join("bad.csv")),
        &mut Silent,
    ) {
        Err(Error::Input(e)) => {
            assert_eq!(e.file, d.join("bad.csv"));
            assert_eq!(e.line, Some(row + 1), "{e}");
        }
        other => panic!("{other:?}"),
    }
    let mut opts = Options::new(d.join("machine.toml"), d.join("lines.csv"));
    opts.data = None;
    opts.design = Some("nine-line".into());
    opts.stats = Some(d.join("s.csv"));
    assert!(matches!(
        identify_lines::run(&opts, &mut Silent),
        Err(Error::Usage(_))
    ));
}
