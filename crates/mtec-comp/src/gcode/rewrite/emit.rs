//! The emitter: the text of the rewritten program.
//!
//! **What it is for**: the pieces of a planned move written as edits of the original line
//! (only the words that change: their value bytes are replaced, new words inserted after the
//! axis words, removed words taken out with their blanks) and as added `G1` lines; numbers
//! rounded to the `--decimals` in effect and the output position tracked as the rounded words
//! command it; the line's letter case and word separators kept; the motion word restored where
//! the output's modal motion differs from the program's; the provenance header and the line
//! length limit when a changed line is written.
//! **Not for**: deciding what the pieces are (`plan`) or the modal state (`interp`); the feed
//! words of split moves are written by `rotary_move`.

// axis loops index several per-axis arrays at once (target, correction, offsets, words)
#![allow(clippy::needless_range_loop)]

use super::super::arc::Arc;
use super::super::block::Block;
use super::super::code::GCode;
use super::super::format::{apply_edits, decimal_value, write_decimal, Edit};
use super::super::lexer::{TokenKind, Value};
use super::interp::Motion;
use super::options::{RewriteOptions, Units};
use super::piece::{EmittedEnd, Piece, ROTARY_DECIMALS};
use super::report::{GcodeError, ProblemKind};
use super::rewriter::Rewriter;
use super::words::{case, case_letter, rounded, write_rounded};
use crate::ErrorModel;
use std::io::Write;

