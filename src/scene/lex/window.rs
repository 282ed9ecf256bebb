//! The lexer's window on its input: a buffer of fixed size that the stream is read into as
//! tokens are taken from it, with the line and column of where it stands. It skips blanks
//! and comments and finds where tokens end; `Lexer` makes tokens and messages of what it
//! finds. Apart from the lexer because keeping the buffer's bookkeeping right (what may
//! be dropped, what a refill moves) is its own job.

use std::io::Read;

use crate::scene::io::{Input, read_error};
use crate::util::error::{Error, Excerpt, Result};

/// One whitespace-separated token and where it starts (1-based line and column). Its
/// bytes are the lexer's (`Lexer::text`), there until the lexer reads past them.
#[derive(Clone, Copy, Debug)]
pub struct Token {
    pub line: u32,
    pub col: u32,
    /// Offset of its first byte in the stream, and its length.
    pub(super) at: u64,
    pub(super) len: u32,
}

/// The stream offset of a `Token::position`, which has none.
const NOWHERE: u64 = u64::MAX;

impl Token {
    /// A position without text, for messages that point between tokens; its message
    /// quotes no line.
    pub fn position(line: u32, col: u32) -> Token {
        Token {
            line,
            col,
            at: NOWHERE,
            len: 0,
        }
    }

    /// The place just past the token (where a statement cut short ends).
    pub fn after(&self) -> Token {
        Token {
            line: self.line,
            col: self.end_col(),
            at: self.at.saturating_add(u64::from(self.len)),
            len: 0,
        }
    }

    /// The column just past the token's last byte.
    pub fn end_col(&self) -> u32 {
        self.col.saturating_add(self.len)
    }
}

/// The UTF-8 byte-order mark.
pub const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Bytes of the current line kept in the buffer before the token being read, so that a
/// message can quote the line (a longer line is quoted from nearer the token).
pub const LINE_KEPT: usize = 4 << 10;

/// The least room a refill reads into without first dropping what was read before.
const MIN_READ: usize = 16 << 10;

/// Bytes that end a token: ASCII whitespace (including vertical tab and form feed) and `#`.
const fn delimiters() -> [bool; 256] {
    let mut t = [false; 256];
    let ends = b" \t\n\r\x0b\x0c#";
    let mut i = 0;
    while i < ends.len() {
        t[ends[i] as usize] = true;
        i += 1;
    }
    t
}
pub(super) static DELIMITER: [bool; 256] = delimiters();

pub(super) struct Window<'a> {
    src: Box<dyn Read + 'a>,
    pub(super) buf: Box<[u8]>,
    /// Next byte to read, and the end of the bytes read into `buf`.
    pub(super) pos: usize,
    pub(super) end: usize,
    /// The input has ended (no bytes after `end`).
    pub(super) eof: bool,
    /// Stream offset of `buf[0]`.
    pub(super) base: u64,
    pub(super) line: u32,
    /// Stream offset of the current line's first byte.
    pub(super) line_start: u64,
    /// Inside a comment that the buffer's end cut (skipping resumes in it).
    in_comment: bool,
    /// The byte-order mark has been looked for.
    started: bool,
    /// Bytes in the whole input, when known.
    pub(super) len: Option<u64>,
    pub(super) name: &'a str,
}

impl<'a> Window<'a> {
    pub(super) fn new(input: Input<'a>, name: &'a str, bytes: usize) -> Self {
        Window {
            src: input.reader,
            buf: vec![0; bytes].into_boxed_slice(),
            pos: 0,
            end: 0,
            eof: false,
            base: 0,
            line: 1,
            line_start: 0,
            in_comment: false,
            started: false,
            len: input.len,
            name,
        }
    }

    /// A token of `len` bytes from buffer index `start`, on the current line.
    pub(super) fn token_at(&self, start: usize, len: usize) -> Token {
        let at = self.base + start as u64;
        Token {
            line: self.line,
            col: (at - self.line_start).min(u32::MAX as u64 - 1) as u32 + 1,
            at,
            len: len as u32,
        }
    }

    pub(super) fn error_at(&self, tok: &Token, msg: impl Into<String>) -> Error {
        Error::Parse {
            file: self.name.to_string(),
            line: tok.line,
            col: tok.col,
            msg: msg.into(),
            excerpt: self.excerpt(tok).map(Box::new),
        }
    }

