//! Invariants of the rewriter on generated programs (issue 10): with a zero model the output is
//! byte-identical; with any model no line is dropped or reordered, comments survive, and every
//! (split) move ends exactly at the original target plus its correction. Bounded to run in CI
//! in seconds: 64 programs of up to 30 lines per property.

use crate::gcode_support;
use gcode_support::*;
use mtec_comp::gcode::lexer::{lex_line, TokenKind};
use mtec_comp::gcode::{correction_mm, rewrite, OnUnsupported, RewriteOptions};
use mtec_comp::ErrorModel;
use proptest::prelude::*;
use std::collections::BTreeMap;

/// PolyModel scaled by k: a family of smooth models.
struct Scaled(f64);
impl ErrorModel for Scaled {
    fn error_um(&self, p: [f64; 3]) -> [f64; 3] {
        PolyModel.error_um(p).map(|e| e * self.0)
    }
    fn describe(&self) -> String {
        format!("scaled analytic model k={}", self.0)
    }
}

#[derive(Debug, Clone)]
enum Op {
    Comment(u8, bool),
    Blank,
    Rapid([f64; 3]),
    Line([Option<f64>; 3], Option<u16>, bool),
    Arc(bool, [f64; 2], f64, bool), // cw, centre offset, end angle, helix
    Distance(bool),
}

fn coord() -> impl Strategy<Value = f64> {
    (-2000i32..2000).prop_map(|v| v as f64 / 20.0) // ±100 mm, 0.05 mm steps
}

fn small() -> impl Strategy<Value = f64> {
    (-500i32..500).prop_map(|v| v as f64 / 20.0) // ±25 mm: arc centre offsets
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        (any::<u8>(), any::<bool>()).prop_map(|(k, semi)| Op::Comment(k, semi)),
        Just(Op::Blank),
        [coord(), coord(), coord()].prop_map(Op::Rapid),
        (
            [
                proptest::option::of(coord()),
                proptest::option::of(coord()),
                proptest::option::of(coord())
            ],
            proptest::option::of(1u16..2000),
            any::<bool>()
        )
            .prop_map(|(p, f, c)| Op::Line(p, f, c)),
        (
            any::<bool>(),
            [small(), small()],
            0.0f64..std::f64::consts::TAU,
            any::<bool>()
        )
            .prop_map(|(cw, c, a, h)| Op::Arc(cw, c, a, h)),
        any::<bool>().prop_map(Op::Distance),
    ]
}

