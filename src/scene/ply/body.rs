//! A PLY file's body, ASCII or binary, read a number at a time as the header describes
//! it, with where each number was (a token's line and column, or a byte offset) for
//! messages.

use std::io::{BufReader, Read};

use super::header::{Element, Kind, Scalar};
use crate::scene::lex::{Lexer, Token, parse_f32};
use crate::util::error::{Error, Result};
use crate::util::limits::MAX_POLYGON_VERTICES;

/// Where a number was read.
#[derive(Clone, Copy, Debug)]
pub enum Pos {
    Token(Token),
    Byte(u64),
}

enum Src<'a> {
    Ascii(Lexer<'a>),
    Binary {
        r: BufReader<Box<dyn Read + 'a>>,
        big: bool,
        /// Stream offset of the next byte, and the stream's length when known.
        at: u64,
        len: Option<u64>,
    },
}

pub struct Body<'a> {
    src: Src<'a>,
    name: &'a str,
    /// Where the latest number was.
    last: Pos,
}

impl<'a> Body<'a> {
    pub fn ascii(lx: Lexer<'a>) -> Self {
        let name = lx.name();
        Body {
            src: Src::Ascii(lx),
            name,
            last: Pos::Byte(0),
        }
    }

    /// The binary body `r`, which starts at stream offset `at` of a stream of `len`
    /// bytes when known; big-endian when `big`.
    pub fn binary(
        r: Box<dyn Read + 'a>,
        (at, len): (u64, Option<u64>),
        big: bool,
        name: &'a str,
        window: Option<usize>,
    ) -> Self {
        let r = BufReader::with_capacity(window.unwrap_or(256 << 10), r);
        Body {
            src: Src::Binary { r, big, at, len },
            name,
            last: Pos::Byte(at),
        }
    }

    /// Bytes left, when the stream's length is known.
    pub fn remaining(&self) -> Option<u64> {
        match &self.src {
            Src::Ascii(lx) => lx.remaining(),
            Src::Binary { at, len, .. } => len.map(|len| len.saturating_sub(*at)),
        }
    }

    pub fn last(&self) -> Pos {
        self.last
    }

    /// An error at a header token (the lexer may be gone: no excerpt).
    pub fn header_error(&self, at: &Token, msg: impl Into<String>) -> Error {
        Error::Parse {
            file: self.name.to_string(),
            line: at.line,
            col: at.col,
            msg: msg.into(),
            excerpt: None,
        }
    }

    pub fn error(&self, at: Pos, msg: impl Into<String>) -> Error {
        match (&self.src, at) {
            (Src::Ascii(lx), Pos::Token(t)) => lx.error_at(&t, msg),
            (_, Pos::Token(t)) => self.header_error(&t, msg),
            (_, Pos::Byte(offset)) => Error::Binary {
                file: self.name.to_string(),
                offset,
                msg: msg.into(),
            },
        }
    }

    /// `FILE:LINE:COL` or `FILE: at byte N`, for warnings.
    pub fn place(&self, at: Pos) -> String {
        match at {
            Pos::Token(t) => format!("{}:{}:{}", self.name, t.line, t.col),
            Pos::Byte(b) => format!("{}: at byte {b}", self.name),
        }
    }

    /// One number of type `s`, property `prop` of element `el`.
    fn value(&mut self, s: Scalar, el: &Element, prop: &str) -> Result<f64> {
        match &mut self.src {
            Src::Ascii(lx) => {
                let what = format_args!("'{prop}' of a '{}' element", el.name);
                let t = lx.expect_token(&what)?;
                self.last = Pos::Token(t);
                let text = lx.text(&t);
                let v = if s.is_integer() {
                    std::str::from_utf8(text)
                        .ok()
                        .and_then(|s| s.parse::<i64>().ok())
                        .map(|i| i as f64)
                } else {
                    parse_f32(text).map(f64::from)
                };
                let kind = if s.is_integer() {
                    "an integer"
                } else {
                    "a number"
                };
                v.ok_or_else(|| {
                    let msg = format!("expected {what} ({kind}), found {}", lx.show(&t));
                    lx.error_at(&t, msg)
                })
            }
            Src::Binary { r, big, at, .. } => {
                let n = s.size() as usize;
                let mut b = [0u8; 8];
                self.last = Pos::Byte(*at);
                if let Err(e) = r.read_exact(&mut b[..n]) {
                    if e.kind() != std::io::ErrorKind::UnexpectedEof {
                        return Err(crate::scene::io::read_error(self.name, e));
                    }
                    return Err(Error::Binary {
                        file: self.name.to_string(),
                        offset: *at,
                        msg: format!("the file ends inside a '{}' element ('{prop}')", el.name),
                    });
                }
                *at += n as u64;
                Ok(decode(&b[..n], s, *big))
            }
        }
    }