impl Rewriter<'_> {
    /// Copies a line as it was read.
    pub(super) fn write_verbatim<W: Write>(
        &mut self,
        body: &[u8],
        ending: &[u8],
        output: &mut W,
    ) -> Result<(), GcodeError> {
        output.write_all(body)?;
        output.write_all(ending)?;
        self.report.lines_written += 1;
        Ok(())
    }

    /// Writes a line with its edits applied and the added lines after it (with the line's own
    /// ending), preceded by the provenance header when it is the first line that changes;
    /// refuses a line longer than the controller reads.
    pub(super) fn write_edited<W: Write>(
        &mut self,
        body: &[u8],
        ending: &[u8],
        output: &mut W,
    ) -> Result<(), GcodeError> {
        let bom = self.line_no == 1 && body.starts_with(b"\xEF\xBB\xBF");
        if !self.report.header_written {
            self.report.header_written = true;
            if bom {
                // the byte-order mark stays the first bytes of the file
                output.write_all(b"\xEF\xBB\xBF")?;
            }
            let header = header_comment(self.planner.view.model(), self.opt);
            output.write_all(header.as_bytes())?;
            output.write_all(if ending.is_empty() { b"\n" } else { ending })?;
            self.report.lines_written += 1;
        }
        self.out_buf.clear();
        let mut edits = std::mem::take(&mut self.edits);
        apply_edits(body, &mut edits, &mut self.out_buf);
        self.edits = edits;
        if bom {
            self.out_buf.drain(..3); // no edit touches the mark: the lexer starts after it
        }
        // the lines added for a `/` block keep its `/`: at the other switch position the whole
        // block is skipped, as in the original, instead of all but its first piece
        let delete = self
            .tokens
            .first()
            .is_some_and(|t| t.kind == TokenKind::BlockDelete);
        let prefix: &[u8] = if delete { b"/" } else { b"" };
        let longest_added =
            self.extra_lines.iter().map(|l| l.len()).max().unwrap_or(0) + prefix.len();
        let edited = self.out_buf.len();
        if (edited > self.opt.max_line_chars && edited > body.len())
            || longest_added > self.opt.max_line_chars
        {
            return Err(GcodeError::At(self.diag(
                1,
                ProblemKind::Correction,
                format!(
                    "the rewritten line would be {} characters, over the controller's limit of {} (--max-line-chars; LinuxCNC refuses longer lines): shorten its comments",
                    edited.max(longest_added),
                    self.opt.max_line_chars
                ),
            )));
        }
        let sep: &[u8] = if ending.is_empty() { b"\n" } else { ending };
        for l in &self.extra_lines {
            self.out_buf.extend_from_slice(sep);
            self.out_buf.extend_from_slice(prefix);
            self.out_buf.extend_from_slice(l.as_bytes());
        }
        self.out_buf.extend_from_slice(ending);
        output.write_all(&self.out_buf)?;
        self.report.lines_written += 1 + self.extra_lines.len();
        self.report.lines_added += self.extra_lines.len();
        Ok(())
    }

    /// Digits after the point of a rewritten word in the units in effect.
    pub(super) fn decimals(&self) -> usize {
        match self.st.units {
            Some(Units::Inch) => self.opt.decimals_inch,
            _ => self.opt.decimals_mm,
        }
    }

    /// Makes sure a block that relies on the modal motion mode still moves the way the program
    /// means, when earlier rewriting changed the mode of the output (an arc turned into G1s).
    pub(super) fn restore_motion_word(&mut self, b: &Block, m: Motion, uses_modal: bool) {
        if uses_modal && self.st.out_motion != m && !m.code().is_empty() {
            let tok = b.first_word.unwrap_or(0);
            let pos = self.tokens.get(tok).map(|t| t.span.start).unwrap_or(0);
            let text = format!("{}{}", case(m.code(), self.lower(b)), self.sep_for(b));
            self.edits.push(Edit {
                span: pos..pos,
                text,
                order: 0,
            });
        }
        self.st.out_motion = m;
    }

    fn lower(&self, _b: &Block) -> bool {
        self.lower
    }

    fn sep_for(&self, b: &Block) -> &'static str {
        let _ = b;
        self.sep_for_line()
    }

    /// " " when the current line separates its words with blanks, "" otherwise.
    pub(super) fn sep_for_line(&self) -> &'static str {
        let spaced = self
            .tokens
            .windows(2)
            .any(|w| w[1].span.start > w[0].span.end);
        if spaced {
            " "
        } else {
            ""
        }
    }

    /// Writes the pieces of one move: the first on the original line (its words edited), the
    /// others as new `G1` lines. `linearised` arcs lose their G2/G3, I, J, K, R and P words.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn emit_pieces(
        &mut self,
        b: &Block,
        body: &[u8],
        m: Motion,
        uses_modal: bool,
        pieces: &[Piece],
        words: &[Option<(f64, usize)>; 3],
        offsets: [f64; 3],
        absolute: bool,
        scale: f64,
        linearised: bool,
    ) -> Result<(), GcodeError> {
        let _ = body;
        self.emitted = true;
        let lower = self.lower(b);
        let sep = self.sep_for(b);
        let decimals = self.decimals();
        // --- the original line = first piece -------------------------------------------------
        if linearised {
            for l in [b'I', b'J', b'K', b'R', b'P'] {
                if let Some(w) = b.word(l) {
                    let span = self.removal_span(body, self.tokens[w.token].span.clone());
                    self.edits.push(Edit {
                        span,
                        text: String::new(),
                        order: 0,
                    });
                }
            }
            let g1 = case("G1", lower);
            match b.g.iter().find(|(c, _)| matches!(c, GCode::G2 | GCode::G3)) {
                Some(&(_, tok)) if !uses_modal => {
                    let span = self.tokens[tok].span.clone();
                    self.edits.push(Edit {
                        span,
                        text: g1,
                        order: 0,
                    });
                }
                _ => {
                    if self.st.out_motion != Motion::Linear {
                        let tok = b.first_word.unwrap_or(0);
                        let pos = self.tokens[tok].span.start;
                        self.edits.push(Edit {
                            span: pos..pos,
                            text: format!("{g1}{sep}"),
                            order: 0,
                        });
                    }
                }
            }
            self.st.out_motion = Motion::Linear;
        } else {
            self.restore_motion_word(b, m, uses_modal);
        }
        let edits_before = self.edits.len();
        let insert_at = [b'X', b'Y', b'Z']
            .iter()
            .filter_map(|&l| b.word(l))
            .map(|w| self.tokens[w.token].span.end)
            .max()
            .or_else(|| {
                // no axis word (a full circle): after the line's last word, before a comment
                self.tokens
                    .iter()
                    .rev()
                    .find(|t| matches!(t.kind, TokenKind::Word { .. }))
                    .map(|t| t.span.end)
            })
            .unwrap_or(0);
        let Piece { t: t0, c: c0, .. } = pieces[0];
        let last = pieces.len() == 1;
        for a in 0..3 {
            let want = t0[a] + c0[a];
            let out_prev = self.st.out[a];
            let letter = [b'X', b'Y', b'Z'][a];
            match words[a] {
                Some((v, tok)) => {
                    let span = self.tokens[tok].value_span.clone();
                    // exact shortcut: the final piece with the same correction as before keeps its text
                    let delta = if absolute {
                        c0[a] + self.shift[a]
                    } else {
                        c0[a] - (out_prev.unwrap_or(0.0) - self.st.prog[a].unwrap_or(0.0))
                    };
                    if last && delta == 0.0 {
                        self.st.out[a] = if absolute {
                            Some(v * scale + offsets[a])
                        } else {
                            out_prev.map(|o| o + v * scale)
                        };
                        continue;
                    }
                    let w = if absolute {
                        (want - offsets[a]) / scale
                    } else {
                        (want - out_prev.unwrap_or(0.0)) / scale
                    };
                    let (r, n) = rounded(w, decimals);
                    if r != v {
                        let mut s = self.spare_texts.pop().unwrap_or_default();
                        write_rounded(w, decimals, n, &mut s);
                        self.edits.push(Edit {
                            span,
                            text: s,
                            order: 0,
                        });
                    }
                    self.st.out[a] = if absolute {
                        Some(r * scale + offsets[a])
                    } else {
                        out_prev.map(|o| o + r * scale)
                    };
                }
                None => {
                    if let Some(text) =
                        self.new_word(a, want, offsets[a], absolute, scale, decimals)
                    {
                        self.edits.push(Edit {
                            span: insert_at..insert_at,
                            text: format!("{sep}{}{text}", case_letter(letter, lower) as char),
                            order: 1 + a as u8,
                        });
                    }
                }
            }
        }
        if let Some(mv) = self.rot_move.filter(|_| pieces.len() > 1) {
            // a split rotary move: its first piece ends at the first piece's angles
            for k in 0..3 {
                let Some((v, tok)) = mv.words[k] else {
                    continue;
                };
                if mv.r1[k] == mv.r0[k] {
                    continue;
                }
                let n = mv.written_count(k, pieces[0].rot.unwrap_or(mv.r1)[k]);
                if decimal_value(n, ROTARY_DECIMALS) != v {
                    let mut text = String::new();
                    write_decimal(n, ROTARY_DECIMALS, &mut text);
                    let span = self.tokens[tok].value_span.clone();
                    self.edits.push(Edit {
                        span,
                        text,
                        order: 0,
                    });
                }
            }
        }
        self.ends.clear();
        self.ends.push(EmittedEnd {
            line: None,
            s: pieces[0].s,
            xyz: self.st.out.map(|o| o.unwrap_or(0.0)),
            rot: pieces[0].rot,
        });
        if self.edits.len() > edits_before || pieces.len() > 1 || linearised {
            self.report.moves_compensated += 1;
        }
        // --- the other pieces as new lines -----------------------------------------------
        for (i, &Piece { t, c, s, rot }) in pieces.iter().enumerate().skip(1) {
            // G53 is not modal: every piece of a machine-coordinate move repeats it
            let mut line = case(if self.g53 { "G53 G1" } else { "G1" }, lower);
            let mut moved = false;
            for a in 0..3 {
                if let Some(text) =
                    self.new_word(a, t[a] + c[a], offsets[a], absolute, scale, decimals)
                {
                    line.push(' ');
                    line.push(case_letter([b'X', b'Y', b'Z'][a], lower) as char);
                    line.push_str(&text);
                    moved = true;
                }
            }
            if let (Some(mv), Some(w)) = (self.rot_move, rot) {
                let prev = pieces[i - 1].rot.unwrap_or(mv.r0);
                let last = i + 1 == pieces.len();
                for k in 0..3 {
                    if mv.r1[k] == mv.r0[k] || (w[k] == prev[k] && !last) {
                        continue;
                    }
                    let text = if last {
                        mv.last_word_text(k, &self.tokens, body, prev[k])
                    } else {
                        Some(mv.word_text(k, w[k], prev[k]))
                    };
                    if let Some(text) = text {
                        line.push(' ');
                        line.push(case_letter([b'A', b'B', b'C'][k], lower) as char);
                        line.push_str(&text);
                        moved = true;
                    }
                }
            }
            if moved {
                self.ends.push(EmittedEnd {
                    line: Some(self.extra_lines.len()),
                    s,
                    xyz: self.st.out.map(|o| o.unwrap_or(0.0)),
                    rot,
                });
                self.extra_lines.push(line);
            } else if let Some(e) = self.ends.last_mut() {
                // nothing written: the previous line's move takes this piece's time too
                e.s = s;
            }
            self.st.out_motion = Motion::Linear;
        }
        Ok(())
    }

    /// The value text of a word moving axis `a` to `want_mm` (machine frame), or None when the
    /// rounded command would not change; updates the output position.
    pub(super) fn new_word(
        &mut self,
        a: usize,
        want_mm: f64,
        offset: f64,
        absolute: bool,
        scale: f64,
        decimals: usize,
    ) -> Option<String> {
        let prev = self.st.out[a];
        if prev == Some(want_mm) {
            return None;
        }
        let mut s = String::new();
        if absolute {
            let w = (want_mm - offset) / scale;
            let (r, n) = rounded(w, decimals);
            if let Some(p) = prev {
                // unchanged after rounding: no word
                let (rp, _) = rounded((p - offset) / scale, decimals);
                if rp == r {
                    return None;
                }
            }
            write_rounded(w, decimals, n, &mut s);
            self.st.out[a] = Some(r * scale + offset);
        } else {
            let p = prev?;
            let w = (want_mm - p) / scale;
            let (r, n) = rounded(w, decimals);
            if r == 0.0 {
                return None;
            }
            write_rounded(w, decimals, n, &mut s);
            self.st.out[a] = Some(p + r * scale);
        }
        Some(s)
    }

    /// M0, M1, M2, M30 and M60 run after the block's motion (LinuxCNC's order of execution:
    /// stops last): when the block is written as several lines they leave the original line
    /// and follow the last one, on a line of their own. Before (found 2026-11-28 with random
    /// blocks), `G1 M2` split in two ended the program after the first piece.
    pub(super) fn move_stops_after_the_move(&mut self, b: &Block, body: &[u8]) {
        for &(code, tok) in &b.m {
            if !matches!(code, 0 | 1 | 2 | 30 | 60) {
                continue;
            }
            let span = self.tokens[tok].span.clone();
            let text = String::from_utf8_lossy(&body[span.clone()]).into_owned();
            let span = self.removal_span(body, span);
            self.edits.push(Edit {
                span,
                text: String::new(),
                order: 0,
            });
            self.extra_lines.push(text);
        }
    }

    /// The span to delete for a removed word: with the blanks before it, or (when it starts
    /// the line) with the blanks after it, so no double or leading blank is left.
    fn removal_span(&self, body: &[u8], span: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let blank = |c: u8| c == b' ' || c == b'\t';
        let mut s = span.start;
        while s > 0 && blank(body[s - 1]) {
            s -= 1;
        }
        if s > 0 {
            return s..span.end;
        }
        let mut e = span.end;
        while e < body.len() && blank(body[e]) {
            e += 1;
        }
        span.start..e
    }

    /// Replaces the R word of an arc kept as an arc by its centre offsets (I, J, K of the
    /// plane), centre = nominal centre moved with the start's correction `c0`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn r_to_center(
        &mut self,
        arc: &Arc,
        r_token: usize,
        start: [f64; 3],
        c0: [f64; 3],
        offsets: [f64; 3],
        scale: f64,
    ) {
        let lower = self.lower;
        let sep = self.sep_for_line();
        let d = self.decimals();
        let absolute_center = self.st.arc_absolute == Some(true);
        let mut text = String::new();
        for (k, axis) in [arc.plane.first, arc.plane.second].into_iter().enumerate() {
            let v = if absolute_center {
                (arc.center[k] + c0[axis] - offsets[axis]) / scale
            } else {
                // incremental: from the written start (start + c0) to the centre + c0
                (arc.center[k] - start[axis]) / scale
            };
            if k > 0 {
                text.push_str(sep);
            }
            text.push(case_letter([b'I', b'J', b'K'][axis], lower) as char);
            let (_, n) = rounded(v, d);
            write_rounded(v, d, n, &mut text);
        }
        let span = self.tokens[r_token].span.clone();
        self.edits.push(Edit {
            span,
            text,
            order: 0,
        });
    }

    /// The centre words (I, J, K) of a G90.1 arc kept as an arc: the end points move with the
    /// correction, the centre with the start's (`c0`), and the written word is read with the
    /// rewritten program's offsets.
    pub(super) fn shift_center_words(&mut self, b: &Block, c0: [f64; 3], scale: f64) {
        // endpoints move with the correction; the centre moves with the start's
        for (a, l) in [b'I', b'J', b'K'].iter().enumerate() {
            if let Some(w) = b.word(*l) {
                // and the written word is read with the rewritten program's offsets
                let shift = c0[a] + self.shift[a];
                if shift != 0.0 {
                    let Value::Number(v) = w.value else { continue };
                    let d = self.decimals();
                    let (r, n) = rounded(v + shift / scale, d);
                    let span = self.tokens[w.token].value_span.clone();
                    if r != v {
                        let mut s = String::new();
                        write_rounded(v + shift / scale, d, n, &mut s);
                        self.edits.push(Edit {
                            span,
                            text: s,
                            order: 0,
                        });
                    }
                }
            }
        }
    }
}

/// The provenance comment written before the first rewritten line.
pub fn header_comment(model: &dyn ErrorModel, opt: &RewriteOptions) -> String {
    let describe: String = model
        .describe()
        .chars()
        .map(|c| match c {
            '(' => '[',
            ')' => ']',
            '\n' | '\r' => ' ',
            c if c.is_ascii() => c,
            _ => '?',
        })
        .collect();
    let knobs = format!(
        "; tolerance {} um, max segment {} mm, chord tolerance {} um)",
        opt.tolerance_um, opt.max_segment_mm, opt.chord_tolerance_um
    );
    let head = format!(
        "(mtec compensate gcode {}: lines below corrected with model: ",
        env!("CARGO_PKG_VERSION")
    );
    // the whole comment stays within the controller's line length: the model's description
    // is shortened (with "...") when it would not fit
    let room = opt
        .max_line_chars
        .saturating_sub(head.len() + knobs.len())
        .max(8);
    let describe = if describe.len() > room {
        format!("{}...", &describe[..room - 3])
    } else {
        describe
    };
    format!("{head}{describe}{knobs}")
}
