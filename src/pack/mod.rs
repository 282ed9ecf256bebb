//! Scene + BVH -> `SceneBuffers`: the flat arrays both renderers read (one `Vec` per GPU
//! binding), with the camera, background and ambient the frames of `frame` start from.

use std::borrow::Cow;
use std::sync::{Arc, OnceLock};

use glam::Vec3;

use crate::bvh::blocks::Blocks;
use crate::bvh::wide;
use crate::bvh::{self, FlatBvh};
use crate::gpu_types::*;
use crate::scene::flat::{self, FlatScene};
use crate::scene::{Bounds, Camera, Light, Scene, Sink, Texture, Wrap};
use crate::util::error::{Error, Result};
use crate::util::limits::{DEFAULT_SPP, MAX_DEPTH, MAX_TEXELS};

mod build;
mod check;
mod emitters;
pub mod frames;
mod trees;

pub use emitters::EMITTER_SAMPLES;
pub use trees::GpuCwide;

/// Secondary rays start this fraction of the scene's size (bounds diagonal) away from the
/// surface, along the geometric normal; shading.md leaves the constant to us. It must clear
/// the f32 rounding of hit points (about 1e-7 of the coordinates, which stay within the
/// bounds) with a wide margin, and stay below the smallest features: balls-6, whose floor
/// makes the diagonal 34, has spheres of radius 7e-4, which this keeps at 1.7e-4.
pub const EPSILON_REL: f32 = 5e-6;

/// The flat scene: what is uploaded to the GPU and what the CPU reference traverses.
#[derive(Clone, Debug)]
pub struct SceneBuffers {
    /// The binary tree, which the GPU's walks read (and build their own trees from), empty
    /// once `for_cpu_alone` has dropped it.
    pub nodes: Vec<GpuNode>,
    /// Nodes of the binary tree as built, kept when `for_cpu_alone` drops them
    /// (`GpuGlobals::n_nodes`, `--stats`).
    node_count: usize,
    /// Bounded primitives in BVH leaf order: a primitive that spatial splits put in
    /// several leaves (`bvh::spatial`) has a record in each.
    pub prims: Vec<GpuPrim>,
    /// How many of `prims` are such copies.
    pub copies: usize,
    pub tri_normals: Vec<GpuTriNormals>,
    /// Texture coordinates, which the shader reads after `tri_normals` (`surface_texels`).
    pub tri_uvs: Vec<GpuTriUvs>,
    /// The textures' headers and their texels (linear RGB, each a texel), which the shader
    /// reads after `tri_uvs`: a header's `first` counts from the first header.
    pub textures: Vec<GpuTexture>,
    /// Shared: a sequence's frames all hold the one copy (`pack::frames`).
    pub texels: Arc<[glam::Vec4]>,
    pub planes: Vec<GpuPlane>,
    pub materials: Vec<GpuMaterial>,
    /// The scene's lights, then one `LIGHT_EMITTER` per emissive material
    /// (`emitters::emitters`).
    pub lights: Vec<GpuLight>,
    /// The emitters' triangles (`GpuLight`), which travel after `lights` in the shader's
    /// lights buffer.
    pub emitter_triangles: Vec<GpuLight>,
    /// Scene bounds (planes excluded) and the secondary-ray offset derived from them.
    pub bounds: Bounds,
    pub epsilon: f32,
    pub bvh_depth: usize,
    /// The build the BVH got (for the render it was packed for).
    pub bvh_quality: bvh::Quality,
    /// How the GPU's wide trees gather the binary tree's nodes (`GPURT_COLLAPSE`).
    pub gpu_collapse: wide::Collapse,
    /// The scene's camera, background and `am` (`None`: the default), kept here so that
    /// the `Scene` can be dropped once packed.
    pub camera: Camera,
    pub background: Vec3,
    pub ambient: Option<Vec3>,
    /// The CPU renderer's eight-wide copy of `nodes`, built on its first render
    /// (`wide_nodes`): a scene rendered only on the GPU never pays for it.
    wide: OnceLock<wide::Tree>,
    /// The CPU renderer's triangle leaves in blocks of up to four (`bvh::blocks`), built from
    /// `wide`'s leaves.
    blocks: OnceLock<Blocks>,
    /// `nodes` collapsed four wide as the GPU's wide walk reads them (`gpu_wide_nodes`),
    /// and the stack entries that walk needs, built on its first upload for that walk.
    gpu_wide: OnceLock<Option<(Vec<GpuWideNode>, u32)>>,
    /// `nodes` as the compressed eight-wide tree of the GPU's `TRAVERSAL_CWIDE` walk
    /// (`gpu_cwide`), built on its first upload for that walk.
    gpu_cwide: OnceLock<Option<GpuCwide>>,
    /// The four-wide tree with its boxes quantised, as the `TRAVERSAL_QWIDE` walk reads
    /// it (`gpu_qwide_nodes`), built on its first upload for that walk.
    gpu_qwide: OnceLock<Option<Vec<GpuQwideNode>>>,
}

