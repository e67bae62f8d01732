//! What a long command shows while a library job runs: warnings on stderr, training progress as
//! one redrawn line, Ctrl-C as the request to stop (neural trainings: the only epoch reporters).

use mtec_workflow::Observer;
use std::io::IsTerminal;

/// Warnings on stderr as `warning: ...`; training progress as one line redrawn on stderr when
/// it is a terminal (none with `--quiet`); Ctrl-C as the request to stop.
pub struct Terminal {
    quiet: bool,
    /// The progress line is on the terminal (a newline ends it).
    drawn: bool,
}

impl Terminal {
    pub fn new(quiet: bool) -> Self {
        Terminal {
            quiet: quiet || !std::io::stderr().is_terminal(),
            drawn: false,
        }
    }
    /// Ends the progress line.
    pub fn done(&mut self) {
        if self.drawn {
            eprintln!();
            self.drawn = false;
        }
    }
}

impl Observer for Terminal {
    fn progress(&mut self, what: &str) {
        if !self.quiet {
            eprint!("\r\x1b[2K{what}");
            self.drawn = true;
        }
    }
    fn warning(&mut self, what: &str) {
        self.done();
        eprintln!("warning: {what}");
    }
    fn stop_requested(&self) -> bool {
        ctrl_c::requested()
    }
}

/// Ctrl-C during a training: the first asks it to stop after the current epoch (the best epoch
/// is kept and the file still written), a second ends the process.
pub mod ctrl_c {
    use std::sync::atomic::{AtomicBool, Ordering};

    /// Set by the SIGINT handler while [`during`] runs.
    static INTERRUPTED: AtomicBool = AtomicBool::new(false);

    extern "C" fn on_sigint(_: libc::c_int) {
        // async-signal-safe: an atomic store, then the default action for a second Ctrl-C
        INTERRUPTED.store(true, Ordering::Relaxed);
        // SAFETY: restoring the default disposition is async-signal-safe.
        unsafe {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
        }
    }

    pub fn requested() -> bool {
        INTERRUPTED.load(Ordering::Relaxed)
    }

    /// Runs `f` with Ctrl-C turned into a request to stop ([`requested`]).
    pub fn during<T>(f: impl FnOnce() -> T) -> T {
        INTERRUPTED.store(false, Ordering::Relaxed);
        let handler = on_sigint as extern "C" fn(libc::c_int);
        // SAFETY: installs a handler that only stores to an atomic and resets the disposition.
        unsafe {
            libc::signal(libc::SIGINT, handler as libc::sighandler_t);
        }
        let out = f();
        // SAFETY: back to the default disposition.
        unsafe {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
        }
        out
    }
}
