//! Fuzz target for the G-code lexer and rewriter (issue 10): any bytes must give a result or a
//! located error — never a panic or a hang — and the invariants must hold:
//! a zero model leaves the bytes unchanged (pass-through mode), and with a model no line is
//! lost (output lines = input lines + added lines + header). When the bytes are a program in
//! the subset the tests' reference interpreter reads (G0–G3, G17–G19, G21, G90/G91, X Y Z I J K
//! R P F N words and comments, every axis set by the first move), the compensated path must
//! also stay within the documented bound of the original one (issue 15).
//!
//! Run for 10 minutes (nightly toolchain, `cargo install cargo-fuzz`):
//!   cd fuzz && cargo +nightly fuzz run gcode_rewrite corpus/gcode_rewrite seeds/gcode_rewrite -- \
//!       -max_total_time=600 -max_len=4096
#![no_main]

#[path = "../../crates/mtec-comp/tests/gcode_support/mod.rs"]
mod gcode_support;

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
    if rewrite(data, &mut out, &Poly, &strict).is_ok() {
        if let (Ok(text), Ok(written)) = (std::str::from_utf8(data), String::from_utf8(out)) {
            if in_reference_subset(text) {
                let bound = (strict.tolerance_um + strict.chord_tolerance_um) * 1e-3;
                gcode_support::check_path_dense(text, &written, &Poly, &[[0.0; 3]; 6], None, 0.05, bound);
            }
        }
    }
});

/// The programs the reference interpreter of the tests reads exactly: plain words of the
/// letters it knows, G codes it models, the first line with a motion setting X, Y and Z.
fn in_reference_subset(text: &str) -> bool {
    let mut first_move = true;
    for line in text.lines() {
        let code = line.split(['(', ';']).next().unwrap_or("");
        if code.contains(['#', '[', 'O', 'o', '/', '%', '@', '^']) || line.matches('(').count() > 1 {
            return false;
        }
        let upper = code.to_ascii_uppercase();
        let words: Vec<&str> = upper.split_whitespace().collect();
        for w in &words {
            let (l, v) = w.split_at(1);
            if !"GXYZIJKRPFN".contains(l) || v.parse::<f64>().is_err() {
                return false;
            }
            if l == "G" && !["0", "1", "2", "3", "17", "18", "19", "21", "90", "91"].contains(&v) {
                return false;
            }
        }
        let moves = words.iter().any(|w| "XYZIJK".contains(&w[..1]));
        if moves && first_move {
            if !["X", "Y", "Z"].iter().all(|a| words.iter().any(|w| w.starts_with(a)))
                || !words.iter().any(|w| *w == "G0" || *w == "G1")
            {
                return false;
            }
            first_move = false;
        }
    }
    true
}
