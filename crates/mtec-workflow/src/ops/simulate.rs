//! A scenario of the virtual machine (`mtec_sim::run_scenario`) written to a folder: its
//! measurement files and `truth.json`. The job of `mtec simulate`.

use crate::{Error, Observer, Result};
use mtec_io::write_output;
use serde::Serialize;
use std::fmt;
use std::path::PathBuf;

pub use mtec_sim::SCENARIOS;

/// The name of the ground-truth file the job writes next to the measurement files.
pub const TRUTH_FILE: &str = "truth.json";

/// Which scenario, with which seed, into which folder.
#[derive(Debug, Clone)]
pub struct Options {
    /// Scenario name (one of [`SCENARIOS`]).
    pub scenario: String,
    /// Output folder; `None`: `./<scenario>-seed<seed>`.
    pub out: Option<PathBuf>,
    /// Random seed: noise, ground-truth shapes.
    pub seed: u64,
}

impl Options {
    /// Seed 1 into the default folder, as `mtec simulate SCENARIO` does.
    pub fn new(scenario: impl Into<String>) -> Options {
        Options {
            scenario: scenario.into(),
            out: None,
            seed: 1,
        }
    }

    /// The folder the files go into.
    pub fn dir(&self) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("{}-seed{}", self.scenario, self.seed)))
    }
}

/// What was written.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// The scenario's name.
    pub scenario: String,
    /// Its seed.
    pub seed: u64,
    /// The folder written into.
    pub dir: PathBuf,
    /// The measurement files written (paths in `dir`), in the scenario's order.
    pub files: Vec<PathBuf>,
    /// The ground truth written (`dir/truth.json`).
    pub truth: PathBuf,
}

/// Runs the scenario and writes its files and `truth.json` into the folder.
pub fn run(opts: &Options, _obs: &mut dyn Observer) -> Result<Outcome> {
    let output = mtec_sim::run_scenario(&opts.scenario, opts.seed)
        .map_err(|e| Error::usage(e.to_string()))?;
    let dir = opts.dir();
    let mut files = Vec::with_capacity(output.files.len());
    for f in &output.files {
        let path = dir.join(&f.name);
        write_output(&path, f.contents.as_bytes())?;
        files.push(path);
    }
    let truth = dir.join(TRUTH_FILE);
    write_output(
        &truth,
        serde_json::to_string_pretty(&output.truth)?.as_bytes(),
    )?;
    Ok(Outcome {
        scenario: opts.scenario.clone(),
        seed: opts.seed,
        dir,
        files,
        truth,
    })
}

impl fmt::Display for Outcome {
    fn fmt(&self, o: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            o,
            "{}: wrote {} files and {TRUTH_FILE} to {}",
            self.scenario,
            self.files.len(),
            self.dir.display()
        )?;
        for f in &self.files {
            writeln!(o, "  {}", f.display())?;
        }
        Ok(())
    }
}
