//! The `mesh PATH [translate ..] [rotate ..] [scale ..]` statement: an STL or OBJ file
//! read (relative to the scene's directory, gzip-aware), transformed and given the current
//! material. The only statement that opens another file, so the only one that needs `io`.

use glam::Vec3;

use super::Parser;
use crate::error::escape;
use crate::error::{Error, Result};
use crate::scene::io::{FileKind, read_file};
use crate::scene::lex::Token;
use crate::scene::mesh::{self, MeshTransform};

impl Parser<'_> {
    pub(super) fn mesh(&mut self, tok: &Token) -> Result<()> {
        let ptok = self.lx.expect_token("mesh file path")?;
        let raw = String::from_utf8_lossy(ptok.text);
        let rel = raw.trim_matches('"');
        let mut xf = MeshTransform::default();
        while let Some(t) = self.lx.peek() {
            match t.text {
                b"translate" => {
                    self.lx.next_token();
                    xf.translate = self.lx.vec3("mesh translation")?;
                }
                b"rotate" => {
                    self.lx.next_token();
                    xf.rotate_deg = self.lx.vec3("mesh rotation in degrees")?;
                }
                b"scale" => {
                    self.lx.next_token();
                    let s = self.lx.number("mesh scale")?;
                    xf.scale = if self.lx.peek_is_number() {
                        Vec3::new(
                            s,
                            self.lx.number("mesh scale y")?,
                            self.lx.number("mesh scale z")?,
                        )
                    } else {
                        Vec3::splat(s)
                    };
                    if xf.scale.cmpeq(Vec3::ZERO).any() {
                        return Err(self.lx.error_at(&t, "mesh scale must not be zero"));
                    }
                }
                _ => break,
            }
        }
        let path = self.base.join(rel);
        let kind = FileKind::of(&path);
        if kind == FileKind::Nff {
            return Err(self.lx.error_at(
                &ptok,
                format!(
                    "mesh file '{}' must end in .stl or .obj (optionally .gz)",
                    escape(rel.as_bytes())
                ),
            ));
        }
        let bytes = read_file(&path).map_err(|e| {
            let why = match e {
                Error::Io { source, .. } => source.to_string(),
                Error::Scene { msg, .. } => msg,
                other => return other,
            };
            self.lx.error_at(
                &ptok,
                format!(
                    "cannot read mesh file '{}': {why}",
                    escape(path.as_os_str().as_encoded_bytes())
                ),
            )
        })?;
        let mesh = mesh::parse_mesh(&bytes, kind, &path.display().to_string())?;
        self.scene.warnings.extend(mesh.warnings);
        let mut tris = mesh.triangles;
        if tris.is_empty() {
            self.warn(
                tok,
                &format!("mesh '{}' has no triangles", escape(rel.as_bytes())),
            );
        }
        let material = self.current_material();
        xf.apply(&mut tris);
        for t in &mut tris {
            t.material = material;
        }
        self.scene.triangles.append(&mut tris);
        Ok(())
    }
}
