//! The `Examples` section that ends the `--help` of every leaf command.
//!
//! Each command's examples are one block: `#` lines say what the next command does, `$ ` lines
//! are the commands (a line ending in `\` continues on the next), and the block runs as written,
//! in order, in an empty folder: every file a command reads, an earlier line of the same block
//! writes. `tests/help_examples.rs` runs every block.

/// The heading every example block starts with.
macro_rules! examples {
    ($body:expr) => {
        concat!(
            "Examples (they run as written, in order, in an empty folder):\n",
            $body
        )
    };
}
pub(crate) use examples;
