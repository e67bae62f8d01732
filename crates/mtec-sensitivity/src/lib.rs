//! mtec-sensitivity: global sensitivity analysis of a model's output to its uncertain inputs.
//!
//! What it is for: telling which inputs (for mtec: which geometric error elements of a machine
//! tool) drive the variance of an output (the volumetric error Ex, Ey, Ez, |E|), alone (the
//! first-order index S1, "key errors") and through interactions (the total index ST; ST − S1
//! measures coupling). Three methods, each split SALib-style into a sampler that draws a design
//! and an analysis that turns the design's outputs into indices, so either half can be used with
//! designs or outputs produced elsewhere:
//! - [`efast`]: extended FAST (Saltelli, Tarantola & Chan 1999), the method of the source
//!   literature;
//! - [`sobol`]: Saltelli 2010 design, Saltelli S1 and Jansen ST estimators, bootstrap intervals;
//! - [`morris`]: elementary effects (μ, μ*, σ), a cheap screening cross-check.
//!
//! The user's model implements [`Model`] (argmin-style: a trait on the user's own type, or a
//! closure through [`FnModel`]); [`evaluate`] runs it on a design in parallel with rayon. Test
//! functions with analytic indices ([`testfns`]: Ishigami, Sobol G, linear) live next to the
//! methods. [`error_model`] applies the methods to a machine's first-order volumetric error
//! model with error statistics read from CSV, and allocates tolerances.
//!
//! What it is not for: correlated inputs (all methods assume independent inputs), second-order
//! Sobol indices, or building the kinematic model itself (that is `mtec-model`).

pub mod distribution;
pub mod efast;
mod error;
pub mod error_model;
mod fastmath;
pub mod interval;
pub mod lhs;
pub mod morris;
pub mod problem;
pub mod sobol;
pub mod testfns;

pub use distribution::Distribution;
pub use error::SensitivityError;
pub use interval::Bootstrap;
pub use problem::{evaluate, FnModel, Indices, Model, Problem, Replicates, SampleMatrix};
