//! STL reader, binary and ASCII, detected by content.
//!
//! Written here rather than with `stl_io` because errors must point at a line and column
//! (ASCII) or a byte offset (binary), and because a binary file may begin with the word
//! `solid`. A file is read as ASCII only when it starts with `solid`, its size does not match
//! the binary `84 + 50 * count`, and it holds no control bytes (a binary file with a `solid`
//! header and a wrong count is then still reported as a broken binary file). Non-zero facet
//! normals are kept as the triangle's shading normal.
//!
//! Both forms are read as a stream. Which one a file is, is told from its first
//! `HEAD_BYTES` (all of a file that short, so the rule above holds exactly) and its size
//! when that is known before reading (a plain file; a gzip file's is not): a longer file
//! that starts like ASCII text is read as ASCII, and control bytes further on are then an
//! error at their line and column.

use std::io::{BufReader, Read};

use glam::Vec3;

use super::io::Input;
use super::lex::Lexer;
use super::model::{MaterialId, Triangle, unit};
use super::sink::{Collect, Sink};
use crate::util::error::{Error, Result};
use crate::util::limits::MAX_PRIMITIVES;

/// The triangles of an STL file's bytes (gzip-compressed or not).
pub fn parse(bytes: &[u8], name: &str) -> Result<Vec<Triangle>> {
    let mut tris = Collect::default();
    read(Input::bytes(bytes), name, &mut tris, (MaterialId(0), None))?;
    Ok(tris.into_triangles())
}

/// How much of a file's start is looked at to tell binary from ASCII.
const HEAD_BYTES: usize = 64 << 10;

