//! Numbers written as text, fast and exactly as Rust's `{}` writes them.
//!
//! `format!("{v}")` of an `f64` gives the shortest digits that read back to the same value, laid
//! out without an exponent (`0.0000001`, `100000000000000000000`, `-0`, `1`). Writing a million
//! rows of a CSV spends most of its time there. [`push_f64`] takes the same shortest digits from
//! `zmij` (Schubfach; faster than `ryu`, which it replaced when `ryu` was a quarter of
//! `map eval`'s time, issue 22) and lays them out the same way, so outputs stay
//! byte-identical; the tests compare the two on values of every magnitude.
//!
//! The one place the two may differ is a tie: when two shortest candidates are equally close
//! (`1658206780088562.25` → std `…562.3`, round-half-even `…562.2`), std rounds the half up. A tie needs a value whose exact decimal expansion has at most 18 significant digits;
//! such values ([`tie_possible`]: short decimals like 0.5, integers beyond 2⁵³) go through std.

/// Appends `v` to `out` exactly as `write!(out, "{v}")` would.
#[inline]
pub fn push_f64(out: &mut Vec<u8>, v: f64) {
    if !v.is_finite() {
        use std::io::Write as _;
        let _ = write!(out, "{v}");
        return;
    }
    if v == 0.0 {
        out.extend_from_slice(if v.is_sign_negative() { b"-0" } else { b"0" });
        return;
    }
    if tie_possible(v) {
        use std::io::Write as _;
        let _ = write!(out, "{v}");
        return;
    }
    let mut buf = zmij::Buffer::new();
    let s = buf.format_finite(v).as_bytes();
    // written positionally for moderate exponents, like std but for an integer's `.0`
    if !s.contains(&b'e') {
        out.extend_from_slice(s.strip_suffix(b".0").unwrap_or(s));
        return;
    }
    let s = match s.split_first() {
        Some((b'-', rest)) => {
            out.push(b'-');
            rest
        }
        _ => s,
    };
    // digits[.digits][e[+-]exponent]
    let (mantissa, exp) = match s.iter().position(|&b| b == b'e') {
        Some(i) => {
            let e = std::str::from_utf8(&s[i + 1..])
                .ok()
                .and_then(|t| t.parse::<i32>().ok())
                .unwrap_or(0);
            (&s[..i], e)
        }
        None => (s, 0),
    };
    let (int, frac) = match mantissa.iter().position(|&b| b == b'.') {
        Some(d) => (&mantissa[..d], &mantissa[d + 1..]),
        None => (mantissa, &[][..]),
    };
    // the significant digits (at most 17, with leading and trailing zeros) and where
    // the decimal point goes among them
    let mut digits = [0u8; 48];
    let mut n = 0;
    for &b in int.iter().chain(frac) {
        if n < digits.len() {
            digits[n] = b;
            n += 1;
        }
    }
    let mut point = int.len() as i32 + exp;
    let mut start = 0;
    while start + 1 < n && digits[start] == b'0' {
        start += 1;
        point -= 1;
    }
    while n > start + 1 && digits[n - 1] == b'0' {
        n -= 1;
    }
    let d = &digits[start..n];
    let len = d.len() as i32;
    if point <= 0 {
        out.extend_from_slice(b"0.");
        out.resize(out.len() + (-point) as usize, b'0');
        out.extend_from_slice(d);
    } else if point >= len {
        out.extend_from_slice(d);
        out.resize(out.len() + (point - len) as usize, b'0');
    } else {
        out.extend_from_slice(&d[..point as usize]);
        out.push(b'.');
        out.extend_from_slice(&d[point as usize..]);
    }
}

/// True when the exact value of the finite, non-zero `v` has at most 18 significant decimal
/// digits (or is an integer of 2⁵³ or more): only then can two shortest candidates be equally
/// close to it. `v` = m·2^e with m odd: for e < 0 its exact digits are those of m·5^−e.
fn tie_possible(v: f64) -> bool {
    let bits = v.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    let (mut m, mut e) = if biased == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), biased - 1075)
    };
    let tz = m.trailing_zeros();
    m >>= tz;
    e += tz as i32;
    if e >= 0 {
        // an integer below 2⁵³ is written with all its digits, no rounding involved
        return v.abs() >= 9_007_199_254_740_992.0;
    }
    let k = (-e) as u32;
    // 5^28 > 10^18: more digits than a tie can have
    k <= 27 && (m as u128) * 5u128.pow(k) < 1_000_000_000_000_000_000u128
}

#[cfg(test)]
mod tests {
    use super::*;

    fn same(v: f64) {
        let mut out = Vec::new();
        push_f64(&mut out, v);
        assert_eq!(String::from_utf8(out).unwrap(), format!("{v}"), "{v:e}");
    }

    #[test]
    fn special_values_and_layouts() {
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.3,
            1.5e-7,
            1e-7,
            1e16,
            1e21,
            1.5e300,
            -2.5e-300,
            5e-324,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            123456789.125,
            0.001,
            100.0,
            1e15,
            2f64.powi(53) + 2.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.7257601361633752,
            -0.949088929035528,
            1_658_206_780_088_562.0 + 0.25,
            0.5,
            2.5,
            1.25e-3,
        ] {
            same(v);
        }
    }

    /// Random bit patterns (every magnitude) and values of the size mtec writes.
    #[test]
    fn random_values_match_std() {
        let mut s = 0x9E3779B97F4A7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for _ in 0..200_000 {
            let bits = next();
            same(f64::from_bits(bits));
            let u = (bits >> 11) as f64 / (1u64 << 53) as f64;
            same(u);
            same((u - 0.5) * 2000.0);
            same(((u * 1000.0).round() / 1000.0) - 300.0);
            same(u * 1e-6);
            // values near 1e15 with a few fraction bits: the ties
            same(1e15 + (bits % 4096) as f64 * 0.25);
            same((bits % 100_000) as f64 / 8.0);
        }
    }
}
