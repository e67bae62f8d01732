//! candle's CPU thread count for the small networks of this crate.
//!
//! candle 0.11 runs every CPU op on a barrier thread pool whose workers spin until the op is done.
//! For networks of this size (a few thousand parameters, 64-row mini-batches) that
//! synchronisation dominates: measured with the source-sized CNN-LSTM on `dbb-rotary` data (2
//! cores, load ≈ 3), 3.49 s per epoch with candle's default thread count against 0.42 s with one
//! thread (`CANDLE_NUM_THREADS=1`) and 0.39 s with `RAYON_NUM_THREADS=1`. The pool is created
//! once, at the first op, from `CANDLE_NUM_THREADS`, so the choice must be made before any
//! training starts.

/// Sets `CANDLE_NUM_THREADS=1` unless the user chose a value. Call it at program start, while the
/// program has no other thread (setting the environment races with threads reading it); the
/// CLI and the examples do.
/// Concurrent callers wait for the first one, so the environment is written at most once.
pub fn prefer_single_thread() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("CANDLE_NUM_THREADS").is_none() {
            std::env::set_var("CANDLE_NUM_THREADS", "1");
        }
    });
}
