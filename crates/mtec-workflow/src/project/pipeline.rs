//! The state a project run's stages share: the folders, the observer, the report being built,
//! the files written.

use crate::{Observer, Result};
use mtec_io::OutputGuard;
use mtec_report::Report;
use std::path::{Path, PathBuf};

/// A path as the report and the list of outputs write it.
pub(super) fn s(p: &Path) -> String {
    p.display().to_string()
}

/// The pipeline state shared by the stages.
pub struct Pipeline<'o> {
    pub base: PathBuf,
    pub out: PathBuf,
    /// Progress (`[i/n] stage`) and every job's warnings.
    pub obs: &'o mut dyn Observer,
    pub report: Report,
    pub outputs: Vec<String>,
    pub(super) guard: OutputGuard,
    pub(super) step: usize,
    pub(super) steps: usize,
    /// The stage running now (its progress line).
    pub(super) current: String,
    /// What the report's first section says (filled by the stages).
    pub summary: super::summary::Summary,
    /// The project's `[tolerances]`.
    pub tolerances: super::spec::Tolerances,
}

impl Pipeline<'_> {
    /// A path of the project file, relative to the project's folder.
    pub fn path_of(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base.join(p)
        }
    }

    /// The next stage starts: `[i/n] what` to the observer.
    pub fn progress_of(&mut self, what: &str) {
        // the stage before this one ran to its end
        if !self.current.is_empty() {
            self.summary
                .completed
                .push(std::mem::take(&mut self.current));
        }
        self.step += 1;
        self.current = what.to_string();
        self.obs
            .progress(&format!("[{}/{}] {what}", self.step, self.steps));
    }

    pub(super) fn save(&mut self, name: &str, text: &str) -> Result<PathBuf> {
        let p = self.out.join(name);
        self.guard.write(&p, text.as_bytes())?;
        self.outputs.push(s(&p));
        Ok(p)
    }

    /// Saves a job's JSON result (`text`, as its command prints it with `--json`) in the output
    /// folder and returns it parsed.
    pub fn json_result(&mut self, file: &str, text: &str) -> Result<serde_json::Value> {
        self.save(file, text)?;
        Ok(serde_json::from_str(text)?)
    }
}
