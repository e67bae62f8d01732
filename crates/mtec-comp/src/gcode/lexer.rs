//! The line lexer: splits one NC block into tokens with byte spans, keeping the original text.
//!
//! Dialect: RS274/NGC as LinuxCNC reads it, and common Fanuc style. A token never owns text; it
//! records where in the line it is, so the rewriter can edit one word and copy every other byte.
//! Numbers are parsed as `f64` from their original digits (the public crates store `f32`).
//!
//! What is recognised: block delete `/`, `%` tape marks, comments `( … )` and `; …`, words
//! (a letter, optional blanks, then a number `[+-]digits[.digits]`, a parameter `#1`,
//! `#<name>`, `##1`, `#[expr]`, an expression `[ … ]` or a function `sin[ … ]`), parameter
//! assignments `#1 = …` and O-words (`O100 sub`, `o<name> call …`, or a Fanuc program number).
//! Blanks inside a number (`X1 0.5`, legal in RS274/NGC) are not accepted: the lexer reports
//! them as an error, which the rewriter treats like any unsupported construct.

use std::ops::Range;

/// The value of a word: a literal number (parsed), or something only an interpreter can evaluate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A literal number, parsed as f64 from the original digits.
    Number(f64),
    /// A parameter reference (`#1`, `#<x>`), an expression `[…]` or a function `sin[…]`.
    Computed,
}

/// What a token is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TokenKind {
    /// `/` at the start of the block: the block is skipped when the operator's switch is on.
    BlockDelete,
    /// A `%` tape mark.
    Percent,
    /// A comment, `( … )` or `; …` to the end of the line.
    Comment,
    /// A word: `letter` (upper case) and its value; `value_span` is where the value's text is.
    Word { letter: u8, value: Value },
    /// A parameter assignment `#n = value`; `param` is the parameter number when it is a
    /// literal numbered parameter, `None` for named or indirect parameters.
    Assignment { param: Option<u32>, named: bool },
    /// An O-word. `keyword` is true for control flow (`sub`, `call`, `if`, `while`, …), false
    /// for a bare program number (Fanuc `O1234`).
    OWord { keyword: bool },
}

/// One token of a line: its kind, its whole span and the span of its value text.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    pub kind: TokenKind,
    pub span: Range<usize>,
    pub value_span: Range<usize>,
}

/// A line the lexer cannot read; `column` is 1-based (in bytes).
#[derive(Debug, Clone, PartialEq)]
pub struct LexError {
    pub column: usize,
    pub message: String,
}

fn err(pos: usize, message: impl Into<String>) -> LexError {
    LexError {
        column: pos + 1,
        message: message.into(),
    }
}

fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | 0x0b | 0x0c)
}

