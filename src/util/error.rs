//! Typed errors. Every error a user can cause names the file and, for text formats, the
//! line and column, so `gpurt` can print `FILE:LINE:COL: message` and exit non-zero; a
//! parse error also carries its line (`Excerpt`), and what an input holds is shown one
//! way in every message (`escape`).

use std::ops::Range;
use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed text input (NFF, ASCII STL, OBJ), with the line it is in as the reader
    /// had it (which the command line shows with a caret under the column).
    #[error("{file}:{line}:{col}: {msg}")]
    Parse {
        file: String,
        line: u32,
        col: u32,
        msg: String,
        excerpt: Option<Box<Excerpt>>,
    },
    /// Malformed binary input (binary STL); the position is a byte offset.
    #[error("{file}: at byte {offset}: {msg}")]
    Binary {
        file: String,
        offset: u64,
        msg: String,
    },
    /// A scene that parsed but cannot be rendered (e.g. a degenerate view).
    #[error("{file}: {msg}")]
    Scene { file: String, msg: String },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("no GPU adapter found{0}")]
    NoAdapter(String),
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("{0}")]
    Image(String),
    /// A library caller's render request that cannot be honoured (a frame the scene's
    /// buffers or an accumulator do not fit).
    #[error("{0}")]
    Render(String),
    /// The viewer found no display to open its window on.
    #[error("cannot open a window: {0}")]
    NoDisplay(String),
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// The line of text an error points into, made printable: at most `EXCERPT_WIDTH` bytes of
/// it around the column (cut ends marked `...`), escaped as `escape` does, tabs and other
/// spacing as single spaces so that the caret stays under the column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Excerpt {
    pub text: String,
    /// Where in `text` the error points: the offending token, or one place.
    pub span: Range<usize>,
}

/// Bytes of a line an excerpt keeps, at most (plus the `...` marks and escapes).
pub const EXCERPT_WIDTH: usize = 100;

impl Excerpt {
    /// The excerpt of `line` (the rest of the input from the line's start: only what is
    /// needed is read, up to the line's end) for `len` bytes from byte `at`.
    pub fn of_line(line: &[u8], at: usize, len: usize) -> Excerpt {
        let end_of_line = line
            .iter()
            .take(at.max(EXCERPT_WIDTH) + EXCERPT_WIDTH)
            .position(|&b| b == b'\n' || b == b'\r')
            .unwrap_or(line.len().min(at.max(EXCERPT_WIDTH) + EXCERPT_WIDTH));
        let at = at.min(end_of_line);
        let boundary = |mut i: usize| {
            while i < end_of_line && (line[i] & 0xC0) == 0x80 {
                i += 1;
            }
            i
        };
        let start = if end_of_line > EXCERPT_WIDTH && at > EXCERPT_WIDTH / 2 {
            boundary(at - EXCERPT_WIDTH / 2).min(at)
        } else {
            0
        };
        let stop = boundary((start + EXCERPT_WIDTH).min(end_of_line)).max(at);
        let shown = |bytes: &[u8]| {
            let spaced: Vec<u8> = bytes
                .iter()
                .map(|&b| {
                    if matches!(b, b'\t' | 0x0b | 0x0c) {
                        b' '
                    } else {
                        b
                    }
                })
                .collect();
            escape(&spaced)
        };
        let mut text = if start > 0 {
            "...".to_string()
        } else {
            String::new()
        };
        text.push_str(&shown(&line[start..at]));
        let from = text.len();
        text.push_str(&shown(&line[at..(at + len).min(stop)]));
        let span = from..text.len().max(from + 1);
        text.push_str(&shown(&line[(at + len).min(stop)..stop]));
        if stop < end_of_line {
            text.push_str("...");
        }
        Excerpt { text, span }
    }
}

/// Text from an input, shown one way in every message: printable UTF-8 as it is, and
/// every other byte (control characters such as an ESC that would recolour the terminal,
/// bytes that are not UTF-8) as `\xNN`.
pub fn escape(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len());
    let hex = |out: &mut String, b: u8| out.push_str(&format!("\\x{b:02x}"));
    for chunk in bytes.utf8_chunks() {
        for c in chunk.valid().chars() {
            if c.is_control() {
                let mut buf = [0; 4];
                c.encode_utf8(&mut buf)
                    .bytes()
                    .for_each(|b| hex(&mut out, b));
            } else {
                out.push(c);
            }
        }
        chunk.invalid().iter().for_each(|&b| hex(&mut out, b));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_are_one_kind_for_controls_and_bad_bytes_alike() {
        assert_eq!(escape(b"ok \xc3\xa9"), "ok \u{e9}");
        assert_eq!(escape(b"\x1b[31m\xff\x07"), "\\x1b[31m\\xff\\x07");
        // U+0085, a control character that is valid UTF-8: its two bytes.
        assert_eq!(escape("a\u{85}".as_bytes()), "a\\xc2\\x85");
    }

    #[test]
    fn excerpts_keep_the_caret_under_the_column_and_cut_long_lines() {
        let x = Excerpt::of_line(b"angle\t200 # c\nnext", 6, 3);
        assert_eq!(x.text, "angle 200 # c");
        assert_eq!(&x.text[x.span.clone()], "200");
        // At the end of the line: one place after it.
        let x = Excerpt::of_line(b"from 0 0\r\n", 8, 0);
        assert_eq!((x.text.as_str(), x.span.clone()), ("from 0 0", 8..9));
        // A line of a million bytes: a window around the column, marked as cut.
        let mut long = vec![b'1'; 1_000_000];
        long[500_000..500_004].copy_from_slice(b"oops");
        let x = Excerpt::of_line(&long, 500_000, 4);
        assert!(
            x.text.starts_with("...") && x.text.ends_with("..."),
            "{}",
            x.text
        );
        assert!(x.text.len() <= EXCERPT_WIDTH + 6);
        assert_eq!(&x.text[x.span.clone()], "oops");
        // Escaped bytes before the column move the span with them.
        let x = Excerpt::of_line(b"\x1b\xff s", 3, 1);
        assert_eq!(x.text, "\\x1b\\xff s");
        assert_eq!(&x.text[x.span.clone()], "s");
    }
}
