//! The place of the project workflow (`mtec run PROJECT.toml`) in the Python module.
//!
//! When the pipeline lands in `mtec_workflow` (issue 18, item 1), its Python binding goes here:
//! `mtec.run_project(project, out=None)` calling the pipeline in-process with an `Observer`
//! that forwards progress and warnings to Python (`warnings.warn`) and asks Python for Ctrl-C
//! (`Python::check_signals`), returning the typed results as the report's JSON (numpy arrays for
//! its tables, see `crate::convert`), and raising the located errors of `crate::errors`.
//! Register it in `lib.rs` next to the other functions, add it to `python/mtec/__init__.py`,
//! `__init__.pyi` and docs/python.md, and test it against `mtec run` on the same project
//! (byte-identical model files, the same report numbers).
