//! Fuzz target for the path bound (issue 15): the fuzzer's bytes choose a random program of
//! lines and arcs (I/J/K and R format, near-semicircles, full circles without axis words, P
//! turns, helices, G18/G19, G91) and a random trilinear map with single-node bumps, through the
//! same generators as `crates/mtec-comp/tests/gcode_path_bound.rs`; the rewritten program,
//! pushed through the machine p + e(p) sample by sample, must stay within the documented bound
//! of the original path (`--tolerance-um` + `--chord-tolerance-um`).
//!
//!   cd fuzz && cargo +nightly fuzz run gcode_path_bound -- -max_total_time=600
#![no_main]

#[path = "../../crates/mtec-comp/tests/gcode_support/mod.rs"]
mod gcode_support;

use gcode_support::{check_path_dense, random_map, random_program, Rng};
use libfuzzer_sys::fuzz_target;
use mtec_comp::gcode::{rewrite, RewriteOptions};

fuzz_target!(|data: &[u8]| {
    let mut seed = [0u8; 8];
    for (i, b) in data.iter().enumerate() {
        seed[i % 8] ^= b.rotate_left((i / 8) as u32 % 8);
    }
    let mut r = Rng(u64::from_le_bytes(seed));
    let map = random_map(&mut r);
    let program = random_program(&mut r);
    let opts = RewriteOptions::default();
    let bound = (opts.tolerance_um + opts.chord_tolerance_um) * 1e-3;
    let mut out = Vec::new();
    rewrite(program.as_bytes(), &mut out, &map, &opts).expect("generated programs are compensable");
    let out = String::from_utf8(out).expect("the rewriter writes UTF-8 for UTF-8 input");
    check_path_dense(&program, &out, &map, &[[0.0; 3]; 6], None, 0.05, bound);
});