    /// A list's length, checked against the polygon limit.
    fn length(&mut self, count: Scalar, el: &Element, prop: &str) -> Result<u32> {
        let n = self.value(count, el, prop)?;
        if !(0.0..=MAX_POLYGON_VERTICES as f64).contains(&n) {
            let msg = format!("a list of {n} items: lengths run from 0 to {MAX_POLYGON_VERTICES}");
            return Err(self.error(self.last, msg));
        }
        Ok(n as u32)
    }

    /// One element's scalar properties into `values` (by property index); its lists
    /// read past.
    pub fn scalars(&mut self, el: &Element, values: &mut [f64]) -> Result<()> {
        for (i, p) in el.props.iter().enumerate() {
            match p.kind {
                Kind::Scalar(s) => values[i] = self.value(s, el, &p.name)?,
                Kind::List { count, item } => {
                    for _ in 0..self.length(count, el, &p.name)? {
                        self.value(item, el, &p.name)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// A face: its scalars into `values` and the vertex indices of list property `list`
    /// into `corners`, each with where it was.
    pub fn face(
        &mut self,
        el: &Element,
        list: usize,
        values: &mut [f64],
        corners: &mut Vec<(u32, Pos)>,
    ) -> Result<()> {
        for (i, p) in el.props.iter().enumerate() {
            match p.kind {
                Kind::Scalar(s) => values[i] = self.value(s, el, &p.name)?,
                Kind::List { count, item } => {
                    for _ in 0..self.length(count, el, &p.name)? {
                        let v = self.value(item, el, &p.name)?;
                        if i != list {
                            continue;
                        }
                        if !(v >= 0.0 && v < u32::MAX as f64 && v.fract() == 0.0) {
                            let msg = format!("vertex index {v} is not a vertex");
                            return Err(self.error(self.last, msg));
                        }
                        corners.push((v as u32, self.last));
                    }
                }
            }
        }
        Ok(())
    }

    /// Checks that nothing follows the last element: data past the counts would mean the
    /// header undercounts, and faces would be lost without a word.
    pub fn finish(self) -> Result<()> {
        match self.src {
            Src::Ascii(mut lx) => match lx.next_token()? {
                None => Ok(()),
                Some(t) => Err(lx.error_at(
                    &t,
                    format!("{} after the last element the header declares", lx.show(&t)),
                )),
            },
            Src::Binary { mut r, at, .. } => {
                let extra = std::io::copy(&mut r, &mut std::io::sink())
                    .map_err(|e| crate::scene::io::read_error(self.name, e))?;
                if extra == 0 {
                    return Ok(());
                }
                Err(Error::Binary {
                    file: self.name.to_string(),
                    offset: at,
                    msg: format!("{extra} bytes after the last element the header declares"),
                })
            }
        }
    }
}

/// A binary number's value.
fn decode(b: &[u8], s: Scalar, big: bool) -> f64 {
    macro_rules! num {
        ($t:ty) => {{
            let a = b.try_into().expect("the type's size");
            if big {
                <$t>::from_be_bytes(a) as f64
            } else {
                <$t>::from_le_bytes(a) as f64
            }
        }};
    }
    match s {
        Scalar::I8 => num!(i8),
        Scalar::U8 => num!(u8),
        Scalar::I16 => num!(i16),
        Scalar::U16 => num!(u16),
        Scalar::I32 => num!(i32),
        Scalar::U32 => num!(u32),
        Scalar::F32 => num!(f32),
        Scalar::F64 => num!(f64),
    }
}
