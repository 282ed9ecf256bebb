//! AFF's textured triangles (`tt`, `ttp`) and the images they name: each image read the
//! first time a surface names it, from the folder of the file naming it or a
//! `TextureFiles` folder beside it (how BART's scenes lay their images out), and the
//! current material given that texture; a missing image leaves the surfaces their colour.

use glam::{Vec2, Vec3};

use super::Parser;
use crate::scene::lex::Token;
use crate::scene::model::{MaterialId, Wrap, unit};
use crate::scene::sink::Sink;
use crate::scene::{images, io};
use crate::util::error::{Result, escape};
use crate::util::limits::MAX_IMAGE_BYTES;

impl Parser<'_> {
    /// `tt texture` and three rows of `x y z u v`, or `ttp texture` (also written `tpp`)
    /// and three rows of `x y z nx ny nz u v`.
    pub(super) fn textured_triangle(&mut self, tok: &Token, patch: bool) -> Result<()> {
        let (texture, _) = self.name("texture name")?;
        let mut v = [Vec3::ZERO; 3];
        let mut n = [Vec3::ZERO; 3];
        let mut uv = [Vec2::ZERO; 3];
        for i in 0..3 {
            v[i] = self.lx.vec3("triangle vertex")?;
            if patch {
                n[i] = self.lx.vec3("triangle vertex normal")?;
            }
            uv[i] = Vec2::new(
                self.lx.number("texture coordinate u")?,
                self.lx.number("texture coordinate v")?,
            );
        }
        let material = self.textured_material(tok, &texture);
        let normals = if patch {
            let units = [unit(n[0]), unit(n[1]), unit(n[2])];
            match units {
                [Some(a), Some(b), Some(c)] => Some([a, b, c]),
                _ => None,
            }
        } else {
            None
        };
        self.room(tok, 1)?;
        self.route().triangle(v, normals, Some(uv), material);
        Ok(())
    }

    /// The material of surfaces textured with the image `name`: the current material
    /// with that texture (repeating, as BART's textures do), or where the image cannot be
    /// had, the current material, with a warning (once an image).
    pub(super) fn textured_material(&mut self, tok: &Token, name: &str) -> MaterialId {
        let material = self.current_material();
        match self.aff_texture(name) {
            Ok(t) => {
                let mut m = self.scene.materials[material.0 as usize];
                m.texture = Some(t);
                self.intern(m)
            }
            Err(why) => {
                let msg = format!(
                    "texture '{}' not applied: {why}; the surfaces keep their material's colour",
                    escape(name.as_bytes())
                );
                self.warn_once(tok, &msg);
                material
            }
        }
    }

    /// The texture of the image file `name`, read the first time a surface names it: in
    /// the folder of the file naming it, else in a `TextureFiles` folder beside that
    /// folder (how BART's scenes lay their images out).
    fn aff_texture(&mut self, name: &str) -> std::result::Result<u32, String> {
        let wrap = [Wrap::Repeat; 2];
        let beside = self.base.join("..").join("TextureFiles");
        let dirs = [self.base.to_path_buf(), beside];
        for dir in dirs {
            let full = dir.join(name);
            let shown = full.display().to_string();
            if let Some(i) = images::find(&self.scene.textures, &shown, wrap) {
                return Ok(i);
            }
            if full.is_file() {
                let bytes = io::read_inside(&dir, name, MAX_IMAGE_BYTES)?;
                let texture = images::decode(&bytes, &shown, wrap)?;
                return Ok(images::add(
                    &mut self.scene.textures,
                    texture,
                    &mut self.scene.warnings,
                ));
            }
        }
        Err("no such file in the folder of the file naming it, nor in a TextureFiles folder beside that folder".into())
    }
}
