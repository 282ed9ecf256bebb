//! Emitters: the triangles of each emissive material (OBJ's `Ke`, glTF's emissive) made
//! one light, `LIGHT_EMITTER`, whose shadow rays go to points chosen over its triangles by
//! area (docs/model.md). Its triangles travel after the lights in the lights' buffer, each
//! with the area summed up to it, which is what a sample is chosen by (`GpuLight`).

use std::collections::BTreeMap;

use crate::gpu_types::{GpuLight, GpuPrim, LIGHT_EMITTER, PRIM_TRIANGLE};
use crate::scene::Material;

/// Shadow rays an emitter sends from each surface point it lights are this squared, as an
/// area light's `nu x nv`: a grid, along the summed area of its triangles and across.
pub const EMITTER_SAMPLES: u32 = 4;

/// The emitters of the triangle `records` (in the model's order, corners as `Flat` holds
/// them): one light per emissive material that has triangles of some area, in the
/// materials' order, and their triangles, each light's `first..first + nv`.
pub fn emitters(records: &[GpuPrim], materials: &[Material]) -> (Vec<GpuLight>, Vec<GpuLight>) {
    let mut by_material: BTreeMap<u32, Vec<GpuLight>> = BTreeMap::new();
    for p in records.iter().filter(|p| p.kind() == PRIM_TRIANGLE) {
        let m = p.material();
        // A material out of range is refused later (`SceneBuffers::check`), not here.
        if !materials.get(m as usize).is_some_and(Material::emits) {
            continue;
        }
        let (u, v) = (p.p1 - p.p0, p.p2 - p.p0);
        let area = 0.5 * u.cross(v).length();
        // No area, no light (and no direction to emit along).
        if area > 0.0 && area.is_finite() {
            by_material.entry(m).or_default().push(GpuLight {
                pos: p.p0,
                u,
                v,
                color: glam::Vec3::new(0.0, area, 0.0),
                ..Default::default()
            });
        }
    }
    let (mut lights, mut triangles) = (Vec::new(), Vec::new());
    for (m, mut tris) in by_material {
        // Summed in f64 so that the last sum is the total to the float, whatever the count.
        let mut sum = 0.0f64;
        for t in &mut tris {
            sum += f64::from(t.color.y);
            t.color.x = sum as f32;
        }
        lights.push(GpuLight {
            kind: LIGHT_EMITTER,
            nu: EMITTER_SAMPLES,
            nv: tris.len() as u32,
            color: materials[m as usize].emission,
            first: triangles.len() as u32,
            ..Default::default()
        });
        triangles.append(&mut tris);
    }
    (lights, triangles)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::gpu_types::{PRIM_KIND_SHIFT, PRIM_SPHERE};

    fn tri(v: [Vec3; 3], material: u32) -> GpuPrim {
        GpuPrim {
            p0: v[0],
            p1: v[1],
            p2: v[2],
            tag: PRIM_TRIANGLE << PRIM_KIND_SHIFT | material,
            ..Default::default()
        }
    }

    #[test]
    fn each_emissive_material_is_one_light_over_its_triangles() {
        let lamp = Material {
            emission: Vec3::new(17.0, 12.0, 4.0),
            ..Material::DEFAULT
        };
        let materials = [Material::DEFAULT, lamp, lamp];
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let records = [
            tri([a, b, c], 2),
            tri([a, b, c], 0),
            tri([a, 2.0 * b, c], 1),
            // No area: not a light.
            tri([a, b, 2.0 * b], 1),
            GpuPrim {
                tag: PRIM_SPHERE << PRIM_KIND_SHIFT | 1,
                ..Default::default()
            },
            tri([b, c, a], 1),
        ];
        let (lights, tris) = emitters(&records, &materials);
        assert_eq!(lights.len(), 2);
        assert_eq!((lights[0].nv, lights[0].first), (2, 0));
        assert_eq!((lights[1].nv, lights[1].first), (1, 2));
        assert_eq!(lights[0].color, lamp.emission);
        assert_eq!(lights[0].nu, EMITTER_SAMPLES);
        // The summed area, then the triangle's own: 1 + 0.5, in the model's order.
        assert_eq!(tris[0].color.truncate(), glam::Vec2::new(1.0, 1.0));
        assert_eq!(tris[1].color.truncate(), glam::Vec2::new(1.5, 0.5));
        assert_eq!((tris[1].pos, tris[1].u, tris[1].v), (b, c - b, a - b));
        assert_eq!(tris[2].color.truncate(), glam::Vec2::new(0.5, 0.5));
    }
}
