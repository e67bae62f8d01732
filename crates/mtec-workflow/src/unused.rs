//! Options a command was given that its chosen model, method or format does not read: refused
//! with exit code 2, never ignored without a word, so that nobody believes a setting took
//! effect (`thermal fit --model ridge --learning-rate 0.01` used to fit ridge and say nothing).

use crate::{Error, Result};

/// One option a user may have given: its name, whether it was given, and the choices (models,
/// methods, formats) that read it.
pub struct Given<'a> {
    pub option: &'a str,
    pub given: bool,
    pub read_by: &'a [&'a str],
}

/// Refuses the first option given that none of `chosen` reads; `what` names the choice the way
/// the user wrote it (`--model ridge`).
pub fn refuse_unused(chosen: &[&str], what: &str, options: &[Given]) -> Result<()> {
    let unused = options
        .iter()
        .find(|o| o.given && !o.read_by.iter().any(|r| chosen.contains(r)));
    match unused {
        None => Ok(()),
        Some(o) => Err(Error::usage(format!(
            "{} is read by {} only; {what} does not use it: leave it out",
            o.option,
            o.read_by.join(" and ")
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_no_chosen_model_reads_is_refused_by_name() {
        let options = [
            Given {
                option: "--window",
                given: true,
                read_by: &["cnn-lstm"],
            },
            Given {
                option: "--hidden",
                given: false,
                read_by: &["bpnn"],
            },
        ];
        assert!(refuse_unused(&["cnn-lstm"], "--model cnn-lstm", &options).is_ok());
        assert!(refuse_unused(&["bpnn", "cnn-lstm"], "auto", &options).is_ok());
        let e = refuse_unused(&["bpnn"], "--model bpnn", &options).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(
            e.to_string(),
            "--window is read by cnn-lstm only; --model bpnn does not use it: leave it out"
        );
    }
}
