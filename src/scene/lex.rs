//! A byte tokenizer shared by the text readers (NFF, ASCII STL).
//!
//! Token-based rather than line-based: NFF entities may span lines. `\r` (CRLF and lone CR
//! files exist) and every other ASCII space is whitespace; `#` starts a comment to the end of
//! the line. Every token remembers its line and column so errors can point at it.

use crate::error::Error;

/// One whitespace-separated token and where it starts (1-based line and column).
#[derive(Clone, Copy, Debug)]
pub struct Token<'a> {
    pub text: &'a [u8],
    pub line: u32,
    pub col: u32,
}

impl Token<'_> {
    /// The token as printable text for messages (lossy, shortened).
    pub fn show(&self) -> String {
        show_bytes(self.text)
    }
}

fn show_bytes(b: &[u8]) -> String {
    const MAX: usize = 40;
    let s = String::from_utf8_lossy(&b[..b.len().min(MAX)]);
    if b.len() > MAX {
        format!("'{s}...'")
    } else {
        format!("'{s}'")
    }
}

pub struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
    name: &'a str,
}

impl<'a> Lexer<'a> {
    pub fn new(src: &'a [u8], name: &'a str) -> Self {
        Lexer {
            src,
            pos: 0,
            line: 1,
            line_start: 0,
            name,
        }
    }

    pub fn name(&self) -> &'a str {
        self.name
    }

    /// Bytes not yet consumed (used to reject counts the rest of the file cannot hold).
    pub fn remaining(&self) -> usize {
        self.src.len() - self.pos
    }

    fn skip_space(&mut self) {
        while let Some(&b) = self.src.get(self.pos) {
            match b {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'#' => {
                    while self.pos < self.src.len() && self.src[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    /// The next token, or `None` at the end of the input.
    pub fn next_token(&mut self) -> Option<Token<'a>> {
        self.skip_space();
        if self.pos >= self.src.len() {
            return None;
        }
        let start = self.pos;
        let col = (start - self.line_start) as u32 + 1;
        while let Some(&b) = self.src.get(self.pos) {
            if b.is_ascii_whitespace() || b == 0x0b || b == b'#' {
                break;
            }
            self.pos += 1;
        }
        Some(Token {
            text: &self.src[start..self.pos],
            line: self.line,
            col,
        })
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Option<Token<'a>> {
        let saved = (self.pos, self.line, self.line_start);
        let t = self.next_token();
        (self.pos, self.line, self.line_start) = saved;
        t
    }

    /// True when the next token is a number (used for optional trailing numbers).
    pub fn peek_is_number(&mut self) -> bool {
        self.peek().is_some_and(|t| parse_f32(t.text).is_some())
    }

    /// Error at a token.
    pub fn error_at(&self, tok: &Token, msg: impl Into<String>) -> Error {
        Error::Parse {
            file: self.name.to_string(),
            line: tok.line,
            col: tok.col,
            msg: msg.into(),
        }
    }

    /// Error at the current position (after skipping whitespace): used at end of input.
    pub fn error_here(&mut self, msg: impl Into<String>) -> Error {
        self.skip_space();
        Error::Parse {
            file: self.name.to_string(),
            line: self.line,
            col: (self.pos - self.line_start) as u32 + 1,
            msg: msg.into(),
        }
    }

    /// Consumes a token that must exist; `what` describes what was expected.
    pub fn expect_token(&mut self, what: &str) -> Result<Token<'a>, Error> {
        match self.next_token() {
            Some(t) => Ok(t),
            None => Err(self.error_here(format!("expected {what}, found end of file"))),
        }
    }

    /// A finite number.
    pub fn number(&mut self, what: &str) -> Result<f32, Error> {
        let t = self.expect_token(what)?;
        match parse_f32(t.text) {
            Some(v) if v.is_finite() => Ok(v),
            Some(_) => Err(self.error_at(
                &t,
                format!("expected {what} (a finite number), found {}", t.show()),
            )),
            None => Err(self.error_at(
                &t,
                format!("expected {what} (a number), found {}", t.show()),
            )),
        }
    }

    pub fn vec3(&mut self, what: &str) -> Result<glam::Vec3, Error> {
        Ok(glam::Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// A non-negative integer count.
    pub fn count(&mut self, what: &str) -> Result<(u32, Token<'a>), Error> {
        let t = self.expect_token(what)?;
        let s = std::str::from_utf8(t.text).unwrap_or("");
        match s.parse::<u32>() {
            Ok(n) => Ok((n, t)),
            Err(_) => {
                let kind = if s.starts_with('-') {
                    "a non-negative integer"
                } else {
                    "an integer below 2^32"
                };
                Err(self.error_at(&t, format!("expected {what} ({kind}), found {}", t.show())))
            }
        }
    }
}

/// Parses a number token; `None` when it is not a number at all.
pub fn parse_f32(text: &[u8]) -> Option<f32> {
    // `str::parse` accepts "inf"/"nan" spelled out; callers reject non-finite values with a
    // message of their own.
    std::str::from_utf8(text).ok()?.parse::<f32>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_carry_line_and_column_through_crlf_and_comments() {
        let src = b"b 1 2\r\n# note\r\n  s\r3 # tail\n4";
        let mut lx = Lexer::new(src, "t");
        let toks: Vec<_> = std::iter::from_fn(|| lx.next_token())
            .map(|t| (String::from_utf8_lossy(t.text).into_owned(), t.line, t.col))
            .collect();
        let want = [
            ("b", 1, 1),
            ("1", 1, 3),
            ("2", 1, 5),
            ("s", 3, 3),
            ("3", 3, 5),
            ("4", 4, 1),
        ];
        let got: Vec<_> = toks.iter().map(|(s, l, c)| (s.as_str(), *l, *c)).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn numbers_with_exponents_parse_and_non_finite_are_rejected() {
        let mut lx = Lexer::new(b"1.11022e-16 nan 1e999 x", "t");
        assert_eq!(lx.number("n").unwrap(), 1.11022e-16);
        for _ in 0..3 {
            assert!(lx.number("n").is_err());
        }
    }
}
