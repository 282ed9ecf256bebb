//! A scene's materials as the readers add them: an NFF `f`, an OBJ's `.mtl` material, the
//! grey of a bare mesh. Identical materials share one id (SPD repeats `f` lines for every
//! object, and every part of an OBJ may name the same `.mtl` material).

use std::collections::HashMap;

use super::model::{Material, MaterialId};

/// The ids of the materials added so far, by value.
#[derive(Debug, Default)]
pub struct Palette {
    ids: HashMap<[u32; 8], MaterialId>,
}

impl Palette {
    /// The id of `m` in `materials`, which it joins if no identical one is there yet.
    /// `materials` must only ever grow through this palette.
    pub fn id(&mut self, materials: &mut Vec<Material>, m: Material) -> MaterialId {
        let key = [
            m.color.x, m.color.y, m.color.z, m.kd, m.ks, m.shine, m.t, m.ior,
        ]
        .map(f32::to_bits);
        *self.ids.entry(key).or_insert_with(|| {
            materials.push(m);
            MaterialId(materials.len() as u32 - 1)
        })
    }
}
