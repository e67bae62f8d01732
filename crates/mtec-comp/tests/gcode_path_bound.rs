//! The path bound on random programs and random maps (issue 15): every sample of every output
//! move, pushed through the machine p + e(p), lies within the documented bound of the original
//! path (`--tolerance-um` + `--chord-tolerance-um`), for programs with straight moves (absolute
//! and G91), arcs in G17/G18/G19 (I/J/K and R format, near-semicircles, full circles without
//! axis words, P turns, helices) over trilinear maps with smooth errors and single-node bumps.
//!
//! 1000 cases in CI (about a second per hundred); `MTEC_PATH_BOUND_CASES=10000` runs more.

use crate::gcode_support;
use gcode_support::*;
use mtec_comp::gcode::{rewrite, RewriteOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

fn cases() -> u32 {
    std::env::var("MTEC_PATH_BOUND_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000)
}

#[test]
fn every_output_sample_lies_within_the_bound_of_the_original_path() {
    // a fixed generator: CI runs the same cases every time (MTEC_PATH_BOUND_SEED varies them)
    let mut seed = [7u8; 32];
    if let Some(s) = std::env::var("MTEC_PATH_BOUND_SEED")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        seed[..8].copy_from_slice(&s.to_le_bytes());
    }
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: cases(),
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &seed),
    );
    let opts = RewriteOptions::default();
    let bound = (opts.tolerance_um + opts.chord_tolerance_um) * 1e-3;
    runner
        .run(&any::<u64>(), |seed| {
            let mut r = Rng(seed);
            let map = random_map(&mut r);
            let program = random_program(&mut r);
            let mut out = Vec::new();
            let res = rewrite(program.as_bytes(), &mut out, &map, &opts);
            prop_assert!(res.is_ok(), "seed {seed}: refused {res:?}\n{program}");
            let out = String::from_utf8(out).unwrap();
            let worst = std::panic::catch_unwind(|| {
                check_path_dense(&program, &out, &map, &[[0.0; 3]; 6], None, 0.05, bound)
            });
            prop_assert!(
                worst.is_ok(),
                "seed {seed}: bound violated\n{program}\n---\n{out}"
            );
            Ok(())
        })
        .unwrap();
}

/// Replays one case: `MTEC_SEED=<seed from a failure> cargo test -p mtec-comp --test integration gcode_path_bound::replay`.
#[test]
fn replay() {
    let Ok(seed) = std::env::var("MTEC_SEED") else {
        return;
    };
    let seed: u64 = seed.parse().unwrap();
    let opts = RewriteOptions::default();
    let bound = (opts.tolerance_um + opts.chord_tolerance_um) * 1e-3;
    let mut r = Rng(seed);
    let map = random_map(&mut r);
    let program = random_program(&mut r);
    let mut out = Vec::new();
    rewrite(program.as_bytes(), &mut out, &map, &opts).unwrap();
    let out = String::from_utf8(out).unwrap();
    check_path_dense(&program, &out, &map, &[[0.0; 3]; 6], None, 0.05, bound);
}
