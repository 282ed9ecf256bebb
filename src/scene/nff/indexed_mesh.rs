//! AFF's indexed meshes (`m vertices ... [normals ...] [texturecoords ...] triangles ...`):
//! the rows of vertices, normals and texture coordinates, each count checked against what
//! the file can hold before anything is allocated, and the triangles that index them.

use glam::{Vec2, Vec3};

use super::Parser;
use crate::scene::lex::Token;
use crate::scene::model::unit;
use crate::scene::sink::Sink;
use crate::util::error::Result;
use crate::util::limits::MAX_MESH_VERTICES;

impl Parser<'_> {
    /// Refuses a count of rows the rest of the file is too short to hold (each of at
    /// least `min_bytes`), before anything is allocated for them.
    pub(super) fn check_count(&self, ntok: &Token, n: u32, min_bytes: u64) -> Result<()> {
        if let Some(rest) = self
            .lx
            .remaining()
            .filter(|&r| u64::from(n) * min_bytes > r + 1)
        {
            return Err(self.lx.error_at(
                ntok,
                format!("{n} rows, but the file has only {rest} bytes left: too few to hold them (is the count right?)"),
            ));
        }
        if n as usize > MAX_MESH_VERTICES {
            return Err(self.lx.error_at(
                ntok,
                format!("{n} is above the limit of {MAX_MESH_VERTICES}"),
            ));
        }
        Ok(())
    }

    /// `m vertices N ... [normals N ...] [texturecoords N texture ...] triangles N ...`:
    /// an indexed mesh; each triangle is its three vertex indices, then its three normal
    /// indices and its three texture coordinate indices where the mesh has them.
    pub(super) fn indexed_mesh(&mut self, tok: &Token) -> Result<()> {
        let mut section = self.lx.expect_token("'vertices'")?;
        self.expect_word(&section, b"vertices", "'vertices' after 'm'")?;
        let verts = self.vectors("mesh vertex")?;
        let mut normals = Vec::new();
        let mut uvs = Vec::new();
        let mut material = None;
        section = self
            .lx
            .expect_token("'normals', 'texturecoords' or 'triangles'")?;
        if self.lx.text(&section) == b"normals" {
            normals = self.vectors("mesh normal")?;
            section = self.lx.expect_token("'texturecoords' or 'triangles'")?;
        }
        if self.lx.text(&section) == b"texturecoords" {
            let (n, ntok) = self.lx.count("number of texture coordinates")?;
            let (texture, _) = self.name("texture name")?;
            self.check_count(&ntok, n, 4)?;
            for _ in 0..n {
                uvs.push(Vec2::new(
                    self.lx.number("texture coordinate u")?,
                    self.lx.number("texture coordinate v")?,
                ));
            }
            material = Some(self.textured_material(tok, &texture));
            section = self.lx.expect_token("'triangles'")?;
        }
        self.expect_word(&section, b"triangles", "'triangles' in the mesh")?;
        let (n, ntok) = self.lx.count("number of mesh triangles")?;
        self.check_count(&ntok, n, 6)?;
        self.room(tok, n as usize)?;
        let material = material.unwrap_or_else(|| self.current_material());
        for _ in 0..n {
            let v = self.indices(&verts, "vertex")?;
            let nm = if normals.is_empty() {
                None
            } else {
                let [a, b, c] = self.indices(&normals, "normal")?;
                match [unit(a), unit(b), unit(c)] {
                    [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                    _ => None,
                }
            };
            let uv = if uvs.is_empty() {
                None
            } else {
                Some(self.indices(&uvs, "texture coordinate")?)
            };
            self.route().triangle(v, nm, uv, material);
        }
        Ok(())
    }

    /// `N` and N vectors.
    fn vectors(&mut self, what: &str) -> Result<Vec<Vec3>> {
        let (n, ntok) = self.lx.count(&format!("number of {what}s"))?;
        self.check_count(&ntok, n, 6)?;
        (0..n).map(|_| self.lx.vec3(what)).collect()
    }

    /// Three indices into `of`, and what they index.
    fn indices<T: Copy>(&mut self, of: &[T], what: &str) -> Result<[T; 3]> {
        let mut out = [of[0]; 3];
        for o in &mut out {
            let (i, itok) = self.lx.count(&format!("mesh {what} index"))?;
            *o = *of.get(i as usize).ok_or_else(|| {
                self.lx.error_at(
                    &itok,
                    format!("mesh {what} index {i} is past the last ({})", of.len() - 1),
                )
            })?;
        }
        Ok(out)
    }
}
