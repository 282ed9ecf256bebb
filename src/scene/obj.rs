//! Wavefront OBJ reader: positions (`v`), normals (`vn`), texture coordinates (`vt`), faces
//! (`f`) and their materials (`mtllib`, `usemtl`: `mtl`); polygons are triangulated by our
//! ear clipper. Every other statement (`o`, `g`, `s`, `l`, `p`, ...) is skipped.
//!
//! Read as a stream: a face goes to the sink as soon as it is read, when every corner
//! refers to a vertex already defined. A face may refer to vertices defined later, so the
//! first one that does not is held, and every face after it, until the file ends (the
//! triangles keep the file's order either way); the positions and normals are held to
//! the end.
//!
//! Written on our tokenizer rather than with `tobj` for two reasons: errors point at a line
//! and column like every other reader's, and a face whose corners lack `vn` indices must get
//! no shading normals (tobj makes up normals for them by repeating the previous index).

use glam::{Affine2, Vec2, Vec3};

use super::lex::{Lexer, Token};
use super::model::{MaterialId, Mesh, Triangle, unit};
use super::mtl::ObjMaterials;
use super::sink::MeshOut;
use super::triangulate::triangulate;
use crate::util::error::Result;
use crate::util::limits::{MAX_MESH_VERTICES, MAX_POLYGON_VERTICES, MAX_PRIMITIVES};

/// One face corner: 0-based position, texture coordinate and normal indices (not yet
/// checked against the arrays, since a face may refer to vertices defined later), and
/// where it was written.
#[derive(Clone, Copy)]
struct Corner {
    v: i64,
    t: Option<i64>,
    n: Option<i64>,
    /// Where it was written: its line and column, and its bytes for a message to quote
    /// while the reader still holds them.
    at: Token,
}

/// The triangles of an OBJ file (see `parse_with_warnings` for what is dropped).
pub fn parse(bytes: &[u8], name: &str) -> Result<Vec<Triangle>> {
    parse_with_warnings(bytes, name).map(|m| m.triangles)
}

/// The triangles of an OBJ file (material 0; its `.mtl` materials are not read), and a
/// warning for each face dropped because it has fewer than three corners or no area (as
/// the NFF reader warns of degenerate polygons).
pub fn parse_with_warnings(bytes: &[u8], name: &str) -> Result<Mesh> {
    MeshOut::collect(|out| read(Lexer::new(bytes, name), out))
}

