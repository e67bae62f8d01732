//! candle's CPU thread count for the small networks of this crate (the BPNN's Adam; the
//! CNN-LSTM runs on its own single-threaded kernel, `cnn_lstm_kernel`, and needs none of this).
//!
//! candle 0.11 runs every CPU op on a barrier thread pool whose workers spin until the op is done.
//! For networks of this size (a few thousand parameters, 64-row mini-batches) that
//! synchronisation dominates: measured with the source-sized CNN-LSTM on `dbb-rotary` data (2
//! cores, load ≈ 3), when it still ran on candle, 3.49 s per epoch with candle's default thread
//! count against 0.42 s with one thread (`CANDLE_NUM_THREADS=1`) and 0.39 s with
//! `RAYON_NUM_THREADS=1`. candle creates that pool once, at the first op, from
//! `CANDLE_NUM_THREADS`; and every matmul asks for the core count again, from
//! `RAYON_NUM_THREADS` or else by reading the system's CPU description (8–10 % of a CNN-LSTM
//! epoch in a profile, issue 22). Neither has another way to be set, so the choice is the
//! program's, made in its `main` before any thread starts. This crate never writes the
//! environment: it only says what to set.

/// The environment variable candle sizes its CPU pool from.
pub const CANDLE_NUM_THREADS: &str = "CANDLE_NUM_THREADS";
/// The environment variable candle's matmul reads its thread count from at every call.
pub const RAYON_NUM_THREADS: &str = "RAYON_NUM_THREADS";

/// The settings a program should make before its first candle op, `(variable, value)`: one
/// thread for each of the two variables the user has not set.
///
/// ```
/// for (var, value) in mtec_nn::threads::single_thread_settings() {
///     // in `main`, before any other thread exists
///     std::env::set_var(var, value);
/// }
/// ```
pub fn single_thread_settings() -> Vec<(&'static str, &'static str)> {
    [CANDLE_NUM_THREADS, RAYON_NUM_THREADS]
        .into_iter()
        .filter(|v| std::env::var_os(v).is_none())
        .map(|v| (v, "1"))
        .collect()
}
