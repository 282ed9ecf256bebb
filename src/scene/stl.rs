//! STL reader, binary and ASCII, detected by content.
//!
//! Written here rather than with `stl_io` because errors must point at a line and column
//! (ASCII) or a byte offset (binary), and because a binary file may begin with the word
//! `solid`. A file is read as ASCII only when it starts with `solid`, its size does not match
//! the binary `84 + 50 * count`, and it holds no control bytes (a binary file with a `solid`
//! header and a wrong count is then still reported as a broken binary file). Non-zero facet
//! normals are kept as the triangle's shading normal.

use glam::Vec3;

use super::lex::Lexer;
use super::model::{MaterialId, Triangle, unit};
use crate::error::{Error, Result};

pub fn parse(bytes: &[u8], name: &str) -> Result<Vec<Triangle>> {
    if binary_size_matches(bytes) || !starts_with_solid(bytes) || !looks_like_text(bytes) {
        parse_binary(bytes, name)
    } else {
        parse_ascii(bytes, name)
    }
}

/// True when every byte could appear in an ASCII STL: no NUL or other control bytes except
/// whitespace. Binary STLs almost always hold a zero byte (the count's high byte, or a
/// coordinate's), so this separates them from text that merely has the wrong size.
fn looks_like_text(b: &[u8]) -> bool {
    b.iter()
        .all(|&c| c >= 0x20 || matches!(c, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c))
}

fn binary_size_matches(b: &[u8]) -> bool {
    b.len() >= 84
        && 84 + 50 * u32::from_le_bytes(b[80..84].try_into().unwrap()) as u64 == b.len() as u64
}

fn starts_with_solid(b: &[u8]) -> bool {
    let b = b.strip_prefix(super::lex::BOM).unwrap_or(b);
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    b[start..].starts_with(b"solid")
}

fn facet_normal(n: Vec3) -> Option<Box<[Vec3; 3]>> {
    unit(n).map(|n| Box::new([n; 3]))
}

fn parse_binary(b: &[u8], name: &str) -> Result<Vec<Triangle>> {
    let err = |offset: usize, msg: String| Error::Binary {
        file: name.to_string(),
        offset: offset as u64,
        msg,
    };
    if b.len() < 84 {
        return Err(err(
            b.len(),
            format!(
                "expected an 84-byte binary STL header, found {} bytes (and no ASCII 'solid')",
                b.len()
            ),
        ));
    }
    let count = u32::from_le_bytes(b[80..84].try_into().unwrap()) as u64;
    let need = 84 + 50 * count;
    let len = b.len() as u64;
    if len < need {
        // Truncated (or a count that is too large): point at where the data stops.
        let whole = (len - 84) / 50;
        return Err(err(
            b.len(),
            format!(
                "file ends inside triangle {} of {count}: the header's count needs {need} bytes, the file has {len}",
                whole + 1
            ),
        ));
    }
    if len > need {
        // A count that is too small: point at the count itself.
        return Err(err(
            80,
            format!("header says {count} triangles ({need} bytes), but the file has {len} bytes"),
        ));
    }
    let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let v3 = |o: usize| Vec3::new(f(o), f(o + 4), f(o + 8));
    let mut tris = Vec::with_capacity(count as usize);
    for i in 0..count as usize {
        let o = 84 + 50 * i;
        let v = [v3(o + 12), v3(o + 24), v3(o + 36)];
        if !v.iter().all(|p| p.is_finite()) {
            return Err(err(
                o + 12,
                format!("triangle {} has a non-finite vertex", i + 1),
            ));
        }
        tris.push(Triangle {
            v,
            n: facet_normal(v3(o)),
            material: MaterialId(0),
        });
    }
    Ok(tris)
}

fn parse_ascii(b: &[u8], name: &str) -> Result<Vec<Triangle>> {
    let mut lx = Lexer::new(b, name);
    let mut tris = Vec::new();
    // Keywords are ASCII literals; quoting them is only done when there is an error.
    let expect = |lx: &mut Lexer, word: &'static str| -> Result<()> {
        let t = lx.expect_token(&format_args!("'{word}'"))?;
        if t.text == word.as_bytes() {
            Ok(())
        } else {
            Err(lx.error_at(&t, format!("expected '{word}', found {}", t.show())))
        }
    };
    let skip_rest_of_line = |lx: &mut Lexer, line: u32| {
        while lx.peek().is_some_and(|t| t.line == line) {
            lx.next_token();
        }
    };
    while let Some(t) = lx.next_token() {
        if t.text != b"solid" {
            return Err(lx.error_at(&t, format!("expected 'solid', found {}", t.show())));
        }
        skip_rest_of_line(&mut lx, t.line); // the solid's name
        loop {
            let t = lx.expect_token("'facet' or 'endsolid'")?;
            match t.text {
                b"endsolid" => {
                    skip_rest_of_line(&mut lx, t.line);
                    break;
                }
                b"facet" => {
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
                    tris.push(Triangle {
                        v,
                        n: facet_normal(n),
                        material: MaterialId(0),
                    });
                }
                _ => {
                    return Err(lx.error_at(
                        &t,
                        format!("expected 'facet' or 'endsolid', found {}", t.show()),
                    ));
                }
            }
        }
    }
    Ok(tris)
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