/// Reads an OBJ file's triangles into `out`, each with the material its `usemtl` names
/// (`out.default` without one), and a warning for each face dropped.
pub fn read(mut lx: Lexer, out: &mut MeshOut) -> Result<()> {
    let mut materials = ObjMaterials::default();
    // The faces' material, and the map of their texture coordinates onto its texture.
    let mut material = (out.default, Affine2::IDENTITY);
    let mut r = Reader {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        held: Vec::new(),
        faces: Vec::new(),
        face: Vec::new(),
        poly: Vec::new(),
        poly_n: Vec::new(),
        poly_uv: Vec::new(),
        idx: Vec::new(),
    };
    while let Some(t) = lx.next_token()? {
        let line = t.line;
        let mut last = t;
        let text = lx.text(&t);
        let vertex = text == b"v";
        match text {
            b"v" | b"vn" => {
                let (what, defined) = if vertex {
                    ("vertex coordinate", r.positions.len())
                } else {
                    ("normal coordinate", r.normals.len())
                };
                if defined >= MAX_MESH_VERTICES {
                    let what = if vertex { "vertices" } else { "normals" };
                    return Err(lx.error_at(
                        &t,
                        format!("more than {MAX_MESH_VERTICES} {what} (the limit)"),
                    ));
                }
                let mut p = [0.0f32; 3];
                for c in &mut p {
                    *c = lx.number_on_line(&mut last, what)?;
                }
                if vertex {
                    r.positions.push(Vec3::from(p));
                } else {
                    r.normals.push(Vec3::from(p));
                }
                // `v x y z w` and `v x y z r g b` (vertex colours): the rest is ignored.
                lx.skip_line(line)?;
            }
            b"vt" => {
                if r.uvs.len() >= MAX_MESH_VERTICES {
                    return Err(lx.error_at(
                        &t,
                        format!("more than {MAX_MESH_VERTICES} texture coordinates (the limit)"),
                    ));
                }
                // `vt u [v [w]]`: v is 0 where it is not given; w is not read.
                let u = lx.number_on_line(&mut last, "texture coordinate")?;
                let v = if lx.peek()?.is_some_and(|n| n.line == line) {
                    lx.number_on_line(&mut last, "texture coordinate")?
                } else {
                    0.0
                };
                r.uvs.push(Vec2::new(u, v));
                lx.skip_line(line)?;
            }
            b"f" | b"fo" => {
                r.face.clear();
                while let Some(c) = lx.token_on_line(line)? {
                    if r.face.len() as u32 >= MAX_POLYGON_VERTICES {
                        return Err(lx.error_at(
                            &c,
                            format!(
                                "a face with more than {MAX_POLYGON_VERTICES} corners (the limit)"
                            ),
                        ));
                    }
                    let defined = [r.positions.len(), r.uvs.len(), r.normals.len()];
                    let corner = corner(&lx, &c, defined)?;
                    r.face.push(corner);
                }
                if out.sink.count() >= MAX_PRIMITIVES {
                    return Err(lx.error_at(
                        &t,
                        format!("more than {MAX_PRIMITIVES} triangles (the limit)"),
                    ));
                }
                if r.faces.is_empty() && r.face.iter().all(|c| r.defined(c)) {
                    let face = std::mem::take(&mut r.face);
                    r.emit(&face, material, &lx, out)?;
                    r.face = face;
                } else {
                    r.faces.push((r.held.len(), material));
                    r.held.extend_from_slice(&r.face);
                }
            }
            b"mtllib" if out.mtl => materials.mtllib(&mut lx, &t, out)?,
            b"usemtl" if out.mtl => material = materials.usemtl(&mut lx, &t, out)?,
            _ => lx.skip_line(line)?,
        }
    }
    // The faces held for vertices defined after them, in order.
    let (held, faces) = (std::mem::take(&mut r.held), std::mem::take(&mut r.faces));
    for (k, &(start, material)) in faces.iter().enumerate() {
        let end = faces.get(k + 1).map_or(held.len(), |&(e, _)| e);
        r.emit(&held[start..end], material, &lx, out)?;
    }
    Ok(())
}

struct Reader {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    /// Corners of the faces held until the end, and where each face starts in it with
    /// its material and texture map.
    held: Vec<Corner>,
    faces: Vec<(usize, (MaterialId, Affine2))>,
    // Scratch buffers reused by every face.
    face: Vec<Corner>,
    poly: Vec<Vec3>,
    poly_n: Vec<Vec3>,
    poly_uv: Vec<Vec2>,
    idx: Vec<[u32; 3]>,
}

impl Reader {
    /// Whether the corner's vertex (and texture coordinate and normal) are defined by now.
    fn defined(&self, c: &Corner) -> bool {
        let ok = |i: i64, n: usize| usize::try_from(i).is_ok_and(|i| i < n);
        ok(c.v, self.positions.len())
            && c.t.is_none_or(|t| ok(t, self.uvs.len()))
            && c.n.is_none_or(|n| ok(n, self.normals.len()))
    }

