//! What the bench examples share (`gcode_rewrite`, `map_batch`).

/// CPU time of the calling thread, ns (Linux: `/proc/thread-self/schedstat`; 0 elsewhere).
pub fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}
