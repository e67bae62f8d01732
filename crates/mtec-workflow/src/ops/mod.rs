//! One module per job of the `mtec` command.

pub mod circular;
pub mod iso230_2;
