//! `ops::simulate` in-process: the files written are the scenario's, byte for byte, with its
//! truth; the same seed gives the same files and another seed other ones; an unknown scenario
//! is a usage error that names the known ones.

use mtec_workflow::ops::simulate::{self, Options, SCENARIOS, TRUTH_FILE};
use mtec_workflow::{Error, Silent};

#[test]
fn the_scenario_files_and_its_truth_are_written_into_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    let mut opts = Options::new("vmc-9line");
    assert_eq!(opts.dir(), std::path::Path::new("vmc-9line-seed1"));
    opts.out = Some(dir.path().join("d"));
    let o = simulate::run(&opts, &mut Silent).unwrap();
    let sim = mtec_sim::run_scenario("vmc-9line", 1).unwrap();
    assert_eq!(o.files.len(), sim.files.len());
    for (path, f) in o.files.iter().zip(&sim.files) {
        assert_eq!(path, &dir.path().join("d").join(&f.name));
        assert_eq!(std::fs::read_to_string(path).unwrap(), f.contents);
    }
    assert!(o.files.iter().any(|p| p.ends_with("machine.toml")));
    assert!(o.files.iter().any(|p| p.ends_with("lines.csv")));
    assert_eq!(o.truth, dir.path().join("d").join(TRUTH_FILE));
    let truth = std::fs::read_to_string(&o.truth).unwrap();
    assert_eq!(truth, serde_json::to_string_pretty(&sim.truth).unwrap());
    assert!(truth.contains("\"format\": \"mtec.truth/1\""));
    let text = o.to_string();
    assert!(text.starts_with(&format!(
        "vmc-9line: wrote {} files and truth.json to {}\n  ",
        sim.files.len(),
        dir.path().join("d").display()
    )));
    assert_eq!(text.lines().count(), 1 + sim.files.len());

    // another seed: another machine of the same kind
    opts.seed = 2;
    opts.out = Some(dir.path().join("d2"));
    let o2 = simulate::run(&opts, &mut Silent).unwrap();
    assert_ne!(
        std::fs::read(&o2.truth).unwrap(),
        std::fs::read(&o.truth).unwrap()
    );
}

#[test]
fn an_unknown_scenario_is_a_usage_error_naming_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let mut opts = Options::new("nope");
    opts.out = Some(dir.path().join("x"));
    match simulate::run(&opts, &mut Silent).unwrap_err() {
        Error::Usage(m) => {
            assert!(m.starts_with("unknown scenario `nope`"), "{m}");
            for (name, _) in SCENARIOS {
                assert!(m.contains(name), "{m}");
            }
        }
        other => panic!("{other}"),
    }
    assert!(!dir.path().join("x").exists());
}
