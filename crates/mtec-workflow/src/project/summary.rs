//! The report's first section (issue 23): the machine, the date, the data files with their
//! dates and checksums, the standards applied, every stage's key figures with units against the
//! project's tolerances, the stages that failed or did not run, and the overall verdict.

use mtec_report::{KeyFigure, Section, Verdict};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// What the stages found worth a line of the summary, collected as they run.
#[derive(Debug, Default)]
pub struct Summary {
    pub machine: Option<String>,
    figures: Vec<KeyFigure>,
    standards: Vec<String>,
    /// Stages that ran to the end, in order.
    pub completed: Vec<String>,
}

/// A value judged against a tolerance on its magnitude: |value| ≤ tolerance passes.
fn judge(value: f64, tolerance: Option<f64>) -> Verdict {
    match tolerance {
        None => Verdict::NotJudged,
        Some(t) if value.abs() <= t => Verdict::Pass,
        Some(_) => Verdict::Fail,
    }
}

impl Summary {
    /// A key figure: `value` in `unit` with `decimals`, judged against `tolerance` (same unit).
    pub fn figure(
        &mut self,
        stage: &str,
        quantity: &str,
        value: f64,
        unit: &str,
        decimals: usize,
        tolerance: Option<f64>,
    ) {
        let with_unit = |x: f64| {
            if unit.is_empty() {
                format!("{x:.decimals$}")
            } else {
                format!("{x:.decimals$} {unit}")
            }
        };
        self.figures.push(KeyFigure {
            stage: stage.to_string(),
            quantity: quantity.to_string(),
            value: with_unit(value),
            tolerance: tolerance.map(|t| format!("≤ {}", with_unit(t))),
            verdict: judge(value, tolerance),
        });
    }

    /// A finding that is not a number (e.g. the key error elements); never judged.
    pub fn fact(&mut self, stage: &str, quantity: &str, value: impl Into<String>) {
        self.figures.push(KeyFigure {
            stage: stage.to_string(),
            quantity: quantity.to_string(),
            value: value.into(),
            tolerance: None,
            verdict: Verdict::NotJudged,
        });
    }

    /// A standard or method applied (listed once).
    pub fn standard(&mut self, s: &str) {
        if !self.standards.iter().any(|x| x == s) {
            self.standards.push(s.to_string());
        }
    }

    /// The overall verdict: FAIL when a stage failed or a figure is out of tolerance; pass when
    /// at least one figure was judged and all passed; otherwise not judged.
    pub fn verdict(&self, failed: bool) -> Verdict {
        if failed || self.figures.iter().any(|f| f.verdict == Verdict::Fail) {
            Verdict::Fail
        } else if self.figures.iter().any(|f| f.verdict == Verdict::Pass) {
            Verdict::Pass
        } else {
            Verdict::NotJudged
        }
    }

    /// The summary section. `files` are (as the project names it, the file); `failed` is the
    /// stage that failed and its error; `not_run` counts the stages after it.
    pub fn section(
        &self,
        project: &str,
        files: &[(String, PathBuf)],
        failed: Option<(&str, String)>,
        not_run: usize,
    ) -> Section {
        let mut sec = Section::new("Summary");
        let verdict = self.verdict(failed.is_some());
        let judged = self
            .figures
            .iter()
            .filter(|f| f.verdict != Verdict::NotJudged)
            .count();
        let out = self
            .figures
            .iter()
            .filter(|f| f.verdict == Verdict::Fail)
            .count();
        let text = match (verdict, &failed) {
            (Verdict::Fail, Some((stage, _))) => format!(
                "FAIL: the stage \u{201c}{stage}\u{201d} failed; the results below are incomplete."
            ),
            (Verdict::Fail, None) => {
                format!("FAIL: {out} of {judged} figures with a tolerance are outside it.")
            }
            (Verdict::Pass, _) => {
                format!("PASS: all {judged} figures with a tolerance are within it.")
            }
            (Verdict::NotJudged, _) => "Not judged: the project file gives no tolerances \
                 (add a [tolerances] table to judge the results)."
                .to_string(),
        };
        sec.verdict(verdict, text);
        let mut facts = vec![["project".to_string(), project.to_string()]];
        if let Some(m) = &self.machine {
            facts.push(["machine".into(), m.clone()]);
        }
        facts.push(["report date".into(), report_date()]);
        facts.push([
            "standards and methods".into(),
            if self.standards.is_empty() {
                "—".into()
            } else {
                self.standards.join("; ")
            },
        ]);
        sec.facts(facts);
        if !self.figures.is_empty() {
            sec.key_figures(self.figures.clone());
        }
        let mut stages: Vec<Vec<String>> = self
            .completed
            .iter()
            .map(|s| vec![s.clone(), "done".into()])
            .collect();
        if let Some((stage, e)) = &failed {
            stages.push(vec![stage.to_string(), format!("FAILED: {e}")]);
        }
        if not_run > 0 {
            stages.push(vec![
                format!("{not_run} later stage(s)"),
                "not run (an earlier stage failed)".into(),
            ]);
        }
        sec.text("Stages:");
        sec.table(&["stage", "status"], stages);
        sec.text("Data files (the SHA-256 identifies the exact file the results come from):");
        sec.table(
            &["file", "modified (UTC)", "size (bytes)", "SHA-256"],
            files.iter().map(|(name, f)| file_row(name, f)).collect(),
        );
        sec
    }
}

/// The report's date: `SOURCE_DATE_EPOCH` (seconds, the reproducible-builds convention) when
/// set, so that two runs of the same project give the same file; otherwise today (UTC).
fn report_date() -> String {
    let t = std::env::var("SOURCE_DATE_EPOCH")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok())
        .map(|s| UNIX_EPOCH + Duration::from_secs(s))
        .unwrap_or_else(SystemTime::now);
    humantime::format_rfc3339_seconds(t).to_string()[..10].to_string()
}

fn file_row(name: &str, f: &Path) -> Vec<String> {
    let meta = std::fs::metadata(f).ok();
    let modified = meta
        .as_ref()
        .and_then(|m| m.modified().ok())
        .map(|t| humantime::format_rfc3339_seconds(t).to_string())
        .unwrap_or_else(|| "—".into());
    let size = meta
        .map(|m| m.len().to_string())
        .unwrap_or_else(|| "—".into());
    vec![name.to_string(), modified, size, sha256_hex(f)]
}

/// The SHA-256 of a file as 64 hex digits ("—" if it cannot be read).
pub fn sha256_hex(f: &Path) -> String {
    match std::fs::read(f) {
        Ok(bytes) => Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect(),
        Err(_) => "—".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_follow_the_tolerances_and_failures() {
        let mut s = Summary::default();
        s.figure("ISO 230-2", "A", 12.0, "µm", 1, None);
        assert_eq!(s.verdict(false), Verdict::NotJudged);
        s.figure("ISO 230-2", "R", -3.0, "µm", 1, Some(4.0));
        assert_eq!(s.verdict(false), Verdict::Pass);
        assert_eq!(s.verdict(true), Verdict::Fail);
        s.figure("ISO 230-4", "G", 16.0, "µm", 1, Some(15.0));
        assert_eq!(s.verdict(false), Verdict::Fail);
        assert_eq!(s.figures[2].tolerance.as_deref(), Some("≤ 15.0 µm"));
    }

    #[test]
    fn the_checksum_is_sha256() {
        // FIPS 180-2 appendix B.1: SHA-256("abc")
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("abc");
        std::fs::write(&f, "abc").unwrap();
        assert_eq!(
            sha256_hex(&f),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