    /// Triangulates a face of `material` (whose texture coordinates `uv_map` maps onto its
    /// texture) and gives its triangles to `out`'s sink, or warns that it is dropped.
    fn emit(
        &mut self,
        face: &[Corner],
        (material, uv_map): (MaterialId, Affine2),
        lx: &Lexer,
        out: &mut MeshOut,
    ) -> Result<()> {
        let at = |c: &Corner, msg: String| lx.error_at(&c.at, msg);
        self.poly.clear();
        self.poly_n.clear();
        self.poly_uv.clear();
        for c in face {
            let p = usize::try_from(c.v)
                .ok()
                .and_then(|i| self.positions.get(i));
            let Some(&p) = p else {
                return Err(at(
                    c,
                    format!(
                        "face corner refers to a vertex that does not exist (the file has {})",
                        self.positions.len()
                    ),
                ));
            };
            self.poly.push(p);
            if let Some(n) = c.n {
                let Some(&n) = usize::try_from(n).ok().and_then(|i| self.normals.get(i)) else {
                    return Err(at(
                        c,
                        format!(
                            "face corner refers to a normal that does not exist (the file has {})",
                            self.normals.len()
                        ),
                    ));
                };
                self.poly_n.push(unit(n).unwrap_or(Vec3::ZERO));
            }
            if let Some(t) = c.t {
                let Some(&uv) = usize::try_from(t).ok().and_then(|i| self.uvs.get(i)) else {
                    return Err(at(
                        c,
                        format!(
                            "face corner refers to a texture coordinate that does not exist (the file has {})",
                            self.uvs.len()
                        ),
                    ));
                };
                self.poly_uv.push(uv_map.transform_point2(uv));
            }
        }
        let (poly, poly_n, poly_uv) = (&self.poly, &self.poly_n, &self.poly_uv);
        // Texture coordinates only when every corner has one.
        let textured = poly_uv.len() == poly.len();
        // Shading normals only when every corner has a usable one; otherwise flat.
        let smooth = poly_n.len() == poly.len() && poly_n.iter().all(|n| n.length_squared() > 0.0);
        self.idx.clear();
        if poly.len() < 3 || !triangulate(poly, &mut self.idx) {
            let (line, col) = face.first().map_or((0, 0), |c| (c.at.line, c.at.col));
            out.warnings.push(format!(
                "{}:{line}:{col}: degenerate face with {} corners dropped",
                lx.name(),
                poly.len()
            ));
            return Ok(());
        }
        for &[a, b, c] in &self.idx {
            let ix = [a, b, c].map(|i| i as usize);
            let n = smooth.then(|| ix.map(|i| poly_n[i]));
            let uv = textured.then(|| ix.map(|i| poly_uv[i]));
            out.sink.triangle(ix.map(|i| poly[i]), n, uv, material);
        }
        Ok(())
    }
}

/// A face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`. Negative indices count back from the
/// last vertex (texture coordinate, normal) defined so far, `defined` of each.
fn corner(lx: &Lexer, t: &Token, [n_pos, n_uv, n_nrm]: [usize; 3]) -> Result<Corner> {
    let bad = || {
        lx.error_at(
            t,
            format!(
                "expected a face corner (v, v/vt, v//vn or v/vt/vn with non-zero integers), found {}",
                lx.show(t)
            ),
        )
    };
    let mut parts = lx.text(t).split(|&b| b == b'/');
    let resolve = |s: &[u8], defined: usize| -> Option<i64> {
        let i: i64 = std::str::from_utf8(s).ok()?.parse().ok()?;
        match i {
            0 => None,
            i if i > 0 => Some(i - 1),
            i => Some(defined as i64 + i),
        }
    };
    let v = resolve(parts.next().unwrap_or_default(), n_pos).ok_or_else(bad)?;
    let mut index = |defined: usize| -> Result<Option<i64>> {
        match parts.next() {
            None | Some(b"") => Ok(None),
            Some(s) => Ok(Some(resolve(s, defined).ok_or_else(bad)?)),
        }
    };
    let uv = index(n_uv)?;
    let n = index(n_nrm)?;
    if parts.next().is_some() {
        return Err(bad());
    }
    Ok(Corner {
        v,
        t: uv,
        n,
        at: *t,
    })
}
