//! A byte tokenizer shared by the text readers (NFF, ASCII STL).
//!
//! Token-based rather than line-based: NFF entities may span lines. `\r` (CRLF and lone CR
//! files exist) and every other ASCII space is whitespace; `#` starts a comment to the end of
//! the line. Every token remembers its line and column so errors can point at it.

use std::fmt::Display;

use crate::error::{Error, Excerpt, escape};

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
    let s = escape(&b[..b.len().min(MAX)]);
    if b.len() > MAX {
        format!("'{s}...'")
    } else {
        format!("'{s}'")
    }
}

/// The UTF-8 byte-order mark.
pub const BOM: &[u8] = b"\xEF\xBB\xBF";

pub struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
    line: u32,
    line_start: usize,
    name: &'a str,
}

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
static DELIMITER: [bool; 256] = delimiters();

impl<'a> Lexer<'a> {
    /// A lexer over `src`, skipping a leading UTF-8 byte-order mark (which some editors
    /// write) so that columns on the first line count from the first visible character.
    pub fn new(src: &'a [u8], name: &'a str) -> Self {
        let start = if src.starts_with(BOM) { BOM.len() } else { 0 };
        Lexer {
            src,
            pos: start,
            line: 1,
            line_start: start,
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

    /// Skips whitespace and comments. A line ends at `\n`, `\r\n` or a lone `\r` (old Mac
    /// files), so line numbers in messages match what an editor shows for all three.
    fn skip_space(&mut self) {
        let src = self.src;
        let mut pos = self.pos;
        while let Some(&b) = src.get(pos) {
            match b {
                b' ' | b'\t' | 0x0b | 0x0c => pos += 1,
                b'\n' => {
                    pos += 1;
                    self.line += 1;
                    self.line_start = pos;
                }
                b'\r' => {
                    pos += 1;
                    // In CRLF the `\n` that follows counts the line.
                    if src.get(pos) != Some(&b'\n') {
                        self.line += 1;
                        self.line_start = pos;
                    }
                }
                b'#' => {
                    while pos < src.len() && src[pos] != b'\n' && src[pos] != b'\r' {
                        pos += 1;
                    }
                }
                _ => break,
            }
        }
        self.pos = pos;
    }

    /// The next token, or `None` at the end of the input.
    pub fn next_token(&mut self) -> Option<Token<'a>> {
        self.skip_space();
        let src = self.src;
        let start = self.pos;
        if start >= src.len() {
            return None;
        }
        let len = src[start..]
            .iter()
            .position(|&b| DELIMITER[b as usize])
            .unwrap_or(src.len() - start);
        self.pos = start + len;
        Some(Token {
            text: &src[start..self.pos],
            line: self.line,
            col: (start - self.line_start) as u32 + 1,
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

    /// Error at a token, with the token's line (`Excerpt`).
    pub fn error_at(&self, tok: &Token, msg: impl Into<String>) -> Error {
        // The token lies in `src`: its line starts col - 1 bytes before it.
        let offset = (tok.text.as_ptr() as usize).wrapping_sub(self.src.as_ptr() as usize);
        let inside = offset < self.src.len() && offset + tok.text.len() <= self.src.len();
        let excerpt = inside.then(|| {
            let line_start = offset.saturating_sub(tok.col as usize - 1);
            let at = offset - line_start;
            Box::new(Excerpt::of_line(
                &self.src[line_start..],
                at,
                tok.text.len(),
            ))
        });
        Error::Parse {
            file: self.name.to_string(),
            line: tok.line,
            col: tok.col,
            msg: msg.into(),
            excerpt,
        }
    }

    /// Error at the current position (after skipping whitespace): used at end of input.
    pub fn error_here(&mut self, msg: impl Into<String>) -> Error {
        self.skip_space();
        let at = self.pos - self.line_start;
        Error::Parse {
            file: self.name.to_string(),
            line: self.line,
            col: at as u32 + 1,
            msg: msg.into(),
            excerpt: Some(Box::new(Excerpt::of_line(
                &self.src[self.line_start..],
                at,
                0,
            ))),
        }
    }

    // The `what` arguments below describe the expected value for error messages. They are
    // `Display` rather than `&str` so that hot callers (polygon vertices) can pass a small
    // struct that is only formatted when an error actually happens.

    /// Consumes a token that must exist.
    pub fn expect_token<W: Display + ?Sized>(&mut self, what: &W) -> Result<Token<'a>, Error> {
        match self.next_token() {
            Some(t) => Ok(t),
            None => Err(self.error_here(format!("expected {what}, found end of file"))),
        }
    }

    /// A finite number.
    #[inline]
    pub fn number<W: Display + ?Sized>(&mut self, what: &W) -> Result<f32, Error> {
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

    #[inline]
    pub fn vec3<W: Display + ?Sized>(&mut self, what: &W) -> Result<glam::Vec3, Error> {
        Ok(glam::Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// A non-negative integer count.
    pub fn count<W: Display + ?Sized>(&mut self, what: &W) -> Result<(u32, Token<'a>), Error> {
        let t = self.expect_token(what)?;
        let s = std::str::from_utf8(t.text).unwrap_or("");
        match s.parse::<u32>() {
            Ok(n) => Ok((n, t)),
            Err(_) => {
                // Only an all-digit token can have failed by being too large.
                let kind = if !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) {
                    "an integer below 2^32"
                } else {
                    "a non-negative integer"
                };
                Err(self.error_at(&t, format!("expected {what} ({kind}), found {}", t.show())))
            }
        }
    }
}

/// Exact powers of ten as f64 (all up to 1e22 are exactly representable).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses a number token; `None` when it is not a number at all.
///
/// Gives exactly the `f32` that `str::parse::<f32>` gives (a unit test compares them over
/// many values). Plain decimals, the bulk of every scene, take a fast path; anything else
/// (long mantissas, big exponents, `inf`, `nan`, odd spellings) goes to `str::parse`.
#[inline]
pub fn parse_f32(text: &[u8]) -> Option<f32> {
    match fast_f32(text) {
        Some(v) => Some(v),
        // `str::parse` accepts "inf"/"nan" spelled out; callers reject non-finite values with
        // a message of their own.
        None => std::str::from_utf8(text).ok()?.parse::<f32>().ok(),
    }
}

/// Clinger's fast path, in f64: a mantissa below 2^53 and a power of ten up to 22 are both
/// exact in f64, so one multiplication or division rounds correctly. Rounding that f64 to f32
/// is then the correct f32 too, unless the f64 landed exactly on the midpoint between two
/// f32s (double rounding): that case, and every input the grammar below does not cover,
/// returns `None` for the slow path.
#[inline]
fn fast_f32(t: &[u8]) -> Option<f32> {
    let mut i = 0;
    let neg = match t.first()? {
        b'-' => {
            i = 1;
            true
        }
        b'+' => {
            i = 1;
            false
        }
        _ => false,
    };
    let mut mant: u64 = 0;
    let mut digits = 0usize; // significant digits accumulated (leading zeros excluded)
    let mut any_digit = false;
    let mut exp: i64 = 0;
    // Digits with at most one '.' among them; each digit after it lowers the exponent.
    let mut after_dot = false;
    while let Some(&b) = t.get(i) {
        if b == b'.' && !after_dot {
            after_dot = true;
            i += 1;
            continue;
        }
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        any_digit = true;
        if mant != 0 || d != 0 {
            digits += 1;
        }
        mant = mant.wrapping_mul(10).wrapping_add(d as u64);
        exp -= after_dot as i64;
        i += 1;
    }
    // 15 significant digits stay below 2^53 and cannot have wrapped.
    if !any_digit || digits > 15 {
        return None;
    }
    if let Some(&(b'e' | b'E')) = t.get(i) {
        i += 1;
        let eneg = match t.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let start = i;
        let mut e: i64 = 0;
        while let Some(&b) = t.get(i) {
            let d = b.wrapping_sub(b'0');
            if d > 9 || i - start >= 4 {
                break;
            }
            e = e * 10 + d as i64;
            i += 1;
        }
        if i == start {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if i != t.len() {
        return None;
    }
    let v = if mant == 0 {
        0.0
    } else if (0..=22).contains(&exp) {
        mant as f64 * POW10[exp as usize]
    } else if (-22..0).contains(&exp) {
        mant as f64 / POW10[(-exp) as usize]
    } else {
        return None;
    };
    // f64 -> f32 drops 29 mantissa bits; all values here are normal in both types
    // (1e-22 <= |v| < 1e38). A dropped part of exactly one half is a midpoint.
    if v.to_bits() & ((1 << 29) - 1) == 1 << 28 {
        return None;
    }
    let v = v as f32;
    Some(if neg { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_carry_line_and_column_through_crlf_lone_cr_and_comments() {
        // Line 1 ends in CRLF, line 2 is a comment ending in CRLF, line 3 ends in a lone CR,
        // line 4 has a comment that must stop at the lone CR ending it.
        let src = b"b 1 2\r\n# note\r\n  s\r3 # tail\r4";
        let mut lx = Lexer::new(src, "t");
        let toks: Vec<_> = std::iter::from_fn(|| lx.next_token())
            .map(|t| (String::from_utf8_lossy(t.text).into_owned(), t.line, t.col))
            .collect();
        let want = [
            ("b", 1, 1),
            ("1", 1, 3),
            ("2", 1, 5),
            ("s", 3, 3),
            ("3", 4, 1),
            ("4", 5, 1),
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

    /// The fast path must agree bit for bit with `str::parse`, including the sign of zero,
    /// on every spelling: random decimals of every length, exponents near the fast path's
    /// limits, exact f32 midpoints (where double rounding would go wrong) and junk.
    #[test]
    fn fast_float_path_matches_str_parse_exactly() {
        fn check(s: &str) {
            let want = s.parse::<f32>().ok();
            let got = parse_f32(s.as_bytes());
            assert_eq!(
                got.map(f32::to_bits),
                want.map(f32::to_bits),
                "parse of {s:?}: got {got:?}, str::parse gives {want:?}"
            );
        }
        for s in [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.0",
            "1",
            "1.",
            ".5",
            "-.5",
            "+.5",
            ".",
            "-",
            "+",
            "",
            "e5",
            "1e",
            "1e+",
            "1e-",
            "1E5",
            "1e+5",
            "1e-5",
            "1e0005",
            "1e00005",
            "1.5e-22",
            "1.5e22",
            "9e22",
            "9e23",
            "1e-23",
            "16777216",
            "16777217",
            "16777219",
            "33554435",
            "0.1",
            "0.2",
            "0.3",
            "3.4028235e38",
            "3.4028236e38",
            "1e38",
            "1e39",
            "1e-45",
            "1e-46",
            "1.11022e-16",
            "100000",
            "999999999999999",
            "9999999999999999",
            "0.000000000000000000001",
            "00000000000000000000001",
            "1..2",
            "1.2.3",
            "1e2e3",
            "--1",
            "+-1",
            "0x10",
            "inf",
            "-inf",
            "nan",
            "infinity",
            "NaN",
            "1_0",
            "1 ",
            " 1",
            "1f",
            "١",
        ] {
            check(s);
        }
        // Random decimals: sign, up to 18 integer and fraction digits, optional exponent.
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut s = String::new();
        for _ in 0..300_000 {
            s.clear();
            let r = next();
            match r % 3 {
                0 => s.push('-'),
                1 if r % 7 == 0 => s.push('+'),
                _ => {}
            }
            let int_digits = (next() % 12) as usize;
            let frac_digits = (next() % 12) as usize;
            for _ in 0..int_digits {
                s.push((b'0' + (next() % 10) as u8) as char);
            }
            if frac_digits > 0 || next() % 4 == 0 {
                s.push('.');
            }
            for _ in 0..frac_digits {
                s.push((b'0' + (next() % 10) as u8) as char);
            }
            if next() % 3 == 0 {
                s.push(if next() % 2 == 0 { 'e' } else { 'E' });
                match next() % 3 {
                    0 => s.push('-'),
                    1 => s.push('+'),
                    _ => {}
                }
                s.push_str(&(next() % 40).to_string());
            }
            check(&s);
        }
        // Exact midpoints between neighbouring f32s written out in decimal: the f64 fast
        // path computes them exactly and must defer to the slow path's ties-to-even.
        for i in 0..2000u32 {
            let a = f32::from_bits(0x4B80_0000 + i * 977); // >= 2^24: integers, spacing >= 2
            let mid = (a as f64 + f32::from_bits(a.to_bits() + 1) as f64) / 2.0;
            check(&format!("{mid}"));
            let b = f32::from_bits(0x3F80_0000 + i * 4099); // in [1, 2): spacing 2^-23
            let mid = (b as f64 + f32::from_bits(b.to_bits() + 1) as f64) / 2.0;
            check(&format!("{mid}"));
        }
    }
}
