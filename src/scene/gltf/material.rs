//! glTF's metallic-roughness materials on the Whitted model: one table, documented in
//! docs/scene-format.md ("glTF materials"), written here once.

use glam::Vec3;

use crate::scene::model::Material;
use crate::util::limits::MAX_LIGHT;

/// The Whitted material of glTF material `m`:
///
/// - colour: the base colour factor's red, green and blue (alpha is not read);
/// - Ks, the highlight's weight and the mirror's: the Fresnel reflectance at normal
///   incidence, 0.04 for a dielectric and 1 for a metal, mixed by `metallic`, times
///   `1 - roughness` (a rough surface mirrors nothing);
/// - Kd: `1 - metallic` (metals have no diffuse term), less the light transmitted;
/// - Shine: the Blinn-Phong exponent of the same highlight width as GGX's roughness,
///   `2 / a^2 - 2` with `a = roughness^2`, between 1 and 10^4;
/// - T: `KHR_materials_transmission`'s factor; ior: `KHR_materials_ior`'s (1.5 without);
/// - emission: the emissive factor times `KHR_materials_emissive_strength`'s strength (1
///   without): the radiance of an emitter, whose triangles light the scene.
pub fn whitted(m: &gltf::Material) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let (base, metallic, roughness) = (
        pbr.base_color_factor(),
        pbr.metallic_factor(),
        pbr.roughness_factor(),
    );
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let ior = m.ior().unwrap_or(1.5);
    let strength = m.emissive_strength().unwrap_or(1.0);
    let clamp = |x: f32| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let (metallic, roughness, t) = (clamp(metallic), clamp(roughness), clamp(transmission));
    let reflect = 0.04 + 0.96 * metallic;
    let a = (roughness * roughness).max(1e-4);
    Material {
        color: Vec3::from_slice(&base[..3]).map(clamp),
        kd: (1.0 - metallic) * (1.0 - t),
        ks: reflect * (1.0 - roughness),
        shine: (2.0 / (a * a) - 2.0).clamp(1.0, 1e4),
        t,
        ior: if ior.is_finite() && ior >= 1.0 {
            ior
        } else {
            1.5
        },
        emission: (Vec3::from(m.emissive_factor()) * strength).map(|e| {
            if e.is_finite() {
                e.clamp(0.0, MAX_LIGHT)
            } else {
                0.0
            }
        }),
        texture: None,
    }
}