/// Flattens a scene for one frame of the camera's own resolution at `DEFAULT_SPP` samples
/// per pixel (the default options, `RenderOptions::for_camera`).
pub fn pack(scene: Scene) -> Result<SceneBuffers> {
    let c = &scene.camera;
    let samples = u64::from(c.width) * u64::from(c.height) * u64::from(DEFAULT_SPP);
    pack_for(scene, samples)
}

/// Flattens a scene, consuming it, with the BVH a render of `samples` camera samples
/// should get (`bvh::Quality::chosen`): its primitives are moved into records kind by
/// kind (`FlatScene::from_scene`), then packed as `pack_flat` packs a scene read straight
/// into records. Fails only on scenes beyond the layout's limits.
pub fn pack_for(scene: Scene, samples: u64) -> Result<SceneBuffers> {
    pack_flat(FlatScene::from_scene(scene), samples)
}

/// Packs a scene read into records (`scene::load_flat`), consuming it: the BVH is built
/// over the records' bounds, worked out from them a group at a time; the records are put
/// in the tree's leaf order in place, and the triangles' turned into edges. Nothing is
/// copied whole, so the peak is the records, the tree and the builder's share of one
/// group (`bvh::build_chunk`).
pub fn pack_flat(flat: FlatScene, samples: u64) -> Result<SceneBuffers> {
    let FlatScene { scene, prims } = flat;
    check_surfaces(&scene, prims.normals(), prims.uvs())?;
    let bounds = prims.bounds();
    let (mut records, tri_normals, tri_uvs) = prims.into_records();
    let emitters = emitters::emitters(&records, &scene.materials);
    let quality = bvh::Quality::chosen(records.len(), samples).map_err(Error::Render)?;
    let (tree, copies) = build::build_in_leaf_order(&mut records, &scene.materials, quality);
    assemble(
        scene,
        Packed {
            records,
            tri_normals,
            tri_uvs,
            emitters,
            tree,
            quality,
            bounds,
            textures: None,
            copies,
        },
    )
}

/// A scene's bounded primitives and their tree, as `assemble` takes them.
struct Packed {
    /// In the tree's leaf order, triangles still by their corners.
    records: Vec<GpuPrim>,
    tri_normals: Vec<GpuTriNormals>,
    tri_uvs: Vec<GpuTriUvs>,
    /// `emitters::emitters` of the records.
    emitters: (Vec<GpuLight>, Vec<GpuLight>),
    /// Its `order` already applied to `records`.
    tree: FlatBvh,
    quality: bvh::Quality,
    bounds: Bounds,
    /// The textures packed already (a sequence packs them once for all its frames);
    /// `None`: packed from the scene's.
    textures: Option<Textures>,
    /// Records that are copies, of primitives spatial splits put in several leaves.
    copies: usize,
}

/// Textures' headers and texels, as `SceneBuffers` holds them.
type Textures = (Vec<GpuTexture>, Arc<[glam::Vec4]>);

