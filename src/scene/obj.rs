//! Wavefront OBJ reader: positions (`v`), normals (`vn`) and faces (`f`); polygons are
//! triangulated by our ear clipper. Every other statement (`vt`, `o`, `g`, `s`, `usemtl`,
//! `mtllib`, `l`, `p`, ...) is skipped: materials come from the `mesh` statement's `f`.
//!
//! Written on our tokenizer rather than with `tobj` for two reasons: errors point at a line
//! and column like every other reader's, and a face whose corners lack `vn` indices must get
//! no shading normals (tobj makes up normals for them by repeating the previous index).

use glam::Vec3;

use super::lex::{Lexer, Token, parse_f32};
use super::model::{MaterialId, Mesh, Triangle, unit};
use super::triangulate::triangulate;
use crate::error::Result;

/// One face corner: 0-based position and normal indices (not yet checked against the
/// arrays, since a face may refer to vertices defined later), and where it was written.
struct Corner {
    v: i64,
    n: Option<i64>,
    line: u32,
    col: u32,
}

/// The triangles of an OBJ file (see `parse_with_warnings` for what is dropped).
pub fn parse(bytes: &[u8], name: &str) -> Result<Vec<Triangle>> {
    parse_with_warnings(bytes, name).map(|m| m.triangles)
}

/// The triangles of an OBJ file, and a warning for each face dropped because it has fewer
/// than three corners or no area (as the NFF reader warns of degenerate polygons).
pub fn parse_with_warnings(bytes: &[u8], name: &str) -> Result<Mesh> {
    let mut lx = Lexer::new(bytes, name);
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut corners: Vec<Corner> = Vec::new();
    // Start of each face in `corners`.
    let mut faces: Vec<usize> = Vec::new();

    while let Some(t) = lx.next_token() {
        let line = t.line;
        let mut last = t;
        match t.text {
            b"v" | b"vn" => {
                let what = if t.text == b"v" {
                    "vertex coordinate"
                } else {
                    "normal coordinate"
                };
                let mut p = [0.0f32; 3];
                for c in &mut p {
                    *c = number_on_line(&mut lx, &mut last, what)?;
                }
                if t.text == b"v" {
                    positions.push(Vec3::from(p));
                } else {
                    normals.push(Vec3::from(p));
                }
                // `v x y z w` and `v x y z r g b` (vertex colours): the rest is ignored.
                skip_line(&mut lx, line);
            }
            b"f" | b"fo" => {
                faces.push(corners.len());
                while let Some(c) = token_on_line(&mut lx, line) {
                    corners.push(corner(&lx, &c, positions.len(), normals.len())?);
                }
            }
            _ => skip_line(&mut lx, line),
        }
    }

    let at = |c: &Corner, msg: String| {
        lx.error_at(
            &Token {
                text: b"",
                line: c.line,
                col: c.col,
            },
            msg,
        )
    };
    let mut tris = Vec::new();
    let mut warnings = Vec::new();
    let mut poly = Vec::new();
    let mut poly_n = Vec::new();
    let mut idx = Vec::new();
    for (k, &start) in faces.iter().enumerate() {
        let end = faces.get(k + 1).copied().unwrap_or(corners.len());
        let face = &corners[start..end];
        poly.clear();
        poly_n.clear();
        for c in face {
            let p = usize::try_from(c.v).ok().and_then(|i| positions.get(i));
            let Some(&p) = p else {
                return Err(at(
                    c,
                    format!(
                        "face corner refers to a vertex that does not exist (the file has {})",
                        positions.len()
                    ),
                ));
            };
            poly.push(p);
            if let Some(n) = c.n {
                let Some(&n) = usize::try_from(n).ok().and_then(|i| normals.get(i)) else {
                    return Err(at(
                        c,
                        format!(
                            "face corner refers to a normal that does not exist (the file has {})",
                            normals.len()
                        ),
                    ));
                };
                poly_n.push(unit(n).unwrap_or(Vec3::ZERO));
            }
        }
        // Shading normals only when every corner has a usable one; otherwise flat.
        let smooth = poly_n.len() == poly.len() && poly_n.iter().all(|n| n.length_squared() > 0.0);
        idx.clear();
        if poly.len() < 3 || !triangulate(&poly, &mut idx) {
            let (line, col) = face.first().map_or((0, 0), |c| (c.line, c.col));
            warnings.push(format!(
                "{name}:{line}:{col}: degenerate face with {} corners dropped",
                poly.len()
            ));
            continue;
        }
        for &[a, b, c] in &idx {
            let ix = [a, b, c].map(|i| i as usize);
            tris.push(Triangle {
                v: ix.map(|i| poly[i]),
                n: smooth.then(|| Box::new(ix.map(|i| poly_n[i]))),
                material: MaterialId(0),
            });
        }
    }
    Ok(Mesh {
        triangles: tris,
        warnings,
    })
}

/// The next token if it is on `line` (OBJ statements end at the end of their line).
fn token_on_line<'a>(lx: &mut Lexer<'a>, line: u32) -> Option<Token<'a>> {
    match lx.peek() {
        Some(t) if t.line == line => lx.next_token(),
        _ => None,
    }
}

fn skip_line(lx: &mut Lexer, line: u32) {
    while token_on_line(lx, line).is_some() {}
}

/// A finite number on the current line; `last` is the statement's latest token, used to
/// point just past it when the line ends too early.
fn number_on_line<'a>(lx: &mut Lexer<'a>, last: &mut Token<'a>, what: &str) -> Result<f32> {
    let Some(t) = token_on_line(lx, last.line) else {
        let end = Token {
            text: b"",
            line: last.line,
            col: last.col + last.text.len() as u32,
        };
        return Err(lx.error_at(&end, format!("expected {what}, found end of line")));
    };
    *last = t;
    match parse_f32(t.text) {
        Some(v) if v.is_finite() => Ok(v),
        _ => Err(lx.error_at(
            &t,
            format!("expected {what} (a finite number), found {}", t.show()),
        )),
    }
}

/// A face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`. Negative indices count back from the
/// last vertex (or normal) defined so far; texture indices are ignored.
fn corner(lx: &Lexer, t: &Token, n_pos: usize, n_nrm: usize) -> Result<Corner> {
    let bad = || {
        lx.error_at(
            t,
            format!(
                "expected a face corner (v, v/vt, v//vn or v/vt/vn with non-zero integers), found {}",
                t.show()
            ),
        )
    };
    let mut parts = t.text.split(|&b| b == b'/');
    let resolve = |s: &[u8], defined: usize| -> Option<i64> {
        let i: i64 = std::str::from_utf8(s).ok()?.parse().ok()?;
        match i {
            0 => None,
            i if i > 0 => Some(i - 1),
            i => Some(defined as i64 + i),
        }
    };
    let v = resolve(parts.next().unwrap_or_default(), n_pos).ok_or_else(bad)?;
    let _texture = parts.next();
    let n = match parts.next() {
        None | Some(b"") => None,
        Some(s) => Some(resolve(s, n_nrm).ok_or_else(bad)?),
    };
    if parts.next().is_some() {
        return Err(bad());
    }
    Ok(Corner {
        v,
        n,
        line: t.line,
        col: t.col,
    })
}
