//! The pieces of a planned move and what is written for them: [`Piece`] (target, correction,
//! fraction of the move, rotary angles), [`RotaryMove`] (a move that turns a rotary axis, and
//! the text of its rotary words), [`EmittedEnd`] (a written line's end, for the feed words).
//! A leaf: the planner makes these, the emitter and `rotary_move` read them.

use super::super::format::{decimal_value, to_decimal, write_decimal};
use super::super::lexer::Token;

/// The end of one output piece of a move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Piece {
    /// The target in machine axes (mm) at the piece's rotary angles.
    pub(super) t: [f64; 3],
    /// The correction (mm): the axes are commanded to `t + c`.
    pub(super) c: [f64; 3],
    /// The fraction of the original move's duration at the piece's end (1 for the last).
    pub(super) s: f64,
    /// The rotary axes' machine angles (deg) written at the piece's end, for a move that turns
    /// a rotary axis.
    pub(super) rot: Option<[f64; 3]>,
}

impl Piece {
    pub(super) fn new(t: [f64; 3], c: [f64; 3], s: f64) -> Piece {
        Piece { t, c, s, rot: None }
    }
}

/// Digits after the point of a rotary word written for a piece (degrees): 10⁻⁴° turns a point
/// 500 mm from the axis by 0.9 µm, which the linear axes absorb at the piece's end.
pub(super) const ROTARY_DECIMALS: usize = 4;

/// A move that turns a rotary axis: start and end in machine axes (mm, deg).
#[derive(Debug, Clone, Copy)]
pub(super) struct RotaryMove {
    pub x0: [f64; 3],
    pub x1: [f64; 3],
    pub r0: [f64; 3],
    pub r1: [f64; 3],
    /// The correction at the start (None: the start is not known).
    pub c0: Option<[f64; 3]>,
    pub c1: [f64; 3],
    /// The block's A, B, C words (value, token).
    pub words: [Option<(f64, usize)>; 3],
    pub absolute: bool,
    /// Machine angle = program angle + this (deg), in absolute mode.
    pub offset: [f64; 3],
}

/// One written line of a move: which line (None: the original one), the fraction of the move
/// at its end, and the written axes there.
#[derive(Debug, Clone, Copy)]
pub(super) struct EmittedEnd {
    pub line: Option<usize>,
    pub s: f64,
    pub xyz: [f64; 3],
    pub rot: Option<[f64; 3]>,
}

impl RotaryMove {
    /// The machine angle written for a wanted machine angle `r` of axis `k` (module docs).
    pub(super) fn written(&self, k: usize, r: f64) -> f64 {
        let base = if self.absolute {
            self.offset[k]
        } else {
            self.r0[k]
        };
        match to_decimal(r - base, ROTARY_DECIMALS) {
            Some(n) => base + decimal_value(n, ROTARY_DECIMALS),
            None => r,
        }
    }

    /// The word value (count of 10⁻⁴) of axis `k` for a piece ending at machine angle `w`, on
    /// the original line (the first piece): absolute, or incremental from the start.
    pub fn written_count(&self, k: usize, w: f64) -> i64 {
        let base = if self.absolute {
            self.offset[k]
        } else {
            self.r0[k]
        };
        to_decimal(w - base, ROTARY_DECIMALS).unwrap_or(0)
    }

    /// The word text of axis `k` for a piece from `prev` to `w` (not the last piece).
    pub fn word_text(&self, k: usize, w: f64, prev: f64) -> String {
        let mut text = String::new();
        let n = self.written_count(k, w);
        let n = if self.absolute {
            n
        } else {
            n - self.written_count(k, prev)
        };
        write_decimal(n, ROTARY_DECIMALS, &mut text);
        text
    }

    /// The word text of axis `k` on the last piece, which ends at the programmed angle exactly:
    /// the original word's text (absolute), or the programmed increment less what the pieces
    /// before it turned, in exact decimal arithmetic (incremental).
    pub fn last_word_text(
        &self,
        k: usize,
        tokens: &[Token],
        body: &[u8],
        prev: f64,
    ) -> Option<String> {
        let (v, tok) = self.words[k]?;
        let span = tokens[tok].value_span.clone();
        let text = String::from_utf8_lossy(&body[span]).to_string();
        if self.absolute {
            return Some(text);
        }
        let digits = text.split_once('.').map_or(0, |(_, f)| {
            f.chars().take_while(|c| c.is_ascii_digit()).count()
        });
        let d = digits.max(ROTARY_DECIMALS);
        if d > 9 {
            return None;
        }
        let total = to_decimal(v, d)?;
        let before = self.written_count(k, prev) * 10i64.pow((d - ROTARY_DECIMALS) as u32);
        let mut out = String::new();
        write_decimal(total - before, d, &mut out);
        Some(out)
    }
}

/// Distance between two points (mm, or deg for angles).
pub(super) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