/// Refuses a scene whose normals and texture coordinates (`normals`, `uvs` triangles'
/// worth) would not fit the records' slots.
fn check_surfaces(scene: &Scene, normals: usize, uvs: usize) -> Result<()> {
    if normals + uvs > 1 << 24 {
        return Err(Error::Scene {
            file: scene.name.clone(),
            msg: format!(
                "{normals} triangles with shading normals and {uvs} with texture coordinates exceed the limit of 2^24 together"
            ),
        });
    }
    Ok(())
}

/// The buffers of `scene` (its primitives taken out) and its primitives `packed` with
/// their tree: materials, planes, lights and textures in the layout's form, the
/// triangles turned into edges.
fn assemble(scene: Scene, packed: Packed) -> Result<SceneBuffers> {
    let Packed {
        mut records,
        tri_normals,
        tri_uvs,
        emitters: (mut emitters, emitter_triangles),
        tree,
        quality,
        bounds,
        textures,
        copies,
    } = packed;
    let too_big = |msg: String| Error::Scene {
        file: scene.name.clone(),
        msg,
    };
    if scene.materials.len() > PRIM_MATERIAL_MASK as usize {
        return Err(too_big(format!(
            "{} materials exceed the limit of {}",
            scene.materials.len(),
            PRIM_MATERIAL_MASK
        )));
    }
    let epsilon = epsilon(bounds, &scene.camera);
    let planes = scene
        .planes
        .iter()
        .map(|p| GpuPlane {
            normal: p.normal,
            d: p.normal.dot(p.point),
            material: p.material.0,
            _pad: [0; 3],
        })
        .collect();
    let materials = scene
        .materials
        .iter()
        .map(|m| GpuMaterial {
            color: m.color,
            kd: m.kd,
            ks: m.ks,
            shine: m.shine,
            t: m.t,
            ior: m.ior,
            emission: m.emission,
            texture: m.texture.unwrap_or(NO_TEXTURE),
            ambient: m.ambient.unwrap_or(m.kd * m.color),
            _pad: 0,
        })
        .collect();
    let (textures, texels) = match textures {
        Some(t) => t,
        None => pack_textures(&scene.textures).map_err(too_big)?,
    };
    let mut lights = pack_lights(&scene.lights);
    lights.append(&mut emitters);
    let (camera, background, ambient) = (scene.camera, scene.background, scene.ambient);
    let gpu_collapse = wide::Collapse::for_gpu().map_err(Error::Render)?;
    let FlatBvh { nodes, depth, .. } = tree;
    flat::to_edges(&mut records);
    Ok(SceneBuffers {
        node_count: nodes.len(),
        nodes,
        copies,
        prims: records,
        tri_normals,
        tri_uvs,
        textures,
        texels,
        planes,
        materials,
        lights,
        emitter_triangles,
        bounds,
        epsilon,
        bvh_depth: depth,
        bvh_quality: quality,
        gpu_collapse,
        camera,
        background,
        ambient,
        wide: OnceLock::new(),
        blocks: OnceLock::new(),
        gpu_wide: OnceLock::new(),
        gpu_cwide: OnceLock::new(),
        gpu_qwide: OnceLock::new(),
    })
}

/// `SceneBuffers::trace_stack` for a scene's materials; the CPU twin checks its own
/// stack against it.
pub fn trace_stack(materials: &[GpuMaterial], max_depth: u32) -> u32 {
    if materials.iter().any(|m| m.ks > 0.0 && m.t > 0.0) {
        max_depth.clamp(1, MAX_DEPTH)
    } else {
        1
    }
}

