//! Writing numbers and applying edits to a line's bytes.

use std::ops::Range;

const POW10: [f64; 10] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];

/// `v` rounded to `decimals` digits, as an integer count of 10^-decimals (None when too large
/// to count exactly). The value it stands for is [`decimal_value`].
pub fn to_decimal(v: f64, decimals: usize) -> Option<i64> {
    let x = (v * POW10[decimals.min(9)]).round();
    if x.is_finite() && x.abs() < 4e15 {
        Some(x as i64)
    } else {
        None
    }
}

/// The f64 nearest to n·10^-decimals: the division of two exact integers is correctly
/// rounded, so this equals parsing the written decimal.
pub fn decimal_value(n: i64, decimals: usize) -> f64 {
    n as f64 / POW10[decimals.min(9)]
}

/// Writes n·10^-decimals in plain decimal, trailing zeros trimmed to one: 12340, 4 → `1.234`.
pub fn write_decimal(n: i64, decimals: usize, out: &mut String) {
    use std::fmt::Write;
    let d = decimals.min(9);
    let p = 10u64.pow(d as u32);
    let a = n.unsigned_abs();
    if n < 0 {
        out.push('-');
    }
    let _ = write!(out, "{}", a / p);
    if d > 0 {
        out.push('.');
        let start = out.len();
        let _ = write!(out, "{:0width$}", a % p, width = d);
        let trimmed = out[start..].trim_end_matches('0').len().max(1);
        out.truncate(start + trimmed);
    }
}

/// Formats `v` with at most `decimals` digits after the point, trailing zeros trimmed to one,
/// and no negative zero: `1.23400` → `1.234`, `-0.00001` → `0.0`.
pub fn format_number(v: f64, decimals: usize, out: &mut String) {
    match to_decimal(v, decimals) {
        Some(n) => write_decimal(n, decimals, out),
        None => {
            use std::fmt::Write;
            let _ = write!(out, "{:.*}", decimals.min(9), v);
        }
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
            // overlapping deletions (two removed words sharing the blank between them) are
            // merged; an overlapping replacement is never produced by the rewriter
            debug_assert!(e.text.is_empty(), "overlapping edit {e:?}");
            if e.text.is_empty() {
                pos = pos.max(e.span.end);
            }
            continue;
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
