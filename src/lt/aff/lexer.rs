//! The AFF reader's lexer: tokens with their line and column, and [`Ctx`], the typed reads of one
//! directive's arguments (numbers, vectors, counts, words) with errors located in the file.

use glam::DVec3;

use crate::error::InputError;

#[derive(Clone, Copy)]
pub(super) struct Tok<'a> {
    pub(super) text: &'a [u8],
    pub(super) line: usize,
    pub(super) col: usize,
}

impl Tok<'_> {
    pub(super) fn show(&self) -> String {
        String::from_utf8_lossy(self.text).into_owned()
    }
    pub(super) fn is(&self, s: &str) -> bool {
        self.text == s.as_bytes()
    }
    pub(super) fn number(&self) -> Option<f64> {
        let c = *self.text.first()?;
        if !(c.is_ascii_digit() || c == b'-' || c == b'+' || c == b'.') {
            return None;
        }
        std::str::from_utf8(self.text)
            .ok()?
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
    }
}

#[derive(Clone, Copy)]
pub(super) struct Lexer<'a> {
    pub(super) src: &'a [u8],
    pub(super) pos: usize,
    pub(super) line: usize,
    pub(super) line_start: usize,
}

impl<'a> Lexer<'a> {
    pub(super) fn new(src: &'a [u8]) -> Self {
        Lexer {
            src,
            pos: 0,
            line: 1,
            line_start: 0,
        }
    }

    pub(super) fn skip(&mut self) {
        let s = self.src;
        while self.pos < s.len() {
            match s[self.pos] {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'%' | b'#' => {
                    while self.pos < s.len() && s[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    pub(super) fn here(&self) -> (usize, usize) {
        (self.line, self.pos - self.line_start + 1)
    }

    pub(super) fn next(&mut self) -> Option<Tok<'a>> {
        self.skip();
        let s = self.src;
        if self.pos >= s.len() {
            return None;
        }
        let (line, col) = self.here();
        let start = self.pos;
        if s[start] == b'{' || s[start] == b'}' {
            self.pos += 1;
        } else {
            while self.pos < s.len()
                && !matches!(
                    s[self.pos],
                    b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c | b'{' | b'}'
                )
            {
                self.pos += 1;
            }
        }
        Some(Tok {
            text: &s[start..self.pos],
            line,
            col,
        })
    }

    pub(super) fn peek(&self) -> Option<Tok<'a>> {
        let mut c = *self;
        c.next()
    }
}

/// Parsing context of one file: its name (for errors) and lexer.
pub(super) struct Ctx<'a> {
    pub(super) name: String,
    pub(super) lx: Lexer<'a>,
    pub(super) key: &'static str,
    /// Where the directive being read starts.
    pub(super) at: (usize, usize),
}

impl<'a> Ctx<'a> {
    pub(super) fn err_at(&self, at: (usize, usize), message: String) -> InputError {
        InputError {
            file: self.name.clone(),
            at: Some(at),
            key: Some(self.key.to_string()),
            message,
        }
    }

    pub(super) fn eof(&self, what: &str) -> InputError {
        self.err_at(
            self.lx.here(),
            format!(
                "the file ends inside `{}` (started at line {}): expected {what}",
                self.key, self.at.0
            ),
        )
    }

    pub(super) fn tok(&mut self, what: &str) -> Result<Tok<'a>, InputError> {
        self.lx.next().ok_or_else(|| self.eof(what))
    }

    pub(super) fn num(&mut self, what: &str) -> Result<f64, InputError> {
        let t = self.tok(what)?;
        t.number().ok_or_else(|| {
            self.err_at(
                (t.line, t.col),
                format!("`{}` is not a number: expected {what}", t.show()),
            )
        })
    }

    pub(super) fn vec3(&mut self, what: &str) -> Result<DVec3, InputError> {
        Ok(DVec3::new(
            self.num(what)?,
            self.num(what)?,
            self.num(what)?,
        ))
    }

    /// A count or an index: a non-negative integer below `limit`.
    pub(super) fn int(&mut self, what: &str, limit: usize) -> Result<usize, InputError> {
        let t = self.tok(what)?;
        let bad = |ctx: &Self, m: String| ctx.err_at((t.line, t.col), m);
        let Some(x) = t.number() else {
            return Err(bad(
                self,
                format!("`{}` is not a number: expected {what}", t.show()),
            ));
        };
        if x < 0.0 || x.fract() != 0.0 {
            return Err(bad(
                self,
                format!(
                    "`{}` is not a non-negative integer: expected {what}",
                    t.show()
                ),
            ));
        }
        if x >= limit as f64 {
            return Err(bad(
                self,
                format!(
                    "{what} {} is out of range (must be below {limit})",
                    t.show()
                ),
            ));
        }
        Ok(x as usize)
    }

    pub(super) fn word(&mut self, word: &str) -> Result<(), InputError> {
        let t = self.tok(&format!("`{word}`"))?;
        if t.is(word) {
            Ok(())
        } else {
            Err(self.err_at(
                (t.line, t.col),
                format!("expected `{word}`, found `{}`", t.show()),
            ))
        }
    }
}
