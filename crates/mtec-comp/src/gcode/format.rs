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
/// The digits are made by hand (no `fmt` machinery: the rewriter writes every corrected word
/// through here), the same text as `write!("{}.{:0d$}")` with the zeros trimmed.
pub fn write_decimal(n: i64, decimals: usize, out: &mut String) {
    let d = decimals.min(9);
    let p = 10u64.pow(d as u32);
    let a = n.unsigned_abs();
    if n < 0 {
        out.push('-');
    }
    // the integer part, most significant digit first (u64 has at most 20 digits)
    let mut digits = [0u8; 20];
    let mut i = digits.len();
    let mut int = a / p;
    loop {
        i -= 1;
        digits[i] = b'0' + (int % 10) as u8;
        int /= 10;
        if int == 0 {
            break;
        }
    }
    push_ascii(out, &digits[i..]);
    if d > 0 {
        out.push('.');
        // the d fraction digits, zero-padded, then trailing zeros trimmed to one
        let mut frac = [b'0'; 9];
        let mut f = a % p;
        for k in (0..d).rev() {
            frac[k] = b'0' + (f % 10) as u8;
            f /= 10;
        }
        let mut len = d;
        while len > 1 && frac[len - 1] == b'0' {
            len -= 1;
        }
        push_ascii(out, &frac[..len]);
    }
}

/// Appends ASCII digits to a string.
fn push_ascii(out: &mut String, digits: &[u8]) {
    for &c in digits {
        out.push(c as char);
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

    /// The hand-made digits equal `fmt`'s (the former implementation), trailing zeros
    /// trimmed, on every number of decimals and integers of every length and sign.
    #[test]
    fn write_decimal_equals_fmt() {
        let reference = |n: i64, d: usize| {
            let p = 10u64.pow(d as u32);
            let a = n.unsigned_abs();
            let mut s = String::new();
            if n < 0 {
                s.push('-');
            }
            s.push_str(&format!("{}", a / p));
            if d > 0 {
                let f = format!("{:0width$}", a % p, width = d);
                s.push('.');
                s.push_str(&f[..f.trim_end_matches('0').len().max(1)]);
            }
            s
        };
        let mut x = 0x2545F4914F6CDD1Du64;
        let mut values = vec![
            0i64,
            1,
            -1,
            9,
            10,
            -10,
            99_999,
            100_000,
            i64::MAX,
            i64::MIN + 1,
        ];
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            // every length from 1 to 19 digits, both signs
            let v = (x >> (x % 63)) as i64;
            values.push(if x & 1 == 0 { v } else { -v });
        }
        for &n in &values {
            for d in 0..=9 {
                let mut s = String::new();
                write_decimal(n, d, &mut s);
                assert_eq!(s, reference(n, d), "{n} with {d} decimals");
            }
        }
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