/// Tokenises one line (without its line ending) into `out` (cleared first).
/// `start` is where lexing begins (after a byte-order mark on the first line).
pub fn lex_line(line: &[u8], start: usize, out: &mut Vec<Token>) -> Result<(), LexError> {
    out.clear();
    let mut i = start;
    let n = line.len();
    let mut first = true;
    while i < n {
        let b = line[i];
        if is_blank(b) {
            i += 1;
            continue;
        }
        let tok_start = i;
        match b {
            b'/' if first => {
                out.push(Token {
                    kind: TokenKind::BlockDelete,
                    span: i..i + 1,
                    value_span: i + 1..i + 1,
                });
                i += 1;
            }
            b'%' => {
                out.push(Token {
                    kind: TokenKind::Percent,
                    span: i..i + 1,
                    value_span: i + 1..i + 1,
                });
                i += 1;
            }
            b'(' => {
                let close = line[i + 1..]
                    .iter()
                    .position(|&c| c == b'(' || c == b')')
                    .map(|p| p + i + 1);
                match close {
                    Some(c) if line[c] == b')' => {
                        out.push(Token {
                            kind: TokenKind::Comment,
                            span: i..c + 1,
                            value_span: i + 1..c,
                        });
                        i = c + 1;
                    }
                    Some(c) => return Err(err(c, "nested comment: '(' inside a comment")),
                    None => return Err(err(i, "comment not closed: '(' without ')'")),
                }
            }
            b';' => {
                out.push(Token {
                    kind: TokenKind::Comment,
                    span: i..n,
                    value_span: i + 1..n,
                });
                i = n;
            }
            b'#' => {
                let (param, named, after) = lex_parameter(line, i)?;
                let mut j = skip_blanks(line, after);
                if j >= n || line[j] != b'=' {
                    return Err(err(
                        tok_start,
                        "parameter outside a word: expected '=' after it (an assignment)",
                    ));
                }
                j = skip_blanks(line, j + 1);
                let (_, end) = lex_value(line, j)?;
                out.push(Token {
                    kind: TokenKind::Assignment { param, named },
                    span: tok_start..end,
                    value_span: j..end,
                });
                i = end;
            }
            b'o' | b'O' => {
                let j = skip_blanks(line, i + 1);
                let after = if j < n && line[j] == b'<' {
                    match line[j..].iter().position(|&c| c == b'>') {
                        Some(p) => j + p + 1,
                        None => return Err(err(j, "O-word name not closed: '<' without '>'")),
                    }
                } else if j < n && line[j] == b'#' {
                    lex_parameter(line, j)?.2
                } else {
                    let d = digits_end(line, j);
                    if d == j {
                        return Err(err(i, "O-word without a number or <name>"));
                    }
                    d
                };
                let k = skip_blanks(line, after);
                let keyword = k < n && line[k].is_ascii_alphabetic();
                let end = if keyword { n } else { after };
                out.push(Token {
                    kind: TokenKind::OWord { keyword },
                    span: tok_start..end,
                    value_span: j..end,
                });
                i = end;
            }
            c if c.is_ascii_alphabetic() || c == b'@' || c == b'^' => {
                let letter = c.to_ascii_uppercase();
                let j = skip_blanks(line, i + 1);
                let (value, end) = lex_value(line, j)?;
                out.push(Token {
                    kind: TokenKind::Word { letter, value },
                    span: tok_start..end,
                    value_span: j..end,
                });
                i = end;
            }
            c if c.is_ascii_digit() || c == b'.' || c == b'+' || c == b'-' => {
                return Err(err(
                    i,
                    "number without a letter (blanks inside a number are not supported)",
                ));
            }
            c if c.is_ascii() => {
                return Err(err(i, format!("unexpected character '{}'", c as char)));
            }
            c => {
                return Err(err(
                    i,
                    format!("non-ASCII byte 0x{c:02x} outside a comment"),
                ))
            }
        }
        first = false;
    }
    Ok(())
}

fn skip_blanks(line: &[u8], mut i: usize) -> usize {
    while i < line.len() && is_blank(line[i]) {
        i += 1;
    }
    i
}

fn digits_end(line: &[u8], mut i: usize) -> usize {
    while i < line.len() && line[i].is_ascii_digit() {
        i += 1;
    }
    i
}

/// A parameter reference starting at `line[i] == '#'`: returns (number, named, end).
fn lex_parameter(line: &[u8], i: usize) -> Result<(Option<u32>, bool, usize), LexError> {
    let n = line.len();
    let j = skip_blanks(line, i + 1);
    if j >= n {
        return Err(err(i, "'#' without a parameter number or <name>"));
    }
    match line[j] {
        b'<' => match line[j..].iter().position(|&c| c == b'>') {
            Some(p) => Ok((None, true, j + p + 1)),
            None => Err(err(j, "parameter name not closed: '<' without '>'")),
        },
        b'#' => {
            let (_, _, end) = lex_parameter(line, j)?;
            Ok((None, false, end))
        }
        b'[' => Ok((None, false, bracket_end(line, j)?)),
        c if c.is_ascii_digit() => {
            let d = digits_end(line, j);
            let num = std::str::from_utf8(&line[j..d])
                .ok()
                .and_then(|s| s.parse::<u32>().ok());
            Ok((num, false, d))
        }
        _ => Err(err(j, "'#' without a parameter number or <name>")),
    }
}

/// End (exclusive) of a bracketed expression starting at `line[i] == '['`.
fn bracket_end(line: &[u8], i: usize) -> Result<usize, LexError> {
    let mut depth = 0usize;
    for (k, &c) in line.iter().enumerate().skip(i) {
        match c {
            b'[' => depth += 1,
            b']' => {
                depth -= 1;
                if depth == 0 {
                    return Ok(k + 1);
                }
            }
            b'(' | b';' => return Err(err(k, "comment inside an expression")),
            _ => {}
        }
    }
    Err(err(i, "expression not closed: '[' without ']'"))
}

