//! One module per job of the `mtec` command.

pub mod thermal;
