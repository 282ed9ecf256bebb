//! Where a reader puts the bounded primitives it reads, the moment it reads them: a
//! `Sink`. Into `Scene`'s vectors (`Collect`: the plain data model, for tests, tools and
//! small scenes), or straight into the packed records the renderers read (`flat::Flat`),
//! so that a large scene is never held twice. Everything else a scene holds (camera,
//! lights, materials, planes, warnings) is small and goes into a `Scene` whose primitive
//! vectors stay empty.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::bounds::Bounds;
pub use super::model::Collect;
use super::model::{BoxPrim, Cone, Material, MaterialId, Mesh, Scene, Sphere, Texture, Triangle};
use super::palette::Palette;
use crate::util::error::Result;

/// Takes a reader's bounded primitives in the order it reads them.
pub trait Sink {
    fn sphere(&mut self, s: Sphere);
    /// A triangle, with its unit shading normals and its texture coordinates if it has
    /// them.
    fn triangle(
        &mut self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
        material: MaterialId,
    );
    fn cone(&mut self, c: Cone);
    fn cuboid(&mut self, b: BoxPrim);
    /// Bounded primitives taken so far (held to `limits::MAX_PRIMITIVES` by the readers).
    fn count(&self) -> usize;
    /// The bounds of every primitive taken so far.
    fn bounds(&self) -> Bounds;
}

/// Where a mesh file's reader puts what it reads: its triangles into `sink`, what it drops
/// or skips into `warnings`, and the materials of an OBJ's `.mtl` libraries into the
/// scene's `materials` (through its `palette`), their images into its `textures`.
pub struct MeshOut<'a> {
    pub sink: &'a mut dyn Sink,
    pub warnings: &'a mut Vec<String>,
    pub materials: &'a mut Vec<Material>,
    pub palette: &'a mut Palette,
    pub textures: &'a mut Vec<Texture>,
    /// The material of faces without one of their own: every STL triangle, OBJ faces
    /// before any `usemtl` or under one whose material no library defines.
    pub default: MaterialId,
    /// Whether an OBJ's `mtllib` and `usemtl` are read (else every face gets `default`).
    pub mtl: bool,
    /// The directory `mtllib` names are relative to (the OBJ's own; `None` for bytes that
    /// come from no file, whose libraries cannot be found).
    pub dir: Option<&'a Path>,
    /// The window the mesh and its libraries are read through (`ReadOptions::window`).
    pub window: Option<usize>,
}

impl MeshOut<'_> {
    /// A mesh read by `read` from bytes that come from no file: its triangles of material
    /// 0 (an OBJ's libraries are not read) and its warnings.
    pub fn collect(read: impl FnOnce(&mut MeshOut) -> Result<()>) -> Result<Mesh> {
        let mut tris = Collect::default();
        let mut warnings = Vec::new();
        let mut out = MeshOut {
            sink: &mut tris,
            warnings: &mut warnings,
            materials: &mut Vec::new(),
            palette: &mut Palette::default(),
            textures: &mut Vec::new(),
            default: MaterialId(0),
            mtl: false,
            dir: None,
            window: None,
        };
        read(&mut out)?;
        Ok(Mesh {
            triangles: tris.into_triangles(),
            warnings,
        })
    }
}

impl Collect {
    /// Moves the primitives into `scene` (whose own vectors of them are empty).
    pub fn into_scene(self, scene: &mut Scene) {
        scene.spheres = self.spheres;
        scene.triangles = self.triangles;
        scene.cones = self.cones;
        scene.boxes = self.boxes;
    }

    /// How many of each kind: spheres, triangles, cones, boxes.
    pub fn counts(&self) -> [usize; 4] {
        [
            self.spheres.len(),
            self.triangles.len(),
            self.cones.len(),
            self.boxes.len(),
        ]
    }

    /// Adds the primitives to those `scene` holds.
    pub fn append_to(self, scene: &mut Scene) {
        scene.spheres.extend(self.spheres);
        scene.triangles.extend(self.triangles);
        scene.cones.extend(self.cones);
        scene.boxes.extend(self.boxes);
    }
}

impl Collect {
    /// Gives every primitive to `sink`, in the order of `Scene::emit`.
    pub fn emit(&self, sink: &mut dyn Sink) {
        emit(
            &self.spheres,
            &self.triangles,
            &self.cones,
            &self.boxes,
            sink,
        );
    }

    /// The triangles alone (what a mesh file holds).
    pub fn into_triangles(self) -> Vec<Triangle> {
        self.triangles
    }
}

impl Sink for Collect {
    fn sphere(&mut self, s: Sphere) {
        self.spheres.push(s);
    }
    fn triangle(
        &mut self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
        material: MaterialId,
    ) {
        self.triangles.push(Triangle {
            v,
            n: n.map(Box::new),
            material,
            uv: uv.map(Box::new),
        });
    }
    fn cone(&mut self, c: Cone) {
        self.cones.push(c);
    }
    fn cuboid(&mut self, b: BoxPrim) {
        self.boxes.push(b);
    }
    fn count(&self) -> usize {
        self.spheres.len() + self.triangles.len() + self.cones.len() + self.boxes.len()
    }
    fn bounds(&self) -> Bounds {
        let spheres = self.spheres.iter().map(Sphere::bounds);
        let triangles = self.triangles.iter().map(Triangle::bounds);
        let cones = self.cones.iter().map(Cone::bounds);
        let boxes = self.boxes.iter().map(BoxPrim::bounds);
        spheres
            .chain(triangles)
            .chain(cones)
            .chain(boxes)
            .fold(Bounds::EMPTY, Bounds::union)
    }
}

impl Scene {
    /// Gives every bounded primitive to `sink`, in the order of `bounded_prims`.
    pub fn emit(&self, sink: &mut dyn Sink) {
        emit(
            &self.spheres,
            &self.triangles,
            &self.cones,
            &self.boxes,
            sink,
        );
    }
}

/// Primitives into `sink`, kind by kind.
fn emit(
    spheres: &[Sphere],
    triangles: &[Triangle],
    cones: &[Cone],
    boxes: &[BoxPrim],
    sink: &mut dyn Sink,
) {
    for s in spheres {
        sink.sphere(*s);
    }
    for t in triangles {
        sink.triangle(
            t.v,
            t.n.as_deref().copied(),
            t.uv.as_deref().copied(),
            t.material,
        );
    }
    for c in cones {
        sink.cone(*c);
    }
    for b in boxes {
        sink.cuboid(*b);
    }
}
