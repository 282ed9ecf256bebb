//! What BART's Animated File Format (AFF) adds to NFF: transform blocks (`xs` fixed, `x`
//! animated by name) and the keyframes that animate them (`k`), the time range (`a`),
//! moving lights (`la`), the extended material (`fm`), textured triangles (`tt`, `ttp`),
//! indexed meshes (`m`), includes with detail levels (`i`, `d`). The format is BART's
//! `parse.c`; `docs/scene-format.md` says what gpurt renders of it. The keyframes are
//! read by `keys`; the blocks' state, and where they send what is read, are `blocks`'.

use std::path::Path;

use glam::{DAffine3, DQuat, DVec3, Vec2, Vec3};

use super::Parser;
use super::blocks::{Open, Route, Target};
use crate::scene::animation::{Animation, Group, Link, MovingLight, TimeRange, Track};
use crate::scene::lex::{Lexer, Token};
use crate::scene::model::{
    Light, Material, MaterialId, Plane, Scene, Wrap, nff_default_camera, unit,
};
use crate::scene::place::Placement;
use crate::scene::sink::Sink;
use crate::scene::{images, io};
use crate::util::error::{Error, Result, escape};
use crate::util::limits::{MAX_IMAGE_BYTES, MAX_LIGHT, MAX_MESH_VERTICES, MAX_SHINE};

/// Includes nested deeper than this are refused (a file that includes itself).
const MAX_INCLUDE_DEPTH: u32 = 32;

