//! What BART's Animated File Format (AFF) adds to NFF: transform blocks (`xs` fixed, `x`
//! animated by name) and the keyframes that animate them (`k`), the time range (`a`),
//! moving lights (`la`), the extended material (`fm`), textured triangles (`tt`, `ttp`),
//! indexed meshes (`m`), includes with detail levels (`i`, `d`). The format is BART's
//! `parse.c`; `docs/scene-format.md` says what gpurt renders of it. The keyframes are
//! read by `keys`; the blocks' state, and where they send what is read, are `blocks`'.
//! This file holds the blocks, the time range, the moving lights, the extended material,
//! the animated triangles read and left out (`tpa`) and the animation handed to the scene
//! at its end; the textured triangles are `textured`'s, the indexed meshes
//! `indexed_mesh`'s and the includes `include`'s.

use glam::{DAffine3, DQuat, DVec3, Vec3};

use super::Parser;
use super::blocks::{Open, Route, Target};
use crate::scene::animation::{Animation, Group, Link, MovingLight, TimeRange, Track};
use crate::scene::lex::Token;
use crate::scene::model::{Light, Material, Plane};
use crate::scene::place::Placement;
use crate::scene::sink::Sink;
use crate::util::error::{Error, Result, escape};
use crate::util::limits::{MAX_LIGHT, MAX_SHINE};

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
        let expected = format!("'{{' opening the {what}");
        let t = self.lx.expect_token(&expected)?;
        self.expect_word(&t, b"{", &expected)
    }

    /// An error at `t` unless it is `word`: "expected {expected}, found ...".
    pub(super) fn expect_word(&self, t: &Token, word: &[u8], expected: &str) -> Result<()> {
        if self.lx.text(t) == word {
            return Ok(());
        }
        Err(self
            .lx
            .error_at(t, format!("expected {expected}, found {}", self.lx.show(t))))
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
