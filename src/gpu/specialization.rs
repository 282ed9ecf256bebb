//! Which parts of the shader a render can reach, as the values of the `override` constants
//! in `types.wgsl`. One pipeline is compiled per combination: code for primitive kinds,
//! lights and features the scene lacks is then compiled out.
//!
//! This matters most on lavapipe, which runs both sides of every `if` under a lane mask:
//! without it a sphere test also paid for the triangle, cone and box tests beside it.
//! The flags only remove unreachable code, so the image does not change; the CPU twin
//! keeps every branch.

use crate::gpu_types::*;
use crate::pack::SceneBuffers;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Specialization {
    pub spheres: bool,
    pub triangles: bool,
    pub cones: bool,
    pub boxes: bool,
    pub planes: bool,
    pub normals: bool,
    pub directional_lights: bool,
    pub area_lights: bool,
    /// Some material emits (seen, and its triangles lights).
    pub emitters: bool,
    /// Some material has a texture.
    pub textures: bool,
    pub reflection: bool,
    pub refraction: bool,
    pub lens: bool,
    pub multisample: bool,
    pub aov: u32,
    /// The highlight's model (`GpuGlobals::shading`): a Phong pipeline has no Blinn-Phong
    /// code.
    pub shading: u32,
    pub pairs: bool,
    pub wide: bool,
    pub cwide: bool,
    /// The wide walk reads quantised nodes (`TRAVERSAL_QWIDE`, with `wide`).
    pub qwide: bool,
    /// Count rays and node fetches by kind (`GpuGlobals::counters`).
    pub counters: bool,
    /// Trace shadow rays; off, every light reaches every surface facing it (set by the
    /// renderer, `GpuRenderer::with_shadow_rays`, for `gpurt bench`'s `shaded` pass).
    pub shadow_rays: bool,
    /// Entries of each invocation's traversal stack in workgroup memory: what the walk
    /// needs on this scene (`SceneBuffers::stack_entries`), rounded up to a multiple of 8
    /// so that few sizes are compiled. A smaller stack lets more workgroups share a
    /// compute unit: on the H100, 48 entries instead of 64 made 4K frames 2 to 9% faster.
    pub stack: u32,
    /// Length of `trace`'s ray stack (`SceneBuffers::trace_stack`). Not an override: WGSL
    /// sizes a function's array with a constant only, so it selects the shader source
    /// (`shaders::source`).
    pub trace_stack: u32,
    /// log2 of the texels in a layer of the node and primitive textures (set by the
    /// renderer from its device's limits).
    pub layer_shift: u32,
    /// The one kernel's entry point: `pooled` rather than `main` (set by the renderer,
    /// `policy::pooled_for`). Not an override either.
    pub pooled: bool,
}

impl Specialization {
    pub fn of(scene: &SceneBuffers, g: &GpuGlobals) -> Self {
        let kind = |k: u32| scene.prims.iter().any(|p| p.kind() == k);
        let light = |k: u32| scene.lights.iter().any(|l| l.kind == k);
        Specialization {
            spheres: kind(PRIM_SPHERE),
            triangles: kind(PRIM_TRIANGLE),
            cones: kind(PRIM_CONE),
            boxes: kind(PRIM_BOX),
            planes: !scene.planes.is_empty(),
            normals: !scene.tri_normals.is_empty(),
            directional_lights: light(LIGHT_DIRECTIONAL),
            area_lights: light(LIGHT_AREA),
            emitters: scene
                .materials
                .iter()
                .any(|m| m.emission != glam::Vec3::ZERO),
            textures: scene.materials.iter().any(|m| m.texture != NO_TEXTURE),
            reflection: scene.materials.iter().any(|m| m.ks > 0.0),
            refraction: scene.materials.iter().any(|m| m.t > 0.0),
            lens: g.aperture > 0.0,
            multisample: g.spp > 1,
            aov: g.aov,
            // The colour AOV alone shades; the others share the Phong pipeline.
            shading: if g.aov == AOV_COLOR {
                g.shading
            } else {
                SHADING_PHONG
            },
            pairs: g.traversal == TRAVERSAL_PAIRS,
            wide: g.traversal == TRAVERSAL_WIDE || g.traversal == TRAVERSAL_QWIDE,
            cwide: g.traversal == TRAVERSAL_CWIDE,
            qwide: g.traversal == TRAVERSAL_QWIDE,
            counters: g.counters != 0,
            shadow_rays: true,
            stack: scene.stack_entries(g.traversal).next_multiple_of(8),
            trace_stack: scene.trace_stack(g.max_depth),
            layer_shift: 0,
            pooled: false,
        }
    }

    /// The pipeline-overridable constants, by their WGSL names.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        let b = |v: bool| if v { 1.0 } else { 0.0 };
        vec![
            ("SPHERES", b(self.spheres)),
            ("TRIANGLES", b(self.triangles)),
            ("CONES", b(self.cones)),
            ("BOXES", b(self.boxes)),
            ("PLANES", b(self.planes)),
            ("NORMALS", b(self.normals)),
            ("DIRECTIONAL_LIGHTS", b(self.directional_lights)),
            ("AREA_LIGHTS", b(self.area_lights)),
            ("EMITTERS", b(self.emitters)),
            ("TEXTURES", b(self.textures)),
            ("REFLECTION", b(self.reflection)),
            ("REFRACTION", b(self.refraction)),
            ("LENS", b(self.lens)),
            ("MULTISAMPLE", b(self.multisample)),
            ("AOV", f64::from(self.aov)),
            ("SHADING", f64::from(self.shading)),
            ("PAIRS", b(self.pairs)),
            ("WIDE", b(self.wide)),
            ("CWIDE", b(self.cwide)),
            ("QWIDE", b(self.qwide)),
            ("COUNTERS", b(self.counters)),
            ("SHADOW_RAYS", b(self.shadow_rays)),
            ("STACK", f64::from(self.stack)),
            ("LAYER_SHIFT", f64::from(self.layer_shift)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every constant the host sets is an `override` in the shader, and every override
    /// is set (a missing one would silently keep its default).
    #[test]
    fn constants_name_exactly_the_shader_overrides() {
        let (module, _) = crate::gpu::shaders::validate(crate::gpu::shaders::Fetch::Textures)
            .expect("shader validates");
        let mut wgsl: Vec<String> = module
            .overrides
            .iter()
            .filter_map(|(_, o)| o.name.clone())
            .collect();
        let spec = Specialization {
            spheres: true,
            triangles: true,
            cones: true,
            boxes: true,
            planes: true,
            normals: true,
            directional_lights: true,
            area_lights: true,
            emitters: true,
            textures: true,
            reflection: true,
            refraction: true,
            lens: true,
            multisample: true,
            aov: 0,
            shading: SHADING_BLINN_PHONG,
            pairs: true,
            wide: true,
            cwide: true,
            qwide: true,
            counters: true,
            shadow_rays: false,
            stack: 64,
            trace_stack: 16,
            layer_shift: 25,
            pooled: true,
        };
        let mut host: Vec<String> = spec
            .constants()
            .iter()
            .map(|(n, _)| n.to_string())
            .collect();
        wgsl.sort();
        host.sort();
        assert_eq!(wgsl, host);
    }
}