    /// `tok`'s line as the buffer holds it: from its start (or from `LINE_KEPT` bytes
    /// before the token, marked as cut, for a longer line) to its end or as far as has
    /// been read. `None` where the buffer no longer holds the token's place.
    fn excerpt(&self, tok: &Token) -> Option<Excerpt> {
        let i = usize::try_from(tok.at.checked_sub(self.base)?).ok()?;
        if tok.at == NOWHERE || i > self.end {
            return None;
        }
        let line_start = tok.at.saturating_sub(u64::from(tok.col) - 1);
        let from = (line_start.max(self.base) - self.base) as usize;
        let len = (tok.len as usize).min(self.end - i);
        let mut x = Excerpt::of_line(&self.buf[from..self.end], i - from, len);
        if line_start < self.base && !x.text.starts_with("...") {
            x.text.insert_str(0, "...");
            x.span = x.span.start + 3..x.span.end + 3;
        }
        Some(x)
    }

    /// Reads more input after `end`, first dropping the bytes before buffer index `keep`
    /// (but the current line's start when it is near) when the room after `end` is
    /// short. False at the end of the input.
    fn refill(&mut self, keep: usize) -> Result<bool> {
        if self.eof {
            return Ok(false);
        }
        let near = LINE_KEPT.min(self.buf.len() / 2);
        let from = match self.line_start.checked_sub(self.base) {
            Some(l) if (l as usize) <= keep && keep - l as usize <= near => l as usize,
            _ => keep,
        };
        // Bytes already read stay while there is room to read after them, so that a
        // message about an earlier token (the `v` of a degenerate view) can still quote
        // its line: a file that fits the buffer is never moved.
        if from > 0 && self.buf.len() - self.end < MIN_READ {
            self.buf.copy_within(from..self.end, 0);
            self.end -= from;
            self.pos -= from;
            self.base += from as u64;
        }
        if self.end == self.buf.len() {
            // Only a token as long as the buffer fills it (`MAX_TOKEN_BYTES` is shorter).
            let tok = self.token_at(keep - from, 0);
            let msg = format!("a token longer than {} bytes", self.buf.len());
            return Err(self.error_at(&tok, msg));
        }
        loop {
            match self.src.read(&mut self.buf[self.end..]) {
                Ok(0) => break,
                Ok(n) => {
                    self.end += n;
                    return Ok(true);
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(read_error(self.name, e)),
            }
        }
        self.eof = true;
        Ok(false)
    }

    /// Skips a leading UTF-8 byte-order mark (which some editors write), so that columns
    /// on the first line count from the first visible character.
    fn start(&mut self) -> Result<()> {
        self.started = true;
        while self.end < BOM.len() && self.refill(0)? {}
        if self.buf[..self.end].starts_with(BOM) {
            self.pos = BOM.len();
            self.line_start = BOM.len() as u64;
        }
        Ok(())
    }

    /// Skips whitespace and comments, reading on as needed. A line ends at `\n`, `\r\n` or
    /// a lone `\r` (old Mac files), so line numbers in messages match what an editor shows
    /// for all three.
    pub(super) fn skip_space(&mut self) -> Result<()> {
        if !self.started {
            self.start()?;
        }
        loop {
            let (mut pos, end) = (self.pos, self.end);
            let mut line = self.line;
            let mut line_start = self.line_start;
            let buf = &self.buf[..end];
            if self.in_comment {
                match memchr::memchr2(b'\n', b'\r', &buf[pos..]) {
                    Some(k) => {
                        pos += k;
                        self.in_comment = false;
                    }
                    None => pos = end,
                }
            }
            let mut done = false;
            while pos < end {
                match buf[pos] {
                    b' ' | b'\t' | 0x0b | 0x0c => pos += 1,
                    b'\n' => {
                        pos += 1;
                        line = line.saturating_add(1);
                        line_start = self.base + pos as u64;
                    }
                    b'\r' => {
                        if pos + 1 == end && !self.eof {
                            // Whether a `\n` follows is in the next read.
                            break;
                        }
                        pos += 1;
                        // In CRLF the `\n` that follows counts the line.
                        if buf.get(pos) != Some(&b'\n') {
                            line = line.saturating_add(1);
                            line_start = self.base + pos as u64;
                        }
                    }
                    b'#' => match memchr::memchr2(b'\n', b'\r', &buf[pos..]) {
                        Some(k) => pos += k,
                        None => {
                            pos = end;
                            self.in_comment = true;
                        }
                    },
                    _ => {
                        done = true;
                        break;
                    }
                }
            }
            (self.pos, self.line, self.line_start) = (pos, line, line_start);
            // At the end of the input, once more if a `\r` waits for its verdict.
            if done || (!self.refill(pos)? && self.pos >= self.end) {
                return Ok(());
            }
        }
    }

    /// Scans the token at `pos` (after `skip_space`), reading on until it ends; tokens
    /// longer than `max` bytes are an error.
    pub(super) fn scan(&mut self, max: usize) -> Result<Option<Token>> {
        loop {
            let start = self.pos;
            if start >= self.end {
                return Ok(None);
            }
            let ended = self.buf[start..self.end]
                .iter()
                .position(|&b| DELIMITER[b as usize]);
            let len = match ended {
                Some(len) => len,
                None if self.eof => self.end - start,
                None => {
                    if self.end - start > max {
                        let tok = self.token_at(start, 0);
                        let msg = format!("a token longer than {max} bytes (is this a text file?)");
                        return Err(self.error_at(&tok, msg));
                    }
                    self.refill(start)?;
                    continue;
                }
            };
            self.pos = start + len;
            return Ok(Some(self.token_at(start, len)));
        }
    }

    /// The common case of `skip_space` and `scan`, for the hot loops: blanks and `\n`
    /// only, then a token that ends before the buffer does. Returns the token's start and
    /// length in the buffer, having consumed it; `None` (having consumed nothing) for
    /// everything else, which the general path takes.
    #[inline]
    pub(super) fn quick_token(&mut self) -> Option<(usize, usize)> {
        if self.in_comment || !self.started {
            return None;
        }
        let buf = &self.buf[..self.end];
        let (mut pos, mut line, mut line_start) = (self.pos, self.line, self.line_start);
        loop {
            match buf.get(pos)? {
                b' ' | b'\t' => pos += 1,
                b'\n' => {
                    pos += 1;
                    line = line.saturating_add(1);
                    line_start = self.base + pos as u64;
                }
                &b if DELIMITER[b as usize] => return None,
                _ => break,
            }
        }
        let len = buf[pos..].iter().position(|&b| DELIMITER[b as usize])?;
        (self.pos, self.line, self.line_start) = (pos + len, line, line_start);
        Some((pos, len))
    }

    /// The bytes of `tok` while they are in the buffer (empty once dropped).
    pub(super) fn text(&self, tok: &Token) -> &[u8] {
        match tok.at.checked_sub(self.base) {
            Some(i) if i as usize + tok.len as usize <= self.end => {
                &self.buf[i as usize..i as usize + tok.len as usize]
            }
            _ => b"",
        }
    }

    /// The stream after the end of the current line (its `\n`), and its offset: for a
    /// text header followed by binary data. `None` when the input ends before a `\n`.
    pub(super) fn rest_after_line(mut self) -> Result<Option<(Box<dyn Read + 'a>, u64)>> {
        loop {
            if let Some(k) = memchr::memchr(b'\n', &self.buf[self.pos..self.end]) {
                let from = self.pos + k + 1;
                let offset = self.base + from as u64;
                let held = std::io::Cursor::new(self.buf[from..self.end].to_vec());
                return Ok(Some((Box::new(held.chain(self.src)), offset)));
            }
            self.pos = self.end;
            if !self.refill(self.pos)? {
                return Ok(None);
            }
        }
    }

    /// See `Lexer::line_text`.
    pub(super) fn line_text(&self) -> (&[u8], u32) {
        let first = self.line_start.max(self.base);
        let from = ((first - self.base) as usize).min(self.end);
        let to = self.buf[from..self.end]
            .iter()
            .position(|&b| b == b'\n' || b == b'\r')
            .map_or(self.end, |k| from + k);
        let col = (first - self.line_start).min(u32::MAX as u64 - 1) as u32 + 1;
        (&self.buf[from..to], col)
    }
}
