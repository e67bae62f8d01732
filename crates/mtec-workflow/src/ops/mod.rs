//! One module per job of the `mtec` command.
