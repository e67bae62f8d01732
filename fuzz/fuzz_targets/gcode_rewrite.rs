//! Fuzz target for the G-code lexer and rewriter (issue 10): any bytes must give a result or a
//! located error — never a panic or a hang — and the invariants must hold:
//! a zero model leaves the bytes unchanged (pass-through mode), and with a model no line is
//! lost (output lines = input lines + added lines + header).
//!
//! Run for 10 minutes (nightly toolchain, `cargo install cargo-fuzz`):
//!   cd fuzz && cargo +nightly fuzz run gcode_rewrite corpus/gcode_rewrite seeds/gcode_rewrite -- \
//!       -max_total_time=600 -max_len=4096
#![no_main]

use libfuzzer_sys::fuzz_target;
use mtec_comp::gcode::{rewrite, OnUnsupported, RewriteOptions};
use mtec_comp::ErrorModel;

struct Zero;
impl ErrorModel for Zero {
    fn error_um(&self, _p: [f64; 3]) -> [f64; 3] {
        [0.0; 3]
    }
    fn describe(&self) -> String {
        "zero".into()
    }
}

struct Poly;
impl ErrorModel for Poly {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = p;
        [
            8.0 + 0.03 * x - 0.01 * y + 2e-4 * x * y,
            -4.0 + 0.02 * y + 1e-4 * x * x,
            3.0 + 0.01 * z,
        ]
    }
    fn describe(&self) -> String {
        "poly".into()
    }
}

fn count_lines(b: &[u8]) -> usize {
    b.split(|&c| c == b'\n').count() - usize::from(b.last() == Some(&b'\n'))
}

fuzz_target!(|data: &[u8]| {
    let pass = RewriteOptions {
        on_unsupported: OnUnsupported::PassThroughWithWarning,
        // keep pathological inputs fast: coarse pieces, few of them
        max_segment_mm: 1e6,
        tolerance_um: 5.0,
        chord_tolerance_um: 50.0,
        max_pieces_per_move: 10_000,
        ..RewriteOptions::default()
    };
    let mut out = Vec::new();
    let rep = rewrite(data, &mut out, &Zero, &pass).expect("zero model never fails in pass-through");
    assert_eq!(out, data, "zero model changed the program");
    assert!(!rep.header_written);

    let mut out = Vec::new();
    if let Ok(rep) = rewrite(data, &mut out, &Poly, &pass) {
        if !data.is_empty() {
            assert_eq!(
                count_lines(&out),
                count_lines(data) + rep.lines_added + usize::from(rep.header_written),
            );
        }
    }
    let mut out = Vec::new();
    let strict = RewriteOptions {
        max_pieces_per_move: 10_000,
        ..RewriteOptions::default()
    };
    let _ = rewrite(data, &mut out, &Poly, &strict);
});
