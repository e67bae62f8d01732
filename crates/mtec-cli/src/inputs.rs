//! Readers shared by several subcommands: machine TOML, error-set JSON, pose CSV (they live in
//! `mtec_workflow::inputs`; re-exported for the commands not yet moved there).

#[allow(unused_imports)]
pub use mtec_workflow::inputs::{pose_column, read_errors, read_machine, read_poses};
