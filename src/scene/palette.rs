//! A scene's materials as the readers add them: an NFF `f`, an OBJ's `.mtl` material, the
//! grey of a bare mesh. Identical materials share one id (SPD repeats `f` lines for every
//! object, and every part of an OBJ may name the same `.mtl` material).

use std::collections::HashMap;

use super::model::{Material, MaterialId};

/// The ids of the materials added so far, by value.
#[derive(Debug, Default)]
pub struct Palette {
    ids: HashMap<[u32; 15], MaterialId>,
}

impl Palette {
    /// The id of `m` in `materials`, which it joins if no identical one is there yet.
    /// `materials` must only ever grow through this palette.
    pub fn id(&mut self, materials: &mut Vec<Material>, m: Material) -> MaterialId {
        // Every field: materials that differ only in their emission, their texture or
        // their ambient colour are different materials.
        let c = [
            m.color.x,
            m.color.y,
            m.color.z,
            m.kd,
            m.ks,
            m.shine,
            m.t,
            m.ior,
            m.emission.x,
            m.emission.y,
            m.emission.z,
        ]
        .map(f32::to_bits);
        let texture = m.texture.unwrap_or(u32::MAX);
        // No float's bits are all ones (a NaN's), so `None` keys apart from any colour.
        let a = m
            .ambient
            .map_or([u32::MAX; 3], |a| a.to_array().map(f32::to_bits));
        let key = [
            c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9], c[10], texture, a[0], a[1],
            a[2],
        ];
        *self.ids.entry(key).or_insert_with(|| {
            materials.push(m);
            MaterialId(materials.len() as u32 - 1)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn materials_that_differ_in_emission_texture_or_ambient_keep_their_own_ids() {
        let (mut palette, mut materials) = (Palette::default(), Vec::new());
        let plain = Material::NEUTRAL_GREY;
        let lit = Material {
            emission: Vec3::ONE,
            ..plain
        };
        let painted = Material {
            texture: Some(0),
            ..plain
        };
        let dim = Material {
            ambient: Some(Vec3::splat(0.1)),
            ..plain
        };
        let ids: Vec<MaterialId> = [plain, lit, painted, dim, plain]
            .into_iter()
            .map(|m| palette.id(&mut materials, m))
            .collect();
        assert_eq!(ids, [0, 1, 2, 3, 0].map(MaterialId));
        assert_eq!(materials, [plain, lit, painted, dim]);
    }
}
