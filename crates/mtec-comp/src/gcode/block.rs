//! One block (line) read into the words the rewriter cares about, with their token indices.
//!
//! The block keeps references into the token list, never copies of the text: an edit later
//! replaces exactly the bytes of one word's value.

use super::code::{tenths_of, GCode};
use super::lexer::{Token, TokenKind, Value};

/// A word of the block: its value and the index of its token.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WordRef {
    pub value: Value,
    pub token: usize,
}

/// A construct the rewriter does not compensate, located by its token.
#[derive(Debug, Clone, PartialEq)]
pub struct Issue {
    pub token: Option<usize>,
    pub message: String,
    /// True when the construct may change state the rewriter tracks in ways it cannot follow
    /// (subroutines, control flow, offsets written by parameters, unknown G-codes).
    pub poisons_all: bool,
}

/// The words of one block, by letter.
#[derive(Debug, Default)]
pub struct Block {
    pub block_delete: bool,
    pub percent: bool,
    /// The G codes with their token index.
    pub g: Vec<(GCode, usize)>,
    /// The M codes (M6 → 6) with their token index.
    pub m: Vec<(u32, usize)>,
    /// A..Z words other than G, M, N (index: letter − b'A'); `@` and `^` in `polar`.
    pub letters: [Option<WordRef>; 26],
    pub polar: Option<usize>,
    pub issues: Vec<Issue>,
    /// Index of the first word token after the line number (where a motion word is inserted).
    pub first_word: Option<usize>,
}

impl Block {
    pub fn word(&self, letter: u8) -> Option<WordRef> {
        self.letters[(letter - b'A') as usize]
    }

    pub fn has_g(&self, code: GCode) -> Option<usize> {
        self.g.iter().find(|(c, _)| *c == code).map(|(_, t)| *t)
    }

    pub fn has_m(&self, code: u32) -> Option<usize> {
        self.m.iter().find(|(c, _)| *c == code).map(|(_, t)| *t)
    }

    fn issue(&mut self, token: usize, message: impl Into<String>, poisons_all: bool) {
        self.issues.push(Issue {
            token: Some(token),
            message: message.into(),
            poisons_all,
        });
    }

    /// Reads the tokens of a line into a block; constructs that cannot be compensated are
    /// collected in `issues` (in order of appearance), not refused here.
    pub fn read(tokens: &[Token], line: &[u8]) -> Block {
        let mut b = Block::default();
        b.read_into(tokens, line);
        b
    }

    /// As [`Block::read`], reusing this block's buffers (no allocation per line).
    pub fn read_into(&mut self, tokens: &[Token], line: &[u8]) {
        let b = self;
        b.block_delete = false;
        b.percent = false;
        b.g.clear();
        b.m.clear();
        b.letters = [None; 26];
        b.polar = None;
        b.issues.clear();
        b.first_word = None;
        for (i, t) in tokens.iter().enumerate() {
            match t.kind {
                TokenKind::BlockDelete => b.block_delete = true,
                TokenKind::Percent => b.percent = true,
                TokenKind::Comment => {}
                TokenKind::OWord { keyword } => {
                    if b.first_word.is_some() {
                        b.issue(
                            i,
                            "O-word after other words: LinuxCNC reads an O-word only at the start of a line (\"Bad character 'o' used\")",
                            true,
                        );
                    } else if keyword {
                        b.issue(
                            i,
                            "O-word control flow or subroutine (sub/call/if/while/…): the path depends on run-time values",
                            true,
                        );
                    }
                }
                TokenKind::Assignment { param, named } => match (param, named) {
                    (_, true) => {}
                    (Some(n), false) if n < 5000 => {}
                    (Some(n), false) => b.issue(
                        i,
                        format!("assignment to system parameter #{n} (offsets and machine state live there)"),
                        true,
                    ),
                    (None, false) => b.issue(i, "assignment to an indirect parameter", true),
                },
                TokenKind::Word { letter, value } => {
                    if b.first_word.is_none() && letter != b'N' {
                        b.first_word = Some(i);
                    }
                    match letter {
                        b'G' | b'M' => {
                            let Value::Number(v) = value else {
                                b.issue(
                                    i,
                                    format!(
                                        "{} word with a parameter or expression: the mode cannot be known before run time",
                                        letter as char
                                    ),
                                    true,
                                );
                                continue;
                            };
                            let Some(tenths) = tenths_of(v) else {
                                b.issue(i, format!("{} code {v} is not a known code", letter as char), true);
                                continue;
                            };
                            if letter == b'G' {
                                b.g.push((GCode::from_tenths(tenths), i));
                            } else if !tenths.is_multiple_of(10) {
                                b.issue(i, format!("M code {v} is not a known code", ), true);
                            } else {
                                b.m.push((tenths / 10, i));
                            }
                        }
                        b'N' if b.first_word.is_some() => b.issue(
                            i,
                            "N word after other words: LinuxCNC reads a line number only at the start of a line (\"Bad character 'n' used\")",
                            true,
                        ),
                        b'N' => {}
                        b'@' | b'^' => {
                            if b.polar.is_none() {
                                b.polar = Some(i);
                            }
                        }
                        l => {
                            let k = (l - b'A') as usize;
                            if b.letters[k].is_some() {
                                b.issue(
                                    i,
                                    format!("two {} words in one block", l as char),
                                    true,
                                );
                            } else {
                                b.letters[k] = Some(WordRef { value, token: i });
                            }
                        }
                    }
                }
            }
        }
        let _ = line;
    }
}