/// Reads an STL file's triangles, of `material`, into `sink` as they are read, through a
/// window of `window` bytes where given (`ReadOptions::window`).
pub fn read(
    mut input: Input,
    name: &str,
    sink: &mut dyn Sink,
    (material, window): (MaterialId, Option<usize>),
) -> Result<()> {
    let io = |e| super::io::read_error(name, e);
    let mut head = Vec::with_capacity(HEAD_BYTES);
    (&mut input.reader)
        .take(HEAD_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(io)?;
    // All of the file when it is shorter than what was asked for.
    let len = input
        .len
        .or((head.len() < HEAD_BYTES).then_some(head.len() as u64));
    let binary = len.is_some_and(|len| binary_size_matches(&head, len))
        || !starts_with_solid(&head)
        || !looks_like_text(&head);
    let rest = std::io::Cursor::new(head).chain(input.reader);
    if binary {
        let rest = BufReader::with_capacity(window.unwrap_or(256 << 10), rest);
        read_binary(rest, len, name, sink, material)
    } else {
        let input = Input {
            reader: Box::new(rest),
            len,
        };
        read_ascii(Lexer::through(input, name, window), sink, material)
    }
}

/// True when every byte could appear in an ASCII STL: no NUL or other control bytes except
/// whitespace. Binary STLs almost always hold a zero byte (the count's high byte, or a
/// coordinate's), so this separates them from text that merely has the wrong size.
fn looks_like_text(b: &[u8]) -> bool {
    b.iter()
        .all(|&c| c >= 0x20 || matches!(c, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c))
}

/// Whether a file of `len` bytes that starts with `head` has the binary size for the
/// count in its header.
fn binary_size_matches(head: &[u8], len: u64) -> bool {
    head.len() >= 84 && 84 + 50 * u32::from_le_bytes(head[80..84].try_into().unwrap()) as u64 == len
}

fn starts_with_solid(b: &[u8]) -> bool {
    let b = b.strip_prefix(super::lex::BOM).unwrap_or(b);
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    b[start..].starts_with(b"solid")
}

fn facet_normal(n: Vec3) -> Option<[Vec3; 3]> {
    unit(n).map(|n| [n; 3])
}

/// Fills `buf` from `r` as far as it goes: the bytes read (fewer only at the end).
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// A binary STL, its size `len` when known before reading: a size that disagrees with
/// the header's count is reported before any triangle is read, as for a file in memory;
/// otherwise where the stream shows it.
fn read_binary(
    mut r: impl Read,
    len: Option<u64>,
    name: &str,
    sink: &mut dyn Sink,
    material: MaterialId,
) -> Result<()> {
    let err = |offset: u64, msg: String| Error::Binary {
        file: name.to_string(),
        offset,
        msg,
    };
    let io = |e| super::io::read_error(name, e);
    let mut header = [0u8; 84];
    let got = read_full(&mut r, &mut header).map_err(io)?;
    if got < 84 {
        return Err(err(
            got as u64,
            format!(
                "expected an 84-byte binary STL header, found {got} bytes (and no ASCII 'solid')"
            ),
        ));
    }
    let count = u32::from_le_bytes(header[80..84].try_into().unwrap()) as u64;
    let need = 84 + 50 * count;
    // Truncated (or a count that is too large): point at where the data stops.
    let truncated = |len: u64| {
        let whole = (len - 84) / 50;
        err(
            len,
            format!(
                "file ends inside triangle {} of {count}: the header's count needs {need} bytes, the file has {len}",
                whole + 1
            ),
        )
    };
    // A count that is too small: point at the count itself.
    let too_long = |len: u64| {
        err(
            80,
            format!("header says {count} triangles ({need} bytes), but the file has {len} bytes"),
        )
    };
    match len {
        Some(len) if len < need => return Err(truncated(len)),
        Some(len) if len > need => return Err(too_long(len)),
        _ => {}
    }
    if sink.count() as u64 + count > MAX_PRIMITIVES as u64 {
        return Err(err(
            80,
            format!("header says {count} triangles, more than the limit of {MAX_PRIMITIVES}"),
        ));
    }
    let f = |b: &[u8], o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let v3 = |b: &[u8], o: usize| Vec3::new(f(b, o), f(b, o + 4), f(b, o + 8));
    let mut rec = [0u8; 50];
    for i in 0..count {
        let got = read_full(&mut r, &mut rec).map_err(io)?;
        let o = 84 + 50 * i;
        if got < 50 {
            return Err(truncated(o + got as u64));
        }
        let v = [v3(&rec, 12), v3(&rec, 24), v3(&rec, 36)];
        if !v.iter().all(|p| p.is_finite()) {
            return Err(err(
                o + 12,
                format!("triangle {} has a non-finite vertex", i + 1),
            ));
        }
        sink.triangle(v, facet_normal(v3(&rec, 0)), None, material);
    }
    // A stream whose size was not known may go on past the count.
    let extra = std::io::copy(&mut r, &mut std::io::sink()).map_err(io)?;
    if extra > 0 {
        return Err(too_long(need + extra));
    }
    Ok(())
}

fn read_ascii(mut lx: Lexer, sink: &mut dyn Sink, material: MaterialId) -> Result<()> {
    // Keywords are ASCII literals; quoting them is only done when there is an error.
    let expect = |lx: &mut Lexer, word: &'static str| -> Result<()> {
        let t = lx.expect_token(&format_args!("'{word}'"))?;
        if lx.text(&t) == word.as_bytes() {
            Ok(())
        } else {
            Err(lx.error_at(&t, format!("expected '{word}', found {}", lx.show(&t))))
        }
    };
    let skip_rest_of_line = |lx: &mut Lexer, line: u32| -> Result<()> {
        while lx.peek()?.is_some_and(|t| t.line == line) {
            lx.next_token()?;
        }
        Ok(())
    };
    while let Some(t) = lx.next_token()? {
        if lx.text(&t) != b"solid" {
            return Err(lx.error_at(&t, format!("expected 'solid', found {}", lx.show(&t))));
        }
        skip_rest_of_line(&mut lx, t.line)?; // the solid's name
        loop {
            let t = lx.expect_token("'facet' or 'endsolid'")?;
            match lx.text(&t) {
                b"endsolid" => {
                    skip_rest_of_line(&mut lx, t.line)?;
                    break;
                }
                b"facet" => {
                    if sink.count() >= MAX_PRIMITIVES {
                        return Err(lx.error_at(
                            &t,
                            format!("more than {MAX_PRIMITIVES} triangles (the limit)"),
                        ));
                    }
                    expect(&mut lx, "normal")?;
                    let n = lx.vec3("facet normal")?;
                    expect(&mut lx, "outer")?;
                    expect(&mut lx, "loop")?;
                    let mut v = [Vec3::ZERO; 3];
                    for p in &mut v {
                        expect(&mut lx, "vertex")?;
                        *p = lx.vec3("vertex coordinate")?;
                    }
                    expect(&mut lx, "endloop")?;
                    expect(&mut lx, "endfacet")?;
                    sink.triangle(v, facet_normal(n), None, material);
                }
                _ => {
                    return Err(lx.error_at(
                        &t,
                        format!("expected 'facet' or 'endsolid', found {}", lx.show(&t)),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Encodes triangles as binary STL (used by tests and to write example meshes).
pub fn write_binary(tris: &[Triangle], header: &[u8; 80]) -> Vec<u8> {
    let mut out = Vec::with_capacity(84 + 50 * tris.len());
    out.extend_from_slice(header);
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        let n = t.n.as_ref().map_or(Vec3::ZERO, |n| n[0]);
        for v in [n, t.v[0], t.v[1], t.v[2]] {
            for c in v.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}
