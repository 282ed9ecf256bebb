//! Materials of the NFF reader: the `f` statement, the current material (the default one
//! until the first `f`), exact duplicates interned to one id, and every colour and
//! coefficient held to its range with a warning (`limits::MAX_LIGHT`, `MAX_SHINE`), so
//! that every pixel stays finite.

use glam::Vec3;

use super::Parser;
use crate::scene::lex::Token;
use crate::scene::model::{Material, MaterialId};
use crate::util::error::Result;
use crate::util::limits::MAX_SHINE;

impl Parser<'_> {
    /// `v` held to `[0, hi]`, with a warning naming the line when it was outside.
    pub(super) fn hold(&mut self, tok: &Token, what: &str, v: f32, hi: f32) -> f32 {
        if (0.0..=hi).contains(&v) {
            return v;
        }
        let held = v.clamp(0.0, hi);
        self.warn(
            tok,
            &format!("{what} {v} is outside [0, {hi}]; using {held}"),
        );
        held
    }

    /// Each component of `v` held to `[0, hi]`, with one warning when any was outside.
    pub(super) fn hold3(&mut self, tok: &Token, what: &str, v: Vec3, hi: f32) -> Vec3 {
        let held = v.clamp(Vec3::ZERO, Vec3::splat(hi));
        if held != v {
            self.warn(
                tok,
                &format!(
                    "{what} {} {} {} is outside [0, {hi}]; using {} {} {}",
                    v.x, v.y, v.z, held.x, held.y, held.z
                ),
            );
        }
        held
    }

    pub(super) fn current_material(&mut self) -> MaterialId {
        match self.material {
            Some(m) => m,
            None => {
                let id = self.intern(Material::DEFAULT);
                self.material = Some(id);
                id
            }
        }
    }

    pub(super) fn intern(&mut self, m: Material) -> MaterialId {
        self.palette.id(&mut self.scene.materials, m)
    }

    /// Makes `m` the current material.
    pub(super) fn set_material(&mut self, m: Material) {
        self.material = Some(self.intern(m));
    }

    pub(super) fn fill(&mut self, tok: &Token) -> Result<()> {
        let color = self.lx.vec3("material colour")?;
        let color = self.hold3(tok, "material colour", color, 1.0);
        let kd = self.lx.number("Kd")?;
        let kd = self.hold(tok, "Kd", kd, 1.0);
        let ks = self.lx.number("Ks")?;
        let ks = self.hold(tok, "Ks", ks, 1.0);
        let shine = self.lx.number("Shine")?;
        let shine = self.hold(tok, "Shine", shine, MAX_SHINE);
        let t = self.lx.number("T")?;
        let t = self.hold(tok, "T", t, 1.0);
        let ior = self.lx.number("index of refraction")?;
        if t > 0.0 && ior <= 0.0 {
            return Err(self.lx.error_at(
                tok,
                format!("a transmitting material (T = {t}) needs a positive index of refraction, found {ior}"),
            ));
        }
        let m = Material {
            color,
            kd,
            ks,
            shine,
            t,
            // T = 0 makes ior meaningless (SPD writes 0): keep a harmless value.
            ior: if t > 0.0 { ior } else { 1.0 },
            emission: Vec3::ZERO,
            texture: None,
            ambient: None,
        };
        self.set_material(m);
        Ok(())
    }
}