/// The value of a word or assignment starting at `i` (blanks already skipped).
fn lex_value(line: &[u8], i: usize) -> Result<(Value, usize), LexError> {
    let n = line.len();
    if i >= n {
        return Err(err(i.saturating_sub(1), "word without a value"));
    }
    match line[i] {
        b'#' => Ok((Value::Computed, lex_parameter(line, i)?.2)),
        b'[' => Ok((Value::Computed, bracket_end(line, i)?)),
        c if c.is_ascii_alphabetic() => {
            // a unary function such as sin[...], or atan[...]/[...]
            let mut j = i;
            while j < n && line[j].is_ascii_alphabetic() {
                j += 1;
            }
            let k = skip_blanks(line, j);
            if k >= n || line[k] != b'[' {
                return Err(err(i.saturating_sub(1), "word without a value"));
            }
            let mut end = bracket_end(line, k)?;
            let s = skip_blanks(line, end);
            if line[i..j].eq_ignore_ascii_case(b"atan") && s < n && line[s] == b'/' {
                let t = skip_blanks(line, s + 1);
                if t < n && line[t] == b'[' {
                    end = bracket_end(line, t)?;
                }
            }
            Ok((Value::Computed, end))
        }
        // a signed parameter, expression or function: `X-#1`, `Z-[#2*2]`, `X-sin[30]`
        b'-' | b'+'
            if i + 1 < n
                && (matches!(line[i + 1], b'#' | b'[') || line[i + 1].is_ascii_alphabetic()) =>
        {
            let (_, end) = lex_value(line, i + 1)?;
            Ok((Value::Computed, end))
        }
        _ => {
            let negative = line[i] == b'-';
            let mut j = i;
            if line[j] == b'+' || line[j] == b'-' {
                j += 1;
            }
            // one pass over `digits[.digits]`, the digits gathered as the integer m (as
            // `parse_short_decimal` does, while they fit its fast path)
            let mut m = 0u64;
            let mut end = j;
            while end < n && line[end].is_ascii_digit() {
                m = m.wrapping_mul(10).wrapping_add(u64::from(line[end] - b'0'));
                end += 1;
            }
            let int_digits = end - j;
            let mut after_point = 0;
            if end < n && line[end] == b'.' {
                end += 1;
                while end < n && line[end].is_ascii_digit() {
                    m = m.wrapping_mul(10).wrapping_add(u64::from(line[end] - b'0'));
                    end += 1;
                    after_point += 1;
                }
            }
            let digits = int_digits + after_point;
            if digits == 0 {
                return Err(err(i.saturating_sub(1), "word without a number"));
            }
            exponent_check(line, i, end)?;
            let value = if digits <= SHORT_DIGITS {
                // m < 10^15 < 2^53 (no wrap): `parse_short_decimal`'s quotient
                let v = m as f64 / POW10[after_point];
                if negative {
                    -v
                } else {
                    v
                }
            } else {
                parse_number(&line[i..end]).ok_or_else(|| err(i, "number cannot be read"))?
            };
            Ok((Value::Number(value), end))
        }
    }
}

/// Refuses a number written with an exponent (`X1e-05`, as printf's `%g` or Python write small
/// values): G-code has no exponent, so a controller reads `X1` and then an `E-05` word, and the
/// axis goes to 1 mm instead of 0.00001 mm. `end` is where the digits of the number at `i` end.
fn exponent_check(line: &[u8], i: usize, end: usize) -> Result<(), LexError> {
    let n = line.len();
    if end >= n || !matches!(line[end], b'e' | b'E') {
        return Ok(());
    }
    let mut k = end + 1;
    if k < n && matches!(line[k], b'+' | b'-') {
        k += 1;
    }
    if k >= n || !line[k].is_ascii_digit() {
        return Ok(());
    }
    let text = String::from_utf8_lossy(&line[i..digits_end(line, k)]);
    Err(err(
        end,
        format!(
            "`{text}` is exponent notation, which G-code does not have: a controller reads the \
             number up to the E and then an E word; write the number in plain decimals (or put a \
             blank before the E if E is a word on your control)"
        ),
    ))
}

/// Parses `[+-]digits[.digits]` (either side of the point may be empty) as f64.
pub fn parse_number(text: &[u8]) -> Option<f64> {
    if let Some(v) = parse_short_decimal(text) {
        return Some(v);
    }
    let s = std::str::from_utf8(text).ok()?;
    let s = s.strip_prefix('+').unwrap_or(s);
    // Rust's parser accepts "5." and ".5" and "-.5"; a lone "." or "-" is refused.
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Most digits of a number read as m / 10^k ([`parse_short_decimal`]): m < 10^15 < 2^53.
const SHORT_DIGITS: usize = 15;

/// 10^k, k = 0..=15: each exact in f64 (10^22 is the largest power of ten that is).
const POW10: [f64; 16] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
];

