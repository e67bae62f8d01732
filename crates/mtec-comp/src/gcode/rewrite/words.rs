//! The text of a written word: a value rounded to the digits in effect and its decimal text,
//! and the letter case of the line. A leaf.

use super::super::format::{decimal_value, format_number, to_decimal, write_decimal};

/// `v` rounded to `decimals` digits: the value the written word stands for, and its count.
pub(super) fn rounded(v: f64, decimals: usize) -> (f64, Option<i64>) {
    match to_decimal(v, decimals) {
        Some(n) => (decimal_value(n, decimals), Some(n)),
        None => (v, None),
    }
}

pub(super) fn write_rounded(v: f64, decimals: usize, n: Option<i64>, out: &mut String) {
    match n {
        Some(n) => write_decimal(n, decimals, out),
        None => format_number(v, decimals, out),
    }
}

pub(super) fn case(code: &str, lower: bool) -> String {
    if lower {
        code.to_ascii_lowercase()
    } else {
        code.to_string()
    }
}

pub(super) fn case_letter(l: u8, lower: bool) -> u8 {
    if lower {
        l.to_ascii_lowercase()
    } else {
        l
    }
}
