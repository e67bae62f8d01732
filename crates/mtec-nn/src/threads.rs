//! candle's CPU thread count for the small networks of this crate.
//!
//! candle 0.11 runs every CPU op on a barrier thread pool whose workers spin until the op is done.
//! For networks of this size (a few thousand parameters, 64-row mini-batches) that
//! synchronisation dominates: measured with the source-sized CNN-LSTM on `dbb-rotary` data (2
//! cores, load ≈ 3), 3.49 s per epoch with candle's default thread count against 0.42 s with one
//! thread (`CANDLE_NUM_THREADS=1`) and 0.39 s with `RAYON_NUM_THREADS=1`. candle creates that
//! pool once, at the first op, from the environment variable `CANDLE_NUM_THREADS`, and offers
//! no other way to size it; so the choice is the program's, made in its `main` before any
//! thread starts. This crate never writes the environment: it only says what to set.

/// The environment variable candle sizes its CPU pool from.
pub const CANDLE_NUM_THREADS: &str = "CANDLE_NUM_THREADS";

/// The setting a program should make before its first candle op, `(variable, value)`, or
/// `None` when the user already chose one:
///
/// ```
/// if let Some((var, value)) = mtec_nn::threads::single_thread_setting() {
///     // in `main`, before any other thread exists
///     std::env::set_var(var, value);
/// }
/// ```
pub fn single_thread_setting() -> Option<(&'static str, &'static str)> {
    std::env::var_os(CANDLE_NUM_THREADS)
        .is_none()
        .then_some((CANDLE_NUM_THREADS, "1"))
}