/// The G-code numbers nearly every line has (`X12.3456`, `N120`, `F1500`): `[+-]digits[.digits]`
/// with at most 15 digits in all, read as m / 10^k with the digits as the integer m < 10^15 and
/// k digits after the point. Both are exact in f64 (m < 2^53, k ≤ 22) and IEEE division rounds
/// correctly, so the quotient is the correctly rounded value of the decimal, the same f64 the
/// standard parser gives (Clinger, "How to read floating point numbers accurately", PLDI 1990,
/// the fast path; Rust's own parser takes it too). `None` for anything else (more digits, no
/// digit, another character): the caller then uses the standard parser.
fn parse_short_decimal(text: &[u8]) -> Option<f64> {
    let (negative, body) = match text.first()? {
        b'-' => (true, &text[1..]),
        b'+' => (false, &text[1..]),
        _ => (false, text),
    };
    if body.len() > 16 {
        return None;
    }
    let mut m = 0u64;
    let (mut digits, mut after_point) = (0usize, 0usize);
    let mut point = false;
    for &c in body {
        match c {
            b'0'..=b'9' => {
                m = m * 10 + u64::from(c - b'0');
                digits += 1;
                after_point += usize::from(point);
            }
            b'.' if !point => point = true,
            _ => return None,
        }
    }
    if digits == 0 || digits > SHORT_DIGITS {
        return None;
    }
    let v = m as f64 / POW10[after_point];
    Some(if negative { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random `[+-]digits[.digits]` of 1 to `max_digits` digits, the point anywhere or
    /// nowhere, from the xorshift state `seed`.
    fn random_decimal(seed: &mut u64, max_digits: u64) -> String {
        let mut next = |n: u64| {
            *seed ^= *seed << 13;
            *seed ^= *seed >> 7;
            *seed ^= *seed << 17;
            *seed % n
        };
        let digits = 1 + next(max_digits) as usize;
        let mut s: String = (0..digits)
            .map(|_| char::from(b'0' + next(10) as u8))
            .collect();
        let point = next(digits as u64 + 2) as usize;
        if point <= digits {
            s.insert(point, '.');
        }
        match next(3) {
            0 => s.insert(0, '-'),
            1 => s.insert(0, '+'),
            _ => {}
        }
        s
    }

    /// A word's number, read in the lexer's one pass, is the standard parser's f64 bit for
    /// bit: 1 to 20 digits (past the fast path's 15 too), points anywhere, signs, zeros.
    #[test]
    fn a_words_number_is_the_standard_parsers() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut toks = Vec::new();
        let mut checked = 0;
        for _ in 0..100_000 {
            let s = random_decimal(&mut seed, 20);
            let line = format!("G1 X{s} F100");
            lex_line(line.as_bytes(), 0, &mut toks).unwrap();
            let TokenKind::Word {
                letter: b'X',
                value: Value::Number(v),
            } = toks[1].kind
            else {
                panic!("{line}: {toks:?}");
            };
            let std = s.trim_start_matches('+').parse::<f64>().unwrap();
            assert_eq!(v.to_bits(), std.to_bits(), "{s}: {v} vs {std}");
            assert_eq!(toks[1].value_span, 4..4 + s.len());
            checked += 1;
        }
        assert_eq!(checked, 100_000);
    }

    /// The short-decimal path gives the standard parser's f64, bit for bit (signs, zeros,
    /// points at either end, 1 to 15 digits), and leaves the rest to it.
    #[test]
    fn short_decimals_read_as_the_standard_parser_reads_them() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut checked = 0;
        for _ in 0..200_000 {
            let s = random_decimal(&mut seed, 15);
            let std = s.trim_start_matches('+').parse::<f64>().unwrap();
            let fast = parse_short_decimal(s.as_bytes()).expect(&s);
            assert_eq!(fast.to_bits(), std.to_bits(), "{s}: {fast} vs {std}");
            assert_eq!(
                parse_number(s.as_bytes()).map(f64::to_bits),
                Some(std.to_bits())
            );
            checked += 1;
        }
        assert_eq!(checked, 200_000);
        for s in [
            "-0",
            "-0.",
            "-.0",
            "0",
            "+0.000",
            "999999999999999",
            ".000000000000001",
        ] {
            let std = s.trim_start_matches('+').parse::<f64>().unwrap();
            assert_eq!(
                parse_short_decimal(s.as_bytes()).map(f64::to_bits),
                Some(std.to_bits()),
                "{s}"
            );
        }
        // left to the standard parser (or refused by it)
        for s in [
            "",
            ".",
            "-",
            "+.",
            "1.2.3",
            "1e5",
            "1234567890123456",
            "0.1234567890123456",
        ] {
            assert_eq!(parse_short_decimal(s.as_bytes()), None, "{s}");
        }
        assert_eq!(parse_number(b"1234567890123456"), Some(1234567890123456.0));
        assert_eq!(parse_number(b"."), None);
        assert_eq!(parse_number(b"-"), None);
    }

    fn kinds(line: &str) -> Vec<TokenKind> {
        let mut v = Vec::new();
        lex_line(line.as_bytes(), 0, &mut v).unwrap();
        v.into_iter().map(|t| t.kind).collect()
    }

    #[test]
    fn exponent_notation_is_refused_where_the_e_is() {
        let mut v = Vec::new();
        for (line, col) in [("G1 X1e-05 Y2", 6), ("G1 X1.5E3", 8), ("g1 x-2e+1", 7)] {
            let e = lex_line(line.as_bytes(), 0, &mut v).unwrap_err();
            assert_eq!(e.column, col, "{line}: {e:?}");
            assert!(e.message.contains("exponent"), "{}", e.message);
        }
        // an E word after a blank, or an E not followed by a number, is not an exponent
        assert_eq!(kinds("G1 X1 E5").len(), 3);
        assert!(lex_line(b"G1 X1E", 0, &mut v).is_err()); // E without a value, as before
    }

    #[test]
    fn words_keep_f64_precision_and_spans() {
        let line = "N40G90 g1x1234.5678 Y-.5 (c) ; rest";
        let mut v = Vec::new();
        lex_line(line.as_bytes(), 0, &mut v).unwrap();
        assert_eq!(v.len(), 7);
        assert_eq!(
            v[3].kind,
            TokenKind::Word {
                letter: b'X',
                value: Value::Number(1234.5678)
            }
        );
        assert_eq!(&line[v[3].value_span.clone()], "1234.5678");
        assert_eq!(&line[v[4].value_span.clone()], "-.5");
        assert_eq!(v[5].kind, TokenKind::Comment);
        assert_eq!(&line[v[6].span.clone()], "; rest");
    }

    #[test]
    fn parameters_expressions_and_owords() {
        assert_eq!(
            kinds("#<xscale> = 1.0")[0],
            TokenKind::Assignment {
                param: None,
                named: true
            }
        );
        assert_eq!(
            kinds("#5221=3")[0],
            TokenKind::Assignment {
                param: Some(5221),
                named: false
            }
        );
        assert_eq!(
            kinds("G0X[#<xscale>*53.]")[1],
            TokenKind::Word {
                letter: b'X',
                value: Value::Computed
            }
        );
        assert_eq!(
            kinds("x sin[30]")[0],
            TokenKind::Word {
                letter: b'X',
                value: Value::Computed
            }
        );
        assert_eq!(
            kinds("o100 while [ #100 le 180 ]"),
            vec![TokenKind::OWord { keyword: true }]
        );
        assert_eq!(kinds("O1234"), vec![TokenKind::OWord { keyword: false }]);
        for signed in ["X-sin[30]", "x+COS[0]", "X-#1", "X-[1]"] {
            assert_eq!(
                kinds(signed)[0],
                TokenKind::Word {
                    letter: b'X',
                    value: Value::Computed
                },
                "{signed}"
            );
        }
        let mut v = Vec::new();
        assert!(lex_line(b"G1 X-e", 0, &mut v).is_err()); // a letter that starts no function
        assert_eq!(kinds("/G1 X1")[0], TokenKind::BlockDelete);
        assert_eq!(kinds(" % ")[0], TokenKind::Percent);
    }

    #[test]
    fn errors_name_the_column() {
        let mut v = Vec::new();
        let e = lex_line(b"G1 X1 (open", 0, &mut v).unwrap_err();
        assert_eq!(e.column, 7);
        let e = lex_line(b"G1 X", 0, &mut v).unwrap_err();
        assert_eq!(e.column, 4);
        let e = lex_line(b"G1 X1 0", 0, &mut v).unwrap_err();
        assert_eq!(e.column, 7);
        assert!(lex_line("G1 X\u{e9}".as_bytes(), 0, &mut v).is_err());
        assert_eq!(parse_number(b"5."), Some(5.0));
        assert_eq!(parse_number(b"-.5"), Some(-0.5));
        assert_eq!(parse_number(b"+1.25"), Some(1.25));
        assert_eq!(parse_number(b"."), None);
    }
}