fn fmt(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Renders ops as a program; every block that moves carries a unique N number.
fn render(ops: &[Op], crlf: bool, lower: bool, compact: bool, final_newline: bool) -> String {
    let nl = if crlf { "\r\n" } else { "\n" };
    let sp = if compact { "" } else { " " };
    let mut pos = [0.0f64; 3];
    let mut absolute = true;
    let mut lines = vec![
        format!("N1{sp}G21{sp}G90{sp}G17{sp}F500"),
        format!("N2{sp}G0{sp}X0{sp}Y0{sp}Z0"),
    ];
    for (i, op) in ops.iter().enumerate() {
        let n = format!("N{}{sp}", 10 * (i + 1));
        let l = match op {
            Op::Comment(k, semi) => {
                if *semi {
                    format!("; note {k} (x)")
                } else {
                    format!("(note {k}; [y])")
                }
            }
            Op::Blank => String::new(),
            Op::Distance(abs) => {
                absolute = *abs;
                format!("{n}{}", if *abs { "G90" } else { "G91" })
            }
            Op::Rapid(p) => {
                let w: Vec<String> = (0..3)
                    .map(|a| {
                        let v = if absolute { p[a] } else { p[a] - pos[a] };
                        format!("{}{}", ["X", "Y", "Z"][a], fmt(v))
                    })
                    .collect();
                pos = *p;
                format!("{n}G0{sp}{}", w.join(sp))
            }
            Op::Line(p, f, comment) => {
                let mut w = vec!["G1".to_string()];
                for a in 0..3 {
                    if let Some(v) = p[a] {
                        let val = if absolute { v } else { v - pos[a] };
                        w.push(format!("{}{}", ["X", "Y", "Z"][a], fmt(val)));
                        pos[a] = if absolute {
                            v
                        } else {
                            pos[a] + fmt(val).parse::<f64>().unwrap()
                        };
                    }
                }
                if w.len() == 1 {
                    w.push(format!("X{}", fmt(if absolute { pos[0] } else { 0.0 })));
                }
                if let Some(f) = f {
                    w.push(format!("F{f}"));
                }
                if *comment {
                    w.push("(cut)".into());
                }
                format!("{n}{}", w.join(sp))
            }
            Op::Arc(cw, c, ang, helix) => {
                // centre = start + (I, J); end on the same circle at angle `ang`
                let r = (c[0] * c[0] + c[1] * c[1]).sqrt();
                if r < 0.5 {
                    continue;
                }
                let cx = pos[0] + c[0];
                let cy = pos[1] + c[1];
                let ex = ((cx + r * ang.cos()) * 1000.0).round() / 1000.0;
                let ey = ((cy + r * ang.sin()) * 1000.0).round() / 1000.0;
                let ez = if *helix { pos[2] - 1.0 } else { pos[2] };
                let (wx, wy, wz) = if absolute {
                    (ex, ey, ez)
                } else {
                    (ex - pos[0], ey - pos[1], ez - pos[2])
                };
                let s = format!(
                    "{n}{}{sp}X{}{sp}Y{}{sp}Z{}{sp}I{}{sp}J{}",
                    if *cw { "G2" } else { "G3" },
                    fmt(wx),
                    fmt(wy),
                    fmt(wz),
                    fmt(c[0]),
                    fmt(c[1])
                );
                // keep the rendered (rounded) end as the new position
                pos = [
                    if absolute {
                        fmt(wx).parse().unwrap()
                    } else {
                        pos[0] + fmt(wx).parse::<f64>().unwrap()
                    },
                    if absolute {
                        fmt(wy).parse().unwrap()
                    } else {
                        pos[1] + fmt(wy).parse::<f64>().unwrap()
                    },
                    ez,
                ];
                s
            }
        };
        lines.push(if lower { l.to_ascii_lowercase() } else { l });
    }
    let mut text = lines.join(nl);
    if final_newline {
        text.push_str(nl);
    }
    text
}

/// Comments, N words and F words of a line: what must survive, in order.
fn skeleton(line: &str) -> Vec<String> {
    let mut toks = Vec::new();
    if lex_line(line.as_bytes(), 0, &mut toks).is_err() {
        return vec![line.to_string()];
    }
    toks.iter()
        .filter(|t| match t.kind {
            TokenKind::Comment => true,
            TokenKind::Word { letter, .. } => letter == b'N' || letter == b'F',
            _ => false,
        })
        .map(|t| line[t.span.clone()].to_string())
        .collect()
}

fn n_of(line: &str) -> Option<String> {
    skeleton(line)
        .into_iter()
        .find(|s| s.starts_with(['N', 'n']))
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 64,
        max_shrink_iters: 200,
        ..ProptestConfig::default()
    }
}

fn count_lines(b: &[u8]) -> usize {
    b.split(|&c| c == b'\n').count() - usize::from(b.last() == Some(&b'\n'))
}

/// Bytes that look like G-code often enough to reach deep into the rewriter: words, numbers,
/// parameters, brackets, comments, line endings and some arbitrary bytes.
fn gcode_soup() -> impl Strategy<Value = Vec<u8>> {
    let piece = prop_oneof![
        4 => proptest::sample::select(vec![
            "G0", "G1", "G2", "G3", "G17", "G18", "G19", "G20", "G21", "G90", "G91", "G90.1",
            "G43", "H1", "G49", "G53", "G54", "G55", "G28", "G80", "G81", "G41", "G40", "G93",
            "G94", "M2", "M6", "T1", "X", "Y", "Z", "I", "J", "K", "R", "P", "F", "N10", "O100",
            "sub", "#1", "#<a>", "=", "[", "]", "(", ")", ";", "/", "%", " ", "\n", "\r\n",
            "-", ".", "+", "A", "@", "^",
        ]).prop_map(|s| s.as_bytes().to_vec()),
        3 => (-100000i32..100000).prop_map(|v| format!("{}", v as f64 / 1000.0).into_bytes()),
        1 => proptest::collection::vec(any::<u8>(), 1..3),
    ];
    proptest::collection::vec(piece, 0..60).prop_map(|v| v.concat())
}