impl SceneBuffers {
    /// The shader's texels of triangle surfaces: `tri_normals`, then `tri_uvs`, then the
    /// textures' headers and texels; borrowed where only normals exist (most scenes), so
    /// that a large mesh's normals are not copied for the upload.
    pub fn surface_texels(&self) -> Cow<'_, [u8]> {
        let parts: [&[u8]; 4] = [
            bytemuck::cast_slice(&self.tri_normals),
            bytemuck::cast_slice(&self.tri_uvs),
            bytemuck::cast_slice(&self.textures),
            bytemuck::cast_slice(&self.texels[..]),
        ];
        if parts[1..].iter().all(|p| p.is_empty()) {
            Cow::Borrowed(parts[0])
        } else {
            Cow::Owned(parts.concat())
        }
    }

    /// The length of `surface_texels` in bytes, without assembling it.
    pub fn surface_texel_bytes(&self) -> usize {
        size_of_val(&self.tri_normals[..])
            + size_of_val(&self.tri_uvs[..])
            + size_of_val(&self.textures[..])
            + size_of_val(&self.texels[..])
    }

    /// The texel of `surface_texels` where the textures' headers start (three a record
    /// before them).
    pub fn textures_at(&self) -> u32 {
        3 * (self.tri_normals.len() + self.tri_uvs.len()) as u32
    }

    /// The shader's lights buffer: `lights`, then `emitter_triangles` (borrowed where there
    /// are none).
    pub fn gpu_lights(&self) -> Cow<'_, [GpuLight]> {
        if self.emitter_triangles.is_empty() {
            Cow::Borrowed(&self.lights)
        } else {
            Cow::Owned([&self.lights[..], &self.emitter_triangles[..]].concat())
        }
    }

    /// The length of `gpu_lights` in bytes, without assembling it.
    pub fn gpu_light_bytes(&self) -> usize {
        size_of_val(&self.lights[..]) + size_of_val(&self.emitter_triangles[..])
    }

    /// Pending rays `trace` can hold at once on this scene with rays `max_depth` deep
    /// (the length of the shader's ray stack, `TRACE_STACK`). A surface pushes its
    /// reflected and its refracted ray, then the refracted one is taken: each level holds
    /// one ray more only where some material both reflects and transmits, so the stack
    /// holds `max_depth` rays there (one waiting per level above the deepest, and the
    /// deepest), and one elsewhere.
    pub fn trace_stack(&self, max_depth: u32) -> u32 {
        trace_stack(&self.materials, max_depth)
    }
}

/// The secondary-ray offset: `EPSILON_REL` times the diagonal of the bounds `b` (or the
/// viewing distance for a scene of planes only).
pub fn epsilon(b: Bounds, camera: &Camera) -> f32 {
    let size = if b.is_empty() {
        (camera.at - camera.from).length()
    } else {
        b.extent().length()
    };
    EPSILON_REL * size.max(1e-3)
}

/// The textures' headers and texels (`SceneBuffers::textures`), or why they cannot be
/// held: more texels than `MAX_TEXELS`.
fn pack_textures(textures: &[Texture]) -> std::result::Result<Textures, String> {
    let total: u64 = textures.iter().map(|t| t.texels.len() as u64).sum();
    if total > MAX_TEXELS {
        return Err(format!(
            "{total} texels of textures exceed the limit of {MAX_TEXELS}"
        ));
    }
    let code = |w: Wrap| match w {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::Clamp => WRAP_CLAMP,
        Wrap::Mirror => WRAP_MIRROR,
    };
    let mut first = textures.len() as u32;
    let mut headers = Vec::with_capacity(textures.len());
    let mut texels = Vec::with_capacity(total as usize);
    for t in textures {
        headers.push(GpuTexture {
            first,
            width: t.width,
            height: t.height,
            wrap: code(t.wrap[0]) | code(t.wrap[1]) << 2,
        });
        texels.extend(t.texels.iter().map(|c| c.extend(1.0)));
        first += t.texels.len() as u32;
    }
    Ok((headers, texels.into()))
}

