//! The help texts of the commands (`help/*.txt`) and the `Examples` ending every leaf's `--help`.
//!
//! Each command's examples are one block: `#` lines say what the next command does, `$ ` lines
//! are the commands (a line ending in `\` continues on the next), and the block runs as written,
//! in order, in an empty folder: every file a command reads, an earlier line of the same block
//! writes. `tests/help_examples.rs` runs every block.

/// The text of `help/NAME.txt`, e.g. `text!("iso230_2.long")`.
macro_rules! text {
    ($name:literal) => {
        include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/help/", $name, ".txt"))
    };
}
pub(crate) use text;

/// The examples of `help/NAME.txt` under the heading every example block starts with.
macro_rules! examples {
    ($name:literal) => {
        concat!(
            "Examples (they run as written, in order, in an empty folder):\n",
            $crate::help::text!($name)
        )
    };
}
pub(crate) use examples;
