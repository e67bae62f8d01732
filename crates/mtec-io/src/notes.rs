//! Notes about what the readers assumed (a spreadsheet dialect), kept for the program to show.
//!
//! A library function several calls deep reads a file; the command that called it is the one that
//! talks to the user. Readers [`record`] their notes here and the command line takes them with
//! [`take`] when the command ends and prints them, so a note is never lost in between. The same
//! note is kept once (a file read twice says so once).

use std::sync::Mutex;

static NOTES: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// Keeps `notes` for [`take`] (each distinct note once).
pub fn record(notes: &[String]) {
    if notes.is_empty() {
        return;
    }
    let mut all = NOTES.lock().unwrap_or_else(|e| e.into_inner());
    for n in notes {
        if !all.contains(n) {
            all.push(n.clone());
        }
    }
}

/// The notes recorded so far, in order; the store is emptied.
pub fn take() -> Vec<String> {
    std::mem::take(&mut *NOTES.lock().unwrap_or_else(|e| e.into_inner()))
}
