//! What a long job tells its caller while it runs: progress and warnings. Passed in by the
//! caller (the CLI prints them on stderr, Python forwards them, a test collects them); the
//! library never prints, draws progress bars or reads a global flag itself.

/// Receives progress and warnings of a job. Every method has a default that ignores it.
pub trait Observer {
    /// A step of a long job starts (`what` is a short phrase, e.g. "fitting ch1").
    fn progress(&mut self, _what: &str) {}
    /// Something the user should know about the inputs or the result. Every warning is also
    /// kept in the job's outcome.
    fn warning(&mut self, _what: &str) {}
    /// True when the caller asks the job to stop at its next safe point (Ctrl-C); a job that
    /// stops early says so in its outcome.
    fn stop_requested(&self) -> bool {
        false
    }
}

/// An observer that ignores everything.
#[derive(Debug, Default, Clone, Copy)]
pub struct Silent;

impl Observer for Silent {}

/// An observer that keeps what it was told (tests, Python).
#[derive(Debug, Default, Clone)]
pub struct Collect {
    pub progress: Vec<String>,
    pub warnings: Vec<String>,
}

impl Observer for Collect {
    fn progress(&mut self, what: &str) {
        self.progress.push(what.to_string());
    }
    fn warning(&mut self, what: &str) {
        self.warnings.push(what.to_string());
    }
}

/// An observer as a neural training's monitor: each epoch as progress, the end of the training
/// as progress, the observer's stop request as the training's.
#[cfg(feature = "neural")]
pub(crate) struct Relay<'a>(pub &'a mut dyn Observer);

#[cfg(feature = "neural")]
impl mtec_nn::Monitor for Relay<'_> {
    fn epoch(&mut self, e: &mtec_nn::Epoch) {
        self.0.progress(&e.to_string());
    }
    fn finished(&mut self, reason: &mtec_nn::StopReason) {
        self.0.progress(&format!("stopped: {reason}"));
    }
    fn stop_requested(&self) -> bool {
        self.0.stop_requested()
    }
}
