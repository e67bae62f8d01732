//! Ballbar (double ball bar, DBB) identification of the error motions of a rotary C axis.
//!
//! What it is for: from ballbar readings taken in five installation modes while the C axis
//! turns, recover the five observable error motions `EXC EYC EZC` (µm) and `EAC EBC` (µrad) at
//! every measured angle, for every experiment and time step (static errors at t = 0, thermal
//! errors later), and say how well the installation modes condition that problem.
//!
//! The path of the data, one module each:
//! - [`setup`]: the installation modes (TOML `[[mode]]` tables with the two ball positions),
//!   their validation, and the preset of the source layout (two centre mounts, constant bar
//!   length).
//! - [`model`]: the bar-length model. Exact: rigid-body transform of the table by the error
//!   motions, bar length from the transformed ball centre. First order:
//!   `L0·ΔL = (r_w − r_t)·Δr(e)`, i.e. `ΔL = n·(δ + ε × r_w)` with `n` the unit bar vector.
//! - [`conditioning`]: the per-angle 5×5 identification matrix, its SVD (rank, singular values,
//!   condition number, worst angle), refusal of a rank-deficient mode set with the invisible
//!   combination named, and the design helper that scores a mode set and searches the preset's
//!   free dimensions.
//! - [`harmonics`]: installation-error removal (mean and first harmonic of each mode signal).
//! - [`mod@identify`]: reading the DBB file, grouping it by experiment/time/mode, and the per-angle
//!   solution.
//! - [`revolution`]: the revolution-level solve of any number of installations at once, each with
//!   its own set-up error: harmonics 1 (the part a ballbar can see) to N, for mode sets that
//!   break the families the five-mode preset cannot see (radial bars at a second height, inclined
//!   bars with their cup at a second height, an axial bar).
//! - [`positioning`]: `ECC` from a rotary positioning test (ISO 230-2) against a reference
//!   instrument: the motion no bar in an axial plane sees.
//!
//! What it is not for: the ISO 230-4 circular test of two linear axes (that is `mtec-measure`),
//! or location errors of the axis (`EX0C EY0C EA0C EB0C`): they are constant or first-harmonic
//! in the readings and are removed together with the set-up error.
//!
//! Conventions (decided here, the spec is silent):
//! - Frames: machine frame X, Y, Z; the C axis is the Z axis through the origin; `C` turns the
//!   table counter-clockwise seen from +Z. A workpiece ball at `p` on the table (coordinates at
//!   C = 0) is ideally at `Rz(C)·p`.
//! - Error motions are defined in the reference (machine) frame, after the ideal rotation
//!   (ISO 230-7 measures them with fixed sensors): the actual pose of the table is
//!   `E(C)·Rz(C)` with `E = Trans(EXC, EYC, EZC)·Rz(ECC)·Ry(EBC)·Rx(EAC)`, the angular motions
//!   turning about the origin (axis average line at the height Z = 0 of the table reference).
//!   This is `mtec-model`'s `error_frame = "reference"` order; motions `E'` given in the turning
//!   table frame (`error_frame = "moving"`, `Rz(C)·E'`) are the same motions seen from the table:
//!   `E' = Rz(−C)·E·Rz(C)`. The exact transforms are `mtec_model::Htm` (`error_exact`,
//!   `rotation`).
//! - `dl_um` is the bar reading minus its value with no error motions (positive = longer bar).
//! - Resolution: at one angle the tilts `EAC`, `EBC` are separated from the radial motions only
//!   by the difference in height of the radial bars (h) and the inclined bars' cup (h + k), so
//!   reading noise σ maps to roughly `2.1·σ/b` µrad per µm (b in m): 1.4 µrad with a 150 mm bar at
//!   σ = 0.1 µm, 0.42 µrad with 500 mm. The conditioning report's `worst_noise_gain` gives the
//!   exact figure for a mode set; [`search_preset`] finds the best preset within given ranges.
//! - `ECC` (rotation about the axis itself) is not observable when every bar lies in a plane that
//!   contains the axis: its coefficient is `(r_w × n)_z = 0`. Mode sets whose bars leave such a
//!   plane are reported (`ecc_coefficient_max`) because an `ECC` motion then leaks into the five.

pub mod conditioning;
pub mod errors;
pub mod harmonics;
pub mod identify;
pub mod model;
pub mod motions_file;
pub mod positioning;
pub mod revolution;
pub mod setup;
pub mod temps;

pub use conditioning::{
    check_identifiable, conditioning_report, revolution_observability, score_mode_set,
    search_preset, AngleConditioning, ConditioningReport, DesignResult, DesignScore, PresetRanges,
    RevolutionObservability,
};
pub use errors::motions_to_errors;
pub use harmonics::remove_mean_and_first_harmonic;
pub use identify::{identify, Identification, IdentifiedRow, Measurements};
pub use model::{
    exact_dl_um, first_order_row, identification_matrix, predicted_dl_um, ErrorMotions,
    OBSERVABLE_NAMES,
};
pub use positioning::{ecc_from_positioning, mean_bidirectional_urad};
pub use revolution::{
    identify_revolution, observability, setup_terms, Basis, FirstHarmonic, ModeSignal,
    Observability, RevolutionIdentification, SetupTerms,
};
pub use setup::{Mode, PresetDims, Setup};
pub use temps::{time_key, TemperatureLog};

/// Why a ballbar identification cannot be done (no file location: the caller adds it).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BallbarError {
    /// The mode set cannot separate the five error motions at some angle.
    #[error("the mode set is rank-deficient: at C = {angle_deg} deg the identification matrix has rank {rank} of 5 (singular values {singular_values}); the combination {null_combination} of error motions changes no bar length, so it cannot be identified. {hint}")]
    RankDeficient {
        angle_deg: f64,
        rank: usize,
        singular_values: String,
        null_combination: String,
        hint: String,
    },
    /// A geometric parameter is impossible (e.g. the preset with a >= b).
    #[error("{0}")]
    Geometry(String),
    /// A mode signal cannot be processed (angles not a full, evenly spaced revolution, ...).
    #[error("{0}")]
    Signal(String),
}
