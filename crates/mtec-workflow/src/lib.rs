//! The mtec workflow as a library.
//!
//! Every job the `mtec` command does lives here, so that a Rust program, the Python module and
//! the CLI run the same code and write the same files:
//!
//! - [`ops`]: one module per job (`ops::iso230_2`, `ops::map`, ...). Each takes an options
//!   struct (plain data: paths and values, no command-line types), reads its inputs, calls the
//!   numerical crates, writes its outputs atomically and returns a typed outcome that serialises
//!   to the JSON the CLI prints with `--json` and renders the CLI's text report (`Display`).
//!   Warnings go into the outcome and to the [`Observer`]; nothing is printed here.
//! - [`Error`]: bad input (located: file, line, column), a usage error, or an internal failure;
//!   the CLI maps them to exit codes 2, 2 and 1.
//!
//! Conventions of an op: `pub fn run(opts: &Options, obs: &mut dyn Observer) -> Result<Outcome>`;
//! outputs that would overwrite an input are refused before any work (`mtec_io::OutputGuard`).

pub mod choice;
pub mod error;
pub mod inputs;
pub mod observer;
pub mod ops;
pub mod project;
pub mod rs274;
pub mod state;
pub mod unused;

pub use choice::Choice;
pub use error::{Error, Result};
pub use observer::{Collect, Observer, Silent};

/// The refusal of `what` (e.g. "`thermal fit --model cnn-lstm`") by a build without the neural
/// models (cargo feature `neural`, off by default: candle more than doubles a cold build): a
/// usage error that says how to build them.
pub fn neural_unavailable(what: &str) -> Error {
    Error::usage(format!(
        "{what} needs the neural models, and this mtec was built without them (cargo feature \
         `neural`, off by default because it more than doubles a cold build): build with \
         `cargo build --release --features neural`, or install with \
         `cargo install --path crates/mtec-cli --features neural`"
    ))
}

/// An outcome as pretty JSON with its keys sorted (through a `serde_json::Value`): the
/// `--json` of the commands whose outcome has no `to_json` of its own.
pub fn pretty_json<T: serde::Serialize>(outcome: &T) -> Result<String> {
    Ok(serde_json::to_string_pretty(&serde_json::to_value(
        outcome,
    )?)?)
}
