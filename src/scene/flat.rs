//! A scene's bounded primitives read straight into the records the renderers read
//! (`GpuPrim`, `GpuTriNormals`): the `Sink` that `run::read` loads through, so that
//! no primitive is ever held in two forms. `pack` builds the tree over the records,
//! puts them in its leaf order in place, and turns the triangles into edges.
//!
//! The records keep the model's order, spheres, then triangles, cones and boxes, each in
//! reading order (the one order of `Scene::bounded_prims`, so that a scene packs the same
//! read either way). A triangle's record holds its three vertices until `to_edges`: its box
//! is then the very floats `Triangle::bounds` gives, and so is the tree.

use glam::{Vec2, Vec3};

use super::bounds::Bounds;
use super::model::{BoxPrim, Cone, MaterialId, Scene, Sphere, unit};
use super::sink::Sink;
use crate::gpu_types::{
    GpuPrim, GpuTriNormals, GpuTriUvs, PRIM_BOX, PRIM_CONE, PRIM_KIND_SHIFT, PRIM_SPHERE,
    PRIM_TRIANGLE,
};

/// Bounded primitives as packed records, by kind.
#[derive(Clone)]
pub struct Flat {
    /// The records of each kind (`PRIM_SPHERE` to `PRIM_BOX`), in reading order.
    parts: [Vec<GpuPrim>; 4],
    counts: [usize; 4],
    tri_normals: Vec<GpuTriNormals>,
    tri_uvs: Vec<GpuTriUvs>,
    bounds: Bounds,
    /// Triangles of some area and their summed area, by material: what `gpurt info` tells
    /// of an emitter (`pack` makes its light from the records).
    surface: Vec<(usize, f64)>,
    /// False for a sink that only counts and bounds (`gpurt info`).
    keep: bool,
}

impl Default for Flat {
    fn default() -> Self {
        Flat::new()
    }
}

impl Flat {
    pub fn new() -> Flat {
        Flat {
            parts: Default::default(),
            counts: [0; 4],
            tri_normals: Vec::new(),
            tri_uvs: Vec::new(),
            bounds: Bounds::EMPTY,
            surface: Vec::new(),
            keep: true,
        }
    }

    /// A sink that keeps no primitive, only their counts and bounds.
    pub fn counting() -> Flat {
        Flat {
            keep: false,
            ..Flat::new()
        }
    }

    /// Spheres, triangles, cones and boxes taken.
    pub fn counts(&self) -> [usize; 4] {
        self.counts
    }

    /// Triangles of some area and their summed area, of material `m`.
    pub fn surface(&self, m: MaterialId) -> (usize, f64) {
        self.surface.get(m.0 as usize).copied().unwrap_or_default()
    }

    /// Triangles with shading normals taken.
    pub fn normals(&self) -> usize {
        self.tri_normals.len()
    }

    /// The records in the model's order (triangles with their vertices, see `to_edges`),
    /// the triangles' shading normals, indexed by their records' normal slot, and their
    /// texture coordinates, by their uv slot less the number of normals' records (the
    /// shader reads both from one array, `SceneBuffers::surface_texels`).
    pub fn into_records(self) -> (Vec<GpuPrim>, Vec<GpuTriNormals>, Vec<GpuTriUvs>) {
        let mut records = concat(self.parts);
        let normals = self.tri_normals.len() as f32;
        if !self.tri_uvs.is_empty() {
            for p in records
                .iter_mut()
                .filter(|p| p.kind() == PRIM_TRIANGLE && p.f0 >= 0.0)
            {
                p.f0 += normals;
            }
        }
        (records, self.tri_normals, self.tri_uvs)
    }

    /// Triangles with texture coordinates taken.
    pub fn uvs(&self) -> usize {
        self.tri_uvs.len()
    }

    /// Counts a primitive of `kind` with bounds `b`; true when its record is kept.
    fn take(&mut self, kind: u32, b: Bounds) -> bool {
        self.counts[kind as usize] += 1;
        self.bounds = self.bounds.union(b);
        self.keep
    }
}

fn tag(kind: u32, material: MaterialId) -> u32 {
    kind << PRIM_KIND_SHIFT | material.0
}

/// The three normals scaled to unit length, or `None` when one has no direction.
fn unit3([a, b, c]: [Vec3; 3]) -> Option<[Vec3; 3]> {
    Some([unit(a)?, unit(b)?, unit(c)?])
}

impl Sink for Flat {
    fn sphere(&mut self, s: Sphere) {
        if self.take(PRIM_SPHERE, s.bounds()) {
            self.parts[PRIM_SPHERE as usize].push(GpuPrim {
                p0: s.center,
                f0: s.radius,
                tag: tag(PRIM_SPHERE, s.material),
                ..Default::default()
            });
        }
    }

