//! What a scenario produces (its files and truth) and why one could not run: the types every
//! scenario module returns, below the dispatcher in `scenario`.

/// One file a scenario writes (name relative to the output folder, full text).
#[derive(Debug, Clone)]
pub struct OutputFile {
    pub name: String,
    pub contents: String,
}

/// What a scenario produces: its measurement files and the truth (written as `truth.json`).
#[derive(Debug, Clone)]
pub struct ScenarioOutput {
    pub files: Vec<OutputFile>,
    pub truth: serde_json::Value,
}

/// Why a scenario could not run.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The name asked for, and the names this build knows.
    #[error("unknown scenario `{0}`; known scenarios: {1}")]
    UnknownScenario(String, String),
    #[error("{0}")]
    Invalid(String),
}
