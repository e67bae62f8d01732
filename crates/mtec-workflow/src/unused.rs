//! Options a command was given that its chosen model, method or format does not read: refused
//! with exit code 2, never ignored without a word, so that nobody believes a setting took
//! effect (`thermal fit --model ridge --learning-rate 0.01` used to fit ridge and say nothing;
//! `compensate table --format linuxcnc --magnification 2` wrote a table without it).

use crate::{Error, Result};
use std::borrow::Cow;

/// One option a user may have given: its name, whether it was given, whether the chosen
/// model, method or format reads it, and what does (for the message).
pub struct Given<'a> {
    pub option: &'a str,
    pub given: bool,
    pub read: bool,
    pub read_by: Cow<'a, str>,
}

impl<'a> Given<'a> {
    /// An option that the choice reads when `read`; `read_by` says what reads it.
    pub fn new(option: &'a str, given: bool, read: bool, read_by: &'a str) -> Self {
        Given {
            option,
            given,
            read,
            read_by: Cow::Borrowed(read_by),
        }
    }

    /// An option that the choices `read_by` read, given to `chosen`.
    pub fn among(option: &'a str, given: bool, read_by: &[&str], chosen: &[&str]) -> Self {
        Given {
            option,
            given,
            read: read_by.iter().any(|r| chosen.contains(r)),
            read_by: Cow::Owned(read_by.join(" and ")),
        }
    }
}

/// Refuses the first option given that the choice does not read; `what` names the choice the
/// way the user wrote it (`--model ridge`).
pub fn refuse_unused(what: &str, options: &[Given]) -> Result<()> {
    match options.iter().find(|o| o.given && !o.read) {
        None => Ok(()),
        Some(o) => Err(refused(o.option, &o.read_by, what)),
    }
}

/// The refusal of one option: `option` is read by `read_by` only, not by `what`.
pub fn refused(option: &str, read_by: &str, what: &str) -> Error {
    Error::usage(format!(
        "{option} is read by {read_by} only; {what} does not use it: leave it out"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_no_chosen_model_reads_is_refused_by_name() {
        let options = |chosen: &[&str]| {
            [
                Given::among("--window", true, &["cnn-lstm"], chosen),
                Given::among("--hidden", false, &["bpnn"], chosen),
            ]
        };
        assert!(refuse_unused("--model cnn-lstm", &options(&["cnn-lstm"])).is_ok());
        assert!(refuse_unused("auto", &options(&["bpnn", "cnn-lstm"])).is_ok());
        let e = refuse_unused("--model bpnn", &options(&["bpnn"])).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(
            e.to_string(),
            "--window is read by cnn-lstm only; --model bpnn does not use it: leave it out"
        );
    }
}