    fn triangle(
        &mut self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
        material: MaterialId,
    ) {
        let b = Bounds {
            min: v[0].min(v[1]).min(v[2]),
            max: v[0].max(v[1]).max(v[2]),
        };
        let area = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
        if area > 0.0 && area.is_finite() {
            let m = material.0 as usize;
            if self.surface.len() <= m {
                self.surface.resize(m + 1, (0, 0.0));
            }
            self.surface[m].0 += 1;
            self.surface[m].1 += f64::from(area);
        }
        // Unit normals or none: one without a direction would make the interpolated
        // shading normal 0 / 0 and the pixel NaN, so such a triangle is shaded flat.
        if !self.take(PRIM_TRIANGLE, b) {
            return;
        }
        let slot = match n.and_then(unit3) {
            Some([n0, n1, n2]) => {
                self.tri_normals.push(GpuTriNormals {
                    n0,
                    n1,
                    n2,
                    ..Default::default()
                });
                (self.tri_normals.len() - 1) as f32
            }
            None => -1.0,
        };
        let uv_slot = match uv {
            Some([uv0, uv1, uv2]) => {
                self.tri_uvs.push(GpuTriUvs {
                    uv0,
                    uv1,
                    uv2,
                    ..Default::default()
                });
                (self.tri_uvs.len() - 1) as f32
            }
            None => -1.0,
        };
        self.parts[PRIM_TRIANGLE as usize].push(GpuPrim {
            p0: v[0],
            f0: uv_slot,
            p1: v[1],
            f1: slot,
            p2: v[2],
            tag: tag(PRIM_TRIANGLE, material),
        });
    }

    fn cone(&mut self, c: Cone) {
        if self.take(PRIM_CONE, c.bounds()) {
            self.parts[PRIM_CONE as usize].push(GpuPrim {
                p0: c.base,
                f0: c.base_radius,
                p1: c.apex,
                f1: c.apex_radius,
                tag: tag(PRIM_CONE, c.material),
                ..Default::default()
            });
        }
    }

    fn cuboid(&mut self, b: BoxPrim) {
        if self.take(PRIM_BOX, b.bounds()) {
            self.parts[PRIM_BOX as usize].push(GpuPrim {
                p0: b.min,
                p1: b.max,
                tag: tag(PRIM_BOX, b.material),
                ..Default::default()
            });
        }
    }

    fn count(&self) -> usize {
        self.counts.iter().sum()
    }

    fn bounds(&self) -> Bounds {
        self.bounds
    }
}

/// The parts one after another, in place in the largest (which a large scene's are
/// nearly all of), so that joining them never holds the scene twice.
fn concat(parts: [Vec<GpuPrim>; 4]) -> Vec<GpuPrim> {
    let mut parts = parts;
    let largest = (0..4).max_by_key(|&k| parts[k].len()).unwrap_or(0);
    let mut out = std::mem::take(&mut parts[largest]);
    out.reserve_exact(parts.iter().map(Vec::len).sum());
    let front: Vec<GpuPrim> = parts[..largest].concat();
    out.splice(0..0, front);
    for p in &parts[largest + 1..] {
        out.extend_from_slice(p);
    }
    out.shrink_to_fit();
    out
}

/// The box of a record as `Flat` holds it (a triangle by its vertices): the floats the
/// model's `bounds` gives for the primitive it was made from.
pub fn record_bounds(p: &GpuPrim) -> Bounds {
    match p.kind() {
        PRIM_SPHERE => {
            let r = Vec3::splat(p.f0.abs());
            Bounds {
                min: p.p0 - r,
                max: p.p0 + r,
            }
        }
        PRIM_TRIANGLE => Bounds {
            min: p.p0.min(p.p1).min(p.p2),
            max: p.p0.max(p.p1).max(p.p2),
        },
        PRIM_CONE => Cone {
            base: p.p0,
            base_radius: p.f0,
            apex: p.p1,
            apex_radius: p.f1,
            material: MaterialId(p.material()),
        }
        .bounds(),
        _ => Bounds {
            min: p.p0,
            max: p.p1,
        },
    }
}

/// Turns every triangle record into the layout's form, its first vertex and two edges
/// (`GpuPrim`), once the tree no longer needs its vertices.
pub fn to_edges(prims: &mut [GpuPrim]) {
    for p in prims.iter_mut().filter(|p| p.kind() == PRIM_TRIANGLE) {
        p.p1 -= p.p0;
        p.p2 -= p.p0;
    }
}

/// A scene read into packed records: everything but its bounded primitives in `scene`
/// (whose vectors of spheres, triangles, cones and boxes are empty), those in `prims`.
#[derive(Clone)]
pub struct FlatScene {
    pub scene: Scene,
    pub prims: Flat,
}

impl FlatScene {
    /// A scene of the data model, its primitives moved into records kind by kind.
    pub fn from_scene(scene: Scene) -> FlatScene {
        // A scene that moves packs as it is at its default time (`Read::still` picks
        // another for the command line, `Scene::at` for the library).
        let t = scene.animation.as_ref().map_or(0.0, |a| a.default_time());
        let mut scene = scene.at(t);
        let mut prims = Flat::new();
        for s in std::mem::take(&mut scene.spheres) {
            prims.sphere(s);
        }
        for t in std::mem::take(&mut scene.triangles) {
            prims.triangle(t.v, t.n.map(|n| *n), t.uv.map(|uv| *uv), t.material);
        }
        for c in std::mem::take(&mut scene.cones) {
            prims.cone(c);
        }
        for b in std::mem::take(&mut scene.boxes) {
            prims.cuboid(b);
        }
        FlatScene { scene, prims }
    }

    /// Bounded primitives: spheres, triangles, cones and boxes.
    pub fn counts(&self) -> [usize; 4] {
        self.prims.counts()
    }

    /// Bounds of every bounded primitive (planes are infinite and excluded).
    pub fn bounds(&self) -> Bounds {
        self.prims.bounds()
    }
}
