//! A byte tokenizer shared by the text readers (NFF, OBJ, ASCII STL), reading its input as
//! a stream through a buffer of fixed size, so that a file of any size is read in the
//! same memory.
//!
//! Token-based rather than line-based: NFF entities may span lines. `\r` (CRLF and lone CR
//! files exist) and every other ASCII space is whitespace; `#` starts a comment to the end of
//! the line. Every token remembers its line and column so errors can point at it; the
//! text of the current line stays in the buffer (up to `LINE_KEPT` bytes of it before the
//! token being read) for messages that show it.

use std::fmt::Display;

mod window;

use crate::scene::io::Input;
pub use crate::scene::number::parse_f32;
use crate::util::error::{Error, Result, escape};
use crate::util::limits::MAX_TOKEN_BYTES;
use window::Window;
pub use window::{BOM, LINE_KEPT, Token};

fn show_bytes(b: &[u8]) -> String {
    const MAX: usize = 40;
    let s = escape(&b[..b.len().min(MAX)]);
    if b.len() > MAX {
        format!("'{s}...'")
    } else {
        format!("'{s}'")
    }
}

/// The buffer the input is read through. Large enough that refills cost nothing next to
/// parsing, small enough not to count: the longest token and the kept start of its line
/// always fit.
const BUFFER_BYTES: usize = 256 << 10;

const _: () = assert!(MAX_TOKEN_BYTES + LINE_KEPT < BUFFER_BYTES);

/// Takes tokens from a stream (`io::Input`), through a `Window` of fixed size.
pub struct Lexer<'a> {
    win: Window<'a>,
    /// A token read ahead by `peek`, returned by the next `next_token`.
    peeked: Option<Token>,
}

impl<'a> Lexer<'a> {
    /// A lexer over bytes in memory (gzip-compressed or not).
    pub fn new(src: &'a [u8], name: &'a str) -> Self {
        Self::through(Input::bytes(src), name, None)
    }

    /// A lexer over a stream (`io::open`), which names `name` in its messages, through a
    /// window of `window` bytes where given (`ReadOptions::window`), else the usual one.
    pub fn through(input: Input<'a>, name: &'a str, window: Option<usize>) -> Self {
        Self::with_buffer(input, name, window.unwrap_or(BUFFER_BYTES))
    }

    /// With a buffer of `bytes`, which must exceed the longest token and, for messages to
    /// quote whole lines, the longest line (tests use tiny ones, to cut tokens and lines
    /// everywhere).
    pub fn with_buffer(input: Input<'a>, name: &'a str, bytes: usize) -> Self {
        Lexer {
            win: Window::new(input, name, bytes.max(2)),
            peeked: None,
        }
    }