impl Parser<'_> {
    pub(super) fn route(&mut self) -> Route<'_> {
        Route::new(&mut *self.sink, &mut self.blocks)
    }

    /// A plane, through the open blocks.
    pub(super) fn put_plane(&mut self, p: Plane) {
        match self.blocks.target() {
            None => self.scene.planes.push(p),
            Some(Target::Fixed(_, place)) => self.scene.planes.extend(place.plane(p)),
            Some(Target::Group(g)) => self.blocks.groups[g].planes.push(p),
        }
    }

    /// A light, through the open blocks.
    pub(super) fn put_light(&mut self, l: Light) {
        match self.blocks.target() {
            None => self.scene.lights.push(l),
            Some(Target::Fixed(_, place)) => self.scene.lights.push(place.light(l)),
            Some(Target::Group(g)) => self.blocks.groups[g].lights.push(l),
        }
    }

    /// `a start end frames`.
    pub(super) fn time_range(&mut self, tok: &Token) -> Result<()> {
        let start = f64::from(self.lx.number("animation start time")?);
        let end = f64::from(self.lx.number("animation end time")?);
        let (frames, ftok) = self.lx.count("animation frame count")?;
        if frames == 0 {
            return Err(self
                .lx
                .error_at(&ftok, "an animation needs at least one frame"));
        }
        if end < start {
            return Err(self.lx.error_at(
                tok,
                format!("animation ends (at {end}) before it starts (at {start})"),
            ));
        }
        if self.blocks.range.is_some() {
            self.warn(tok, "second 'a' replaces the first");
        }
        self.blocks.range = Some(TimeRange { start, end, frames });
        Ok(())
    }

    pub(super) fn expect_open_brace(&mut self, what: &str) -> Result<()> {
        let t = self.lx.expect_token(&format!("'{{' opening the {what}"))?;
        if self.lx.text(&t) != b"{" {
            return Err(self.lx.error_at(
                &t,
                format!(
                    "expected '{{' opening the {what}, found {}",
                    self.lx.show(&t)
                ),
            ));
        }
        Ok(())
    }

    /// A transform's name: one word.
    pub(super) fn name(&mut self, what: &str) -> Result<(String, Token)> {
        let t = self.lx.expect_token(what)?;
        let name = String::from_utf8_lossy(self.lx.text(&t)).into_owned();
        if name == "{" || name == "}" {
            return Err(self
                .lx
                .error_at(&t, format!("expected {what}, found {}", self.lx.show(&t))));
        }
        Ok((name, t))
    }

    /// `xs sx sy sz  rx ry rz degrees  tx ty tz {`.
    pub(super) fn open_fixed(&mut self, tok: &Token) -> Result<()> {
        let s = self.lx.vec3("transform scale")?.as_dvec3();
        let axis = self.lx.vec3("transform rotation axis")?.as_dvec3();
        let deg = f64::from(self.lx.number("transform rotation in degrees")?);
        let t = self.lx.vec3("transform translation")?.as_dvec3();
        let rotation = self.rotation(tok, axis, deg)?;
        if s.cmpeq(DVec3::ZERO).any() {
            return Err(self.lx.error_at(tok, "transform scale must not be zero"));
        }
        self.expect_open_brace("transform block")?;
        let a = DAffine3::from_scale_rotation_translation(s, rotation, t);
        let target = match self.blocks.target() {
            None => self.fixed(tok, a)?,
            Some(Target::Fixed(outer, _)) => self.fixed(tok, outer * a)?,
            Some(Target::Group(g)) => {
                let mut chain = self.blocks.groups[g].chain.clone();
                chain.push(Link::Fixed(a));
                self.group(chain)
            }
        };
        self.blocks.stack.push(Open { tok: *tok, target });
        Ok(())
    }

    fn fixed(&self, tok: &Token, a: DAffine3) -> Result<Target> {
        match Placement::new(a) {
            Some(p) => Ok(Target::Fixed(a, p)),
            None => Err(self.lx.error_at(
                tok,
                "the transforms of this block flatten space (a zero scale)",
            )),
        }
    }

    fn group(&mut self, chain: Vec<Link>) -> Target {
        self.blocks.groups.push(Group {
            chain,
            ..Group::default()
        });
        Target::Group(self.blocks.groups.len() - 1)
    }

    /// A rotation of `deg` degrees about `axis`, which need not be of unit length.
    fn rotation(&self, tok: &Token, axis: DVec3, deg: f64) -> Result<DQuat> {
        if deg == 0.0 {
            return Ok(DQuat::IDENTITY);
        }
        match axis.try_normalize() {
            Some(axis) => Ok(DQuat::from_axis_angle(axis, deg.to_radians())),
            None => Err(self.lx.error_at(
                tok,
                format!("a rotation of {deg} degrees about a zero axis"),
            )),
        }
    }

    /// `x name {`.
    pub(super) fn open_moving(&mut self, tok: &Token) -> Result<()> {
        let (name, ntok) = self.name("transform name")?;
        let used = (self.lx.name().to_string(), ntok.line, ntok.col);
        let track = self.blocks.name(&name, Some(used));
        self.expect_open_brace("animated transform block")?;
        let chain = match self.blocks.target() {
            None => vec![Link::Moving(track)],
            Some(Target::Fixed(outer, _)) => vec![Link::Fixed(outer), Link::Moving(track)],
            Some(Target::Group(g)) => {
                let mut chain = self.blocks.groups[g].chain.clone();
                chain.push(Link::Moving(track));
                chain
            }
        };
        let target = self.group(chain);
        self.blocks.stack.push(Open { tok: *tok, target });
        Ok(())
    }

    /// `}`.
    pub(super) fn close_block(&mut self, tok: &Token) -> Result<()> {
        if self.blocks.stack.len() <= self.depth_floor {
            return Err(self.lx.error_at(tok, "'}' closes no block"));
        }
        self.blocks.stack.pop();
        Ok(())
    }

    /// At the end of a file: every block it opened is closed.
    pub(super) fn check_closed(&self) -> Result<()> {
        match self.blocks.stack.get(self.depth_floor) {
            Some(open) => Err(self.lx.error_at(
                &open.tok,
                "this block is never closed (a '}' is missing before the end of the file)",
            )),
            None => Ok(()),
        }
    }

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

    /// `la name x y z [r g b]`: a point light that the track `name` moves.
    pub(super) fn moving_light(&mut self, _tok: &Token) -> Result<()> {
        let (name, ntok) = self.name("light name")?;
        let used = (self.lx.name().to_string(), ntok.line, ntok.col);
        let position = self.lx.vec3("light position")?;
        let color = self.optional_colour("light colour")?;
        let color = color.map(|c| self.hold3(&ntok, "light colour", c, MAX_LIGHT));
        let track = self.blocks.name(&name, Some(used));
        self.blocks.lights.push(MovingLight {
            track,
            light: Light::Point { position, color },
        });
        Ok(())
    }

    /// `fm ambient(rgb) diffuse(rgb) specular(rgb) shine T ior`: the material's colour is
    /// the diffuse colour, its ambient colour the ambient colour; the specular colour's
    /// largest part is the specular weight (the model's highlights are white).
    pub(super) fn fill_material(&mut self, tok: &Token) -> Result<()> {
        let ambient = self.lx.vec3("ambient colour")?;
        let diffuse = self.lx.vec3("diffuse colour")?;
        let specular = self.lx.vec3("specular colour")?;
        let diffuse = self.hold3(tok, "diffuse colour", diffuse, 1.0);
        let specular = self.hold3(tok, "specular colour", specular, 1.0);
        let shine = self.lx.number("Shine")?;
        let shine = self.hold(tok, "Shine", shine, MAX_SHINE);
        let t = self.lx.number("T")?;
        let t = self.hold(tok, "T", t, 1.0);
        let mut ior = self.lx.number("index of refraction")?;
        if t > 0.0 && ior <= 0.0 {
            // BART's robots have such materials (T 0.04, ior 0): read as glass that does
            // not bend light, where NFF's `f` refuses it.
            self.warn_once(
                tok,
                &format!("a transmitting material (T = {t}) with an index of refraction of {ior}: read as 1 (no bending)"),
            );
            ior = 1.0;
        }
        if specular.max_element() - specular.min_element() > 1e-3 {
            self.warn_once(
                tok,
                "a coloured specular colour is read as white highlights of its largest part",
            );
        }
        let ambient = self.hold3(tok, "ambient colour", ambient, 1.0);
        self.set_material(Material {
            color: diffuse,
            kd: 1.0,
            ks: specular.max_element(),
            shine,
            t,
            ior: if t > 0.0 { ior } else { 1.0 },
            emission: Vec3::ZERO,
            texture: None,
            ambient: Some(ambient),
        });
        Ok(())
    }

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
    fn textured_material(&mut self, tok: &Token, name: &str) -> MaterialId {
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

    /// `tpa N` and N samples of `time` and three rows of `x y z nx ny nz`: a triangle
    /// that moves by its own keys. Read and left out, with a warning.
    pub(super) fn animated_triangle(&mut self, tok: &Token) -> Result<()> {
        let (n, ntok) = self.lx.count("number of animated triangle samples")?;
        self.check_count(&ntok, n, 38)?;
        for _ in 0..n {
            self.lx.number("animated triangle sample time")?;
            for _ in 0..6 {
                self.lx.vec3("animated triangle vertex")?;
            }
        }
        self.warn_once(
            tok,
            "animated triangles ('tpa') are not rendered yet; left out",
        );
        Ok(())
    }

    /// `m vertices N ... [normals N ...] [texturecoords N texture ...] triangles N ...`:
    /// an indexed mesh; each triangle is its three vertex indices, then its three normal
    /// indices and its three texture coordinate indices where the mesh has them.
    pub(super) fn indexed_mesh(&mut self, tok: &Token) -> Result<()> {
        let mut section = self.lx.expect_token("'vertices'")?;
        if self.lx.text(&section) != b"vertices" {
            return Err(self.lx.error_at(
                &section,
                format!(
                    "expected 'vertices' after 'm', found {}",
                    self.lx.show(&section)
                ),
            ));
        }
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
        if self.lx.text(&section) != b"triangles" {
            return Err(self.lx.error_at(
                &section,
                format!(
                    "expected 'triangles' in the mesh, found {}",
                    self.lx.show(&section)
                ),
            ));
        }
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

    /// `d level`: includes of a higher detail level are skipped from here on.
    pub(super) fn detail_level(&mut self) -> Result<()> {
        let (level, _) = self.lx.count("detail level")?;
        self.blocks.detail = level;
        Ok(())
    }

    /// `i level file`: another AFF (or NFF) file read here, inside the open blocks, with
    /// the current material; skipped when its level is above the detail level (`d`).
    pub(super) fn include(&mut self, _tok: &Token) -> Result<()> {
        let (level, _) = self.lx.count("include detail level")?;
        let ptok = self.lx.expect_token("included file name")?;
        if level > self.blocks.detail {
            return Ok(());
        }
        let raw = String::from_utf8_lossy(self.lx.text(&ptok)).into_owned();
        let path = self.base.join(raw.trim_matches('"'));
        if self.blocks.depth >= MAX_INCLUDE_DEPTH {
            return Err(self.lx.error_at(
                &ptok,
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)"),
            ));
        }
        let input = io::open(&path).map_err(|e| {
            self.lx.error_at(
                &ptok,
                format!(
                    "cannot read included file '{}': {}",
                    escape(path.as_os_str().as_encoded_bytes()),
                    match e {
                        Error::Io { source, .. } => source.to_string(),
                        other => other.to_string(),
                    }
                ),
            )
        })?;
        let name = path.display().to_string();
        let dir = path.parent().unwrap_or(Path::new("."));
        let blank = || Scene::new(String::new(), nff_default_camera());
        let mut child = Parser {
            lx: Lexer::through(input, &name, self.window),
            base: dir,
            sink: &mut *self.sink,
            lenient: self.lenient,
            window: self.window,
            scene: std::mem::replace(&mut self.scene, blank()),
            have_view: self.have_view,
            material: self.material,
            palette: std::mem::take(&mut self.palette),
            verts: Vec::new(),
            normals: Vec::new(),
            tris: Vec::new(),
            blocks: std::mem::take(&mut self.blocks),
            depth_floor: 0,
            warned: std::mem::take(&mut self.warned),
        };
        child.blocks.depth += 1;
        child.depth_floor = child.blocks.stack.len();
        let read = child.statements();
        self.scene = child.scene;
        self.have_view = child.have_view;
        self.material = child.material;
        self.palette = child.palette;
        self.blocks = child.blocks;
        self.blocks.depth -= 1;
        self.warned = child.warned;
        read
    }

    /// At the end of the scene: every animated transform has its keyframes, and what
    /// moves is handed to the scene.
    pub(super) fn finish_animation(&mut self) -> Result<()> {
        let blocks = std::mem::take(&mut self.blocks);
        let mut tracks = Vec::with_capacity(blocks.names.len());
        let mut camera = None;
        for (i, n) in blocks.names.into_iter().enumerate() {
            match (n.track, n.used) {
                (None, Some((file, line, col))) => {
                    let name = escape(n.name.as_bytes());
                    let msg = format!(
                        "transform '{name}' has no keyframes (no 'k {name}' block in the scene)"
                    );
                    if !self.lenient {
                        return Err(Error::Parse {
                            file,
                            line,
                            col,
                            msg,
                            excerpt: None,
                        });
                    }
                    // BART's previewer takes a transform without keys as the identity
                    // (one of its robots has one).
                    let msg = format!("{file}:{line}:{col}: {msg}; it stays still (--lenient)");
                    self.scene.warnings.push(msg);
                    tracks.push(Track {
                        name: n.name,
                        ..Track::default()
                    });
                }
                (None, None) => tracks.push(Track::default()),
                (Some(track), used) => {
                    if track.name == "camera" {
                        camera = Some(i);
                    } else if used.is_none() {
                        let name = escape(track.name.as_bytes());
                        self.scene.warnings.push(format!(
                            "{}: keyframes for '{name}', which no 'x {name}' block or 'la {name}' light uses",
                            self.lx.name()
                        ));
                    }
                    tracks.push(track);
                }
            }
        }
        let groups: Vec<Group> = blocks
            .groups
            .into_iter()
            .filter(|g| g.prims.count() > 0 || !g.planes.is_empty() || !g.lights.is_empty())
            .collect();
        let animation = Animation {
            range: blocks.range,
            tracks,
            groups,
            lights: blocks.lights,
            camera,
        };
        if animation.range.is_some() || !animation.is_still() {
            self.scene.animation = Some(Box::new(animation));
        }
        Ok(())
    }
}