proptest! {
    #![proptest_config(config())]

    /// The fuzz target's checks, bounded for CI: any bytes give a result or a located error,
    /// never a panic; a zero model copies them exactly; a model never loses a line.
    #[test]
    fn arbitrary_bytes_never_panic_and_keep_their_lines(data in gcode_soup()) {
        let pass = RewriteOptions {
            on_unsupported: OnUnsupported::PassThroughWithWarning,
            max_pieces_per_move: 10_000,
            ..RewriteOptions::default()
        };
        let mut out = Vec::new();
        let rep = rewrite(&data[..], &mut out, &ZeroModel, &pass).unwrap();
        prop_assert_eq!(&out, &data);
        prop_assert!(!rep.header_written);
        let mut out = Vec::new();
        if let Ok(rep) = rewrite(&data[..], &mut out, &PolyModel, &pass) {
            if !data.is_empty() {
                prop_assert_eq!(count_lines(&out), count_lines(&data) + rep.lines_added + usize::from(rep.header_written));
            }
        }
        let mut out = Vec::new();
        if let Err(mtec_comp::gcode::GcodeError::At(d)) = rewrite(&data[..], &mut out, &PolyModel, &RewriteOptions::default()) {
            prop_assert!(d.line >= 1 && d.line <= count_lines(&data).max(1) && d.column >= 1);
        }
    }

    #[test]
    fn zero_model_output_is_byte_identical(
        ops in proptest::collection::vec(op(), 0..30),
        crlf in any::<bool>(), lower in any::<bool>(), compact in any::<bool>(), nl in any::<bool>(),
    ) {
        let input = render(&ops, crlf, lower, compact, nl);
        let mut out = Vec::new();
        let opts = RewriteOptions { on_unsupported: OnUnsupported::PassThroughWithWarning, ..RewriteOptions::default() };
        rewrite(input.as_bytes(), &mut out, &ZeroModel, &opts).unwrap();
        prop_assert_eq!(String::from_utf8(out).unwrap(), input);
    }

    #[test]
    fn any_model_keeps_lines_and_comments_and_ends_moves_at_target_plus_correction(
        ops in proptest::collection::vec(op(), 1..30),
        crlf in any::<bool>(), lower in any::<bool>(), compact in any::<bool>(), nl in any::<bool>(),
        k in 0.1f64..2.0,
    ) {
        let model = Scaled(k);
        let input = render(&ops, crlf, lower, compact, nl);
        // a coarser chord tolerance keeps arcs to tens of chords: the test stays within seconds
        let opts = RewriteOptions { chord_tolerance_um: 5.0, ..RewriteOptions::default() };
        let mut out = Vec::new();
        let rep = rewrite(input.as_bytes(), &mut out, &model, &opts).unwrap();
        let output = String::from_utf8(out).unwrap();
        let in_lines: Vec<&str> = input.lines().collect();
        let out_lines: Vec<&str> = output.lines().collect();
        // line count changes only by the header and the split pieces
        prop_assert_eq!(out_lines.len(), in_lines.len() + rep.lines_added + rep.header_written as usize);
        // no line dropped or reordered, comments survive
        let sk_in: Vec<Vec<String>> = in_lines.iter().map(|l| skeleton(l)).filter(|s| !s.is_empty()).collect();
        let sk_out: Vec<Vec<String>> = out_lines.iter()
            .filter(|l| !l.starts_with("(mtec compensate gcode"))
            .map(|l| skeleton(l)).filter(|s| !s.is_empty()).collect();
        prop_assert_eq!(&sk_in, &sk_out);
        // the end of each original move: the last output move of its block group
        let work = [[0.0; 3]; 6];
        let tools = BTreeMap::new();
        let want = interpret(&input, &work, &tools, None);
        let got = interpret(&output, &work, &tools, None);
        let mut group_end: BTreeMap<String, [f64; 3]> = BTreeMap::new();
        for g in &got {
            let n = (0..g.line).rev().find_map(|i| n_of(out_lines[i])).unwrap();
            group_end.insert(n.to_ascii_uppercase(), g.end);
        }
        for w in &want {
            let n = n_of(in_lines[w.line - 1]).unwrap().to_ascii_uppercase();
            let end = group_end[&n];
            let c = correction_mm(&model, w.end, 500.0).unwrap();
            for a in 0..3 {
                // exactly target + correction, to the 4 decimals written (mm)
                prop_assert!((end[a] - (w.end[a] + c[a])).abs() <= 0.5e-4 + 1e-9,
                    "block {}: axis {} ends at {} not {} + {}", n, a, end[a], w.end[a], c[a]);
            }
            prop_assert!(dist(machine(&model, end), w.end) < opts.tolerance_um * 1e-3);
        }
    }
}
