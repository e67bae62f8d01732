//! How the CLI shows what a library job tells it: progress and warnings on stderr.

/// Prints warnings (`warning: ...`) and, unless quiet, progress on stderr.
#[derive(Debug, Default)]
pub struct Stderr {
    pub quiet: bool,
}

impl mtec_workflow::Observer for Stderr {
    fn progress(&mut self, what: &str) {
        if !self.quiet {
            eprintln!("{what}");
        }
    }
    fn warning(&mut self, what: &str) {
        eprintln!("warning: {what}");
    }
}
