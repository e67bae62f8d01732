//! Writing numbers and applying edits to a line's bytes.

use std::ops::Range;

/// Formats `v` with at most `decimals` digits after the point (correctly rounded), trailing
/// zeros trimmed to one, and no negative zero: `1.23400` → `1.234`, `-0.00001` → `0.0`.
pub fn format_number(v: f64, decimals: usize, out: &mut String) {
    use std::fmt::Write;
    let start = out.len();
    let _ = write!(out, "{:.*}", decimals, v);
    if decimals > 0 {
        let trimmed = out[start..].trim_end_matches('0').len();
        out.truncate(start + trimmed);
        if out.ends_with('.') {
            out.push('0');
        }
    }
    if out[start..].starts_with('-') && out[start + 1..].bytes().all(|c| c == b'0' || c == b'.') {
        out.remove(start);
    }
}

/// A replacement of `span` (possibly empty: an insertion) by `text`.
#[derive(Debug, Clone, PartialEq)]
pub struct Edit {
    pub span: Range<usize>,
    pub text: String,
    /// Order among insertions at the same position.
    pub order: u8,
}

/// Writes `line` with `edits` applied (edits must not overlap; they are sorted here).
pub fn apply_edits(line: &[u8], edits: &mut [Edit], out: &mut Vec<u8>) {
    edits.sort_by(|a, b| {
        (a.span.start, a.span.end, a.order).cmp(&(b.span.start, b.span.end, b.order))
    });
    let mut pos = 0;
    for e in edits.iter() {
        if e.span.start < pos {
            continue; // overlapping edit: never produced by the rewriter
        }
        out.extend_from_slice(&line[pos..e.span.start]);
        out.extend_from_slice(e.text.as_bytes());
        pos = e.span.end;
    }
    out.extend_from_slice(&line[pos..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_rounded_and_trimmed() {
        let f = |v: f64, d| {
            let mut s = String::new();
            format_number(v, d, &mut s);
            s
        };
        assert_eq!(f(1.234_000_4, 4), "1.234");
        assert_eq!(f(2.0, 4), "2.0");
        assert_eq!(f(-0.000_01, 4), "0.0");
        assert_eq!(f(-1.000_06, 4), "-1.0001");
        assert_eq!(f(12.345_65, 0), "12");
    }

    #[test]
    fn edits_replace_and_insert() {
        let mut e = vec![
            Edit {
                span: 4..6,
                text: "9.5".into(),
                order: 0,
            },
            Edit {
                span: 6..6,
                text: " Z1".into(),
                order: 2,
            },
            Edit {
                span: 6..6,
                text: " Y2".into(),
                order: 1,
            },
        ];
        let mut out = Vec::new();
        apply_edits(b"G1 X10 (c)", &mut e, &mut out);
        assert_eq!(out, b"G1 X9.5 Y2 Z1 (c)");
    }
}