    pub fn name(&self) -> &'a str {
        self.win.name
    }

    /// Bytes not yet consumed, when the input's length is known (used to reject counts
    /// the rest of the file cannot hold).
    pub fn remaining(&self) -> Option<u64> {
        let w = &self.win;
        let next = self.peeked.map_or(w.base + w.pos as u64, |t| t.at);
        w.len.map(|len| len.saturating_sub(next))
    }

    /// Bytes in the whole input, when known.
    pub fn input_len(&self) -> Option<u64> {
        self.win.len
    }

    /// The bytes of `tok`: the latest token read or peeked, or one before it that the
    /// lexer has not read past the buffer since (empty if it has).
    pub fn text(&self, tok: &Token) -> &[u8] {
        self.win.text(tok)
    }

    /// The token as printable text for messages (lossy, shortened).
    pub fn show(&self, tok: &Token) -> String {
        show_bytes(self.text(tok))
    }

    /// What the buffer holds of the current line: from its start (or, for a line longer
    /// than `LINE_KEPT`, from shortly before the latest token) to its end or as far as
    /// has been read; and the column of its first byte. For messages that quote the line.
    pub fn line_text(&self) -> (&[u8], u32) {
        self.win.line_text()
    }

    /// The input after the end of the current line, as a stream, and the offset it starts
    /// at; `None` when the input ends first. For a text header followed by binary data
    /// (PLY's `end_header`): the lexer reads no further.
    pub fn rest_after_line(self) -> Result<Option<(Box<dyn std::io::Read + 'a>, u64)>> {
        self.win.rest_after_line()
    }

    /// The next token, or `None` at the end of the input.
    #[inline]
    pub fn next_token(&mut self) -> Result<Option<Token>> {
        if let Some(t) = self.peeked.take() {
            return Ok(Some(t));
        }
        if let Some((start, len)) = self.win.quick_token() {
            return Ok(Some(self.win.token_at(start, len)));
        }
        self.win.skip_space()?;
        self.win.scan(MAX_TOKEN_BYTES)
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Result<Option<Token>> {
        if self.peeked.is_none() {
            self.peeked = self.next_token()?;
        }
        Ok(self.peeked)
    }

    /// True when the next token is a number (used for optional trailing numbers).
    pub fn peek_is_number(&mut self) -> Result<bool> {
        Ok(match self.peek()? {
            Some(t) => parse_f32(self.text(&t)).is_some(),
            None => false,
        })
    }

    /// Error at a token, with the token's line (`Excerpt`) as far as the buffer holds it.
    pub fn error_at(&self, tok: &Token, msg: impl Into<String>) -> Error {
        self.win.error_at(tok, msg)
    }

    /// Error at the current position (after skipping whitespace): used at end of input.
    pub fn error_here(&mut self, msg: impl Into<String>) -> Error {
        let at = match self.peeked {
            Some(t) => t,
            None => {
                if let Err(e) = self.win.skip_space() {
                    return e;
                }
                self.win.token_at(self.win.pos, 0)
            }
        };
        self.error_at(&at, msg)
    }

    /// The next token if it is on `line` (for line-based formats: OBJ, MTL).
    pub fn token_on_line(&mut self, line: u32) -> Result<Option<Token>> {
        match self.peek()? {
            Some(t) if t.line == line => self.next_token(),
            _ => Ok(None),
        }
    }

    /// Skips what is left of `line`.
    pub fn skip_line(&mut self, line: u32) -> Result<()> {
        while self.token_on_line(line)?.is_some() {}
        Ok(())
    }

    /// A finite number on the current line; `last` is the statement's latest token, used
    /// to point just past it when the line ends too early.
    pub fn number_on_line(&mut self, last: &mut Token, what: &str) -> Result<f32> {
        let Some(t) = self.token_on_line(last.line)? else {
            let end = last.after();
            return Err(self.error_at(&end, format!("expected {what}, found end of line")));
        };
        *last = t;
        match parse_f32(self.text(&t)) {
            Some(v) if v.is_finite() => Ok(v),
            _ => Err(self.error_at(
                &t,
                format!("expected {what} (a finite number), found {}", self.show(&t)),
            )),
        }
    }

    /// What is left of `line`, its tokens joined by single spaces (names that may hold
    /// spaces: `newmtl`, `usemtl`, `mtllib`).
    pub fn rest_of_line(&mut self, line: u32) -> Result<String> {
        let mut words: Vec<String> = Vec::new();
        while let Some(t) = self.token_on_line(line)? {
            words.push(String::from_utf8_lossy(self.text(&t)).into_owned());
        }
        Ok(words.join(" "))
    }

    // The `what` arguments below describe the expected value for error messages. They are
    // `Display` rather than `&str` so that hot callers (polygon vertices) can pass a small
    // struct that is only formatted when an error actually happens.

    /// Consumes a token that must exist.
    pub fn expect_token<W: Display + ?Sized>(&mut self, what: &W) -> Result<Token> {
        match self.next_token()? {
            Some(t) => Ok(t),
            None => Err(self.error_here(format!("expected {what}, found end of file"))),
        }
    }

    /// A finite number.
    #[inline]
    pub fn number<W: Display + ?Sized>(&mut self, what: &W) -> Result<f32> {
        if self.peeked.is_none()
            && let Some((start, len)) = self.win.quick_token()
        {
            match parse_f32(&self.win.buf[start..start + len]) {
                Some(v) if v.is_finite() => return Ok(v),
                // Not a number after all: the message is the general path's.
                _ => self.peeked = Some(self.win.token_at(start, len)),
            }
        }
        let t = self.expect_token(what)?;
        match parse_f32(self.text(&t)) {
            Some(v) if v.is_finite() => Ok(v),
            Some(_) => Err(self.error_at(
                &t,
                format!("expected {what} (a finite number), found {}", self.show(&t)),
            )),
            None => Err(self.error_at(
                &t,
                format!("expected {what} (a number), found {}", self.show(&t)),
            )),
        }
    }

    #[inline]
    pub fn vec3<W: Display + ?Sized>(&mut self, what: &W) -> Result<glam::Vec3> {
        Ok(glam::Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// A non-negative integer count.
    pub fn count<W: Display + ?Sized>(&mut self, what: &W) -> Result<(u32, Token)> {
        let t = self.expect_token(what)?;
        let text = self.text(&t);
        let s = std::str::from_utf8(text).unwrap_or("");
        match s.parse::<u32>() {
            Ok(n) => Ok((n, t)),
            Err(_) => {
                // Only an all-digit token can have failed by being too large.
                let kind = if !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) {
                    "an integer below 2^32"
                } else {
                    "a non-negative integer"
                };
                Err(self.error_at(
                    &t,
                    format!("expected {what} ({kind}), found {}", self.show(&t)),
                ))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// Every token with its text, line and column, read through a buffer of `bytes`,
    /// from a reader that hands out at most `chunk` bytes a read.
    fn tokens(src: &[u8], bytes: usize, chunk: usize) -> Vec<(String, u32, u32)> {
        struct Dribble<'a>(&'a [u8], usize);
        impl Read for Dribble<'_> {
            fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
                let n = self.0.len().min(out.len()).min(self.1);
                out[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                Ok(n)
            }
        }
        let input = Input {
            reader: Box::new(Dribble(src, chunk)),
            len: Some(src.len() as u64),
        };
        let mut lx = Lexer::with_buffer(input, "t", bytes);
        let mut out = Vec::new();
        while let Some(t) = lx.next_token().unwrap() {
            let text = String::from_utf8_lossy(lx.text(&t)).into_owned();
            out.push((text, t.line, t.col));
        }
        out
    }

    #[test]
    fn tokens_carry_line_and_column_through_crlf_lone_cr_and_comments() {
        // Line 1 ends in CRLF, line 2 is a comment ending in CRLF, line 3 ends in a lone CR,
        // line 4 has a comment that must stop at the lone CR ending it.
        let src = b"b 1 2\r\n# note\r\n  s\r3 # tail\r4";
        let want = [
            ("b", 1, 1),
            ("1", 1, 3),
            ("2", 1, 5),
            ("s", 3, 3),
            ("3", 4, 1),
            ("4", 5, 1),
        ];
        let got = tokens(src, BUFFER_BYTES, usize::MAX);
        let got: Vec<_> = got.iter().map(|(s, l, c)| (s.as_str(), *l, *c)).collect();
        assert_eq!(got, want);
    }

    /// Through buffers barely larger than the longest token and reads of one byte and
    /// up, every token, line and column comes out as from one buffer holding everything:
    /// tokens, comments and CRLF pairs cut by the buffer's end at every offset.
    #[test]
    fn small_buffers_and_short_reads_give_the_same_tokens() {
        let mut src = Vec::new();
        src.extend_from_slice(BOM);
        for i in 0..40 {
            let line: &[u8] = match i % 5 {
                0 => b"s 1.25 -3e2 4\r\n",
                1 => b"# a comment that is longer than the buffers\r",
                2 => b"pp 3\t0.5 0.5 0.5 1 2 3#c\n",
                3 => b"\r\n\x0b\x0c  v from 0 0 0\r\r",
                _ => b"longtoken_0123456789 x\n",
            };
            src.extend_from_slice(line);
        }
        src.extend_from_slice(b"last");
        let whole = tokens(&src, src.len() + 1, usize::MAX);
        assert_eq!(whole.len(), 8 * (4 + 8 + 5 + 2) + 1);
        assert_eq!(whole[0], ("s".into(), 1, 1), "columns count after the BOM");
        for bytes in [24, 25, 31, 64] {
            for chunk in [1, 2, 3, 7, usize::MAX] {
                let got = tokens(&src, bytes, chunk);
                assert_eq!(got, whole, "buffer {bytes}, reads of {chunk}");
            }
        }
    }

    #[test]
    fn a_token_longer_than_the_limit_is_an_error_at_its_start() {
        let mut src = b"s 1\n  ".to_vec();
        src.extend(std::iter::repeat_n(b'x', MAX_TOKEN_BYTES + 1));
        let mut lx = Lexer::new(&src, "t");
        lx.next_token().unwrap();
        lx.next_token().unwrap();
        let e = lx.next_token().unwrap_err().to_string();
        assert!(e.starts_with("t:2:3: a token longer than"), "{e}");
        // One byte shorter is a token.
        let mut lx = Lexer::new(&src[..src.len() - 1], "t");
        lx.next_token().unwrap();
        lx.next_token().unwrap();
        let t = lx.next_token().unwrap().unwrap();
        assert_eq!(lx.text(&t).len(), MAX_TOKEN_BYTES);
    }

    #[test]
    fn the_current_line_is_kept_for_messages() {
        let src = b"s 0 0 0 1\nsphere 1 2 3\n";
        let mut lx = Lexer::new(src, "t");
        for _ in 0..6 {
            lx.next_token().unwrap();
        }
        assert_eq!(lx.line_text(), (&b"sphere 1 2 3"[..], 1));
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