/// Uncoloured lights get SPD's intensity `1/sqrt(number of lights)`.
fn pack_lights(lights: &[Light]) -> Vec<GpuLight> {
    let default = Vec3::splat(1.0 / (lights.len().max(1) as f32).sqrt());
    lights
        .iter()
        .map(|l| match *l {
            Light::Point { position, color } => GpuLight {
                pos: position,
                kind: LIGHT_POINT,
                color: color.unwrap_or(default),
                ..Default::default()
            },
            Light::Directional { direction, color } => GpuLight {
                // Stored as the direction towards the light.
                pos: -direction,
                kind: LIGHT_DIRECTIONAL,
                color: color.unwrap_or(default),
                ..Default::default()
            },
            Light::Area {
                corner,
                u,
                v,
                color,
                samples,
            } => GpuLight {
                pos: corner,
                kind: LIGHT_AREA,
                u,
                nu: samples[0],
                v,
                nv: samples[1],
                color,
                first: 0,
            },
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::nff;
    use crate::util::limits::DEFAULT_DEPTH;

    /// The render constants `check` compares with the buffers, as `frame::globals` sets
    /// them for the default options.
    fn globals(b: &SceneBuffers) -> GpuGlobals {
        GpuGlobals {
            max_depth: DEFAULT_DEPTH,
            spp: DEFAULT_SPP,
            n_nodes: b.nodes.len() as u32,
            n_planes: b.planes.len() as u32,
            n_lights: b.lights.len() as u32,
            traversal: TRAVERSAL_SINGLE,
            textures_at: b.textures_at(),
            ..GpuGlobals::default()
        }
    }

    fn balls() -> Scene {
        let src = b"v from 0 -5 1 at 0 0 0 up 0 0 1 angle 40 resolution 8 8
            l 1 -2 3
            l -1 -2 3 0.5 0.5 0.5
            f 1 0 0 1 0 1 0 1
            s 0 0 0 1  s 2 0 0 0.5  s -2 0 0 0.5  s 0 0 2 0.3  s 0 2 0 0.4  s 1 1 1 0.2
            p 3 -3 -3 -1  3 -3 -1  0 3 -1";
        nff::parse(src, "t.nff", std::path::Path::new(".")).unwrap()
    }

    /// The stack a walk needs is read off that walk's own tree: the compressed tree, and
    /// its reordered copy of every primitive, is never built for another walk.
    #[test]
    fn each_walk_builds_only_its_own_tree() {
        for (traversal, built) in [
            (TRAVERSAL_SINGLE, (false, false, false)),
            (TRAVERSAL_PAIRS, (false, false, false)),
            (TRAVERSAL_WIDE, (true, false, false)),
            (TRAVERSAL_CWIDE, (false, true, false)),
            (TRAVERSAL_QWIDE, (true, false, true)),
        ] {
            let b = pack(balls()).unwrap();
            b.stack_entries(traversal);
            b.traversal_for(traversal);
            assert_eq!(
                b.trees_built(),
                built,
                "{}",
                TRAVERSAL_NAMES[traversal as usize]
            );
        }
    }

    #[test]
    fn packed_scene_passes_its_checks_and_corruption_is_caught() {
        let b = pack(balls()).unwrap();
        let g = globals(&b);
        b.check(&g).unwrap();
        let mut cpu = b.clone();
        cpu.for_cpu_alone(AOV_COLOR);
        assert!(cpu.is_cpu_only() && cpu.check_for_gpu(&g).is_err());
        cpu.check(&g).unwrap();
        let inner = b.nodes.iter().position(|n| n.count() == 0).unwrap();

        let mut bad = b.clone();
        bad.nodes[inner].offset = inner as u32; // a cycle
        assert!(bad.check(&g).is_err());
        let mut bad = b.clone();
        let leaf = bad.nodes.iter().position(|n| n.count() > 0).unwrap();
        bad.nodes[leaf].offset = bad.prims.len() as u32;
        assert!(bad.check(&g).is_err());
        let mut bad = b.clone();
        bad.prims[0].tag = PRIM_SPHERE << PRIM_KIND_SHIFT | 99;
        assert!(bad.check(&g).is_err());
        let deep = GpuGlobals {
            max_depth: MAX_DEPTH + 1,
            ..g
        };
        assert!(b.check(&deep).is_err());
    }

    #[test]
    fn uncoloured_lights_share_spd_intensity_and_coloured_keep_theirs() {
        let b = pack(balls()).unwrap();
        let grey = 1.0 / 2f32.sqrt();
        assert_eq!(b.lights[0].color, Vec3::splat(grey));
        assert_eq!(b.lights[1].color, Vec3::splat(0.5));
    }
}
