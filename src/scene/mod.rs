//! Scenes: the data model (`model`, plain data produced by the readers and consumed by
//! `pack`), its bounds, reading files (`io`), and the readers.
//!
//! The readers (`nff`, `stl`, `obj`, `ply`, `gltf`) read a stream (`io::Input`: a file, or bytes in
//! memory) and give every bounded primitive to a `Sink` the moment it is read: into a
//! `Scene` (`load`), or straight into the renderers' records (`load_flat`), so that a
//! scene of any size is read holding nothing twice. `load*` open a file (gzip-aware) and
//! pick the reader by its first bytes and its extension (`sniff`).

pub mod animation;
pub mod auto;
pub mod bounds;
pub mod flat;
pub mod gltf;
pub mod images;
pub mod io;
pub mod lex;
pub mod mesh;
pub mod model;
pub mod mtl;
pub mod nff;
pub mod number;
pub mod obj;
pub mod options;
pub mod palette;
pub mod place;
pub mod ply;
pub mod sink;
pub mod sniff;
pub mod spline;
pub mod stl;
pub mod triangulate;

use std::path::Path;

pub use bounds::{Bounded, Bounds};
pub use flat::{Flat, FlatScene};
pub use model::{
    BoxPrim, Camera, Cone, Light, Material, MaterialId, Mesh, Plane, Scene, Sphere, Texture,
    Triangle, Wrap, nff_default_camera, unit,
};
pub use options::ReadOptions;
pub use sink::{Collect, Sink};

use crate::util::error::Result;
use io::FileKind;
use palette::Palette;
use sink::MeshOut;

/// Loads a scene file: NFF (with our extensions), or a bare STL/OBJ/PLY mesh that gets an
/// automatic camera, light, material and ground plane.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, &ReadOptions::default())
}

/// `load` with reading options.
pub fn load_with(path: &Path, opts: &ReadOptions) -> Result<Scene> {
    let mut prims = Collect::default();
    let mut scene = read(path, &mut prims, opts)?;
    prims.into_scene(&mut scene);
    Ok(scene)
}

/// Loads a scene file as `load` does, its bounded primitives straight into the records
/// the renderers read (`pack::pack_flat` builds its tree).
pub fn load_flat(path: &Path) -> Result<FlatScene> {
    load_flat_with(path, &ReadOptions::default())
}

/// `load_flat` with reading options.
pub fn load_flat_with(path: &Path, opts: &ReadOptions) -> Result<FlatScene> {
    let mut prims = Flat::new();
    let scene = read(path, &mut prims, opts)?;
    Ok(FlatScene { scene, prims })
}

/// What `load` would give, but for the bounded primitives, which are only counted and
/// bounded: what `gpurt info` prints, in memory that does not grow with the scene.
pub fn summary(path: &Path) -> Result<FlatScene> {
    summary_with(path, &ReadOptions::default())
}

/// `summary` with reading options.
pub fn summary_with(path: &Path, opts: &ReadOptions) -> Result<FlatScene> {
    let mut prims = Flat::counting();
    let scene = read(path, &mut prims, opts)?;
    Ok(FlatScene { scene, prims })
}

/// Reads the scene file at `path`, its bounded primitives into `sink`; returns the rest.
/// A bare mesh's faces get the materials of its OBJ's `.mtl` libraries, the neutral grey
/// (material 0) where they name none.
pub fn read(path: &Path, sink: &mut dyn Sink, opts: &ReadOptions) -> Result<Scene> {
    let input = io::open(path)?;
    let name = path.display().to_string();
    let dir = path.parent().unwrap_or(Path::new("."));
    read_input(input, FileKind::of(path), &name, dir, sink, opts)
}

/// Reads a scene from bytes in memory (plain or gzip) with the reader for `kind`, as
/// `load` reads a file with those contents: for callers that hold the bytes (a string in
/// Python, a dropped file in the browser). `name` names the scene in messages; an NFF
/// `mesh` include and an OBJ's `.mtl` libraries are looked for under `base`.
pub fn parse(bytes: &[u8], kind: FileKind, name: &str, base: &Path) -> Result<Scene> {
    parse_with(bytes, kind, name, base, &ReadOptions::default())
}

/// `parse` with reading options.
pub fn parse_with(
    bytes: &[u8],
    kind: FileKind,
    name: &str,
    base: &Path,
    opts: &ReadOptions,
) -> Result<Scene> {
    let mut prims = Collect::default();
    let mut scene = read_input(io::Input::bytes(bytes), kind, name, base, &mut prims, opts)?;
    prims.into_scene(&mut scene);
    Ok(scene)
}

/// Reads `input` with the reader for `kind`, its bounded primitives into `sink`.
fn read_input(
    input: io::Input,
    kind: FileKind,
    name: &str,
    dir: &Path,
    sink: &mut dyn Sink,
    opts: &ReadOptions,
) -> Result<Scene> {
    let (input, kind) = sniff::sniff(input, kind, name)?;
    match kind {
        FileKind::Gltf => gltf::read(input, name, dir, sink),
        FileKind::Nff => nff::read(
            lex::Lexer::through(input, name, opts.window),
            dir,
            sink,
            opts,
        ),
        kind => {
            let mut scene = Scene::new(name, nff_default_camera());
            let mut palette = Palette::default();
            let grey = palette.id(&mut scene.materials, Material::NEUTRAL_GREY);
            let mut out = MeshOut {
                sink,
                warnings: &mut scene.warnings,
                materials: &mut scene.materials,
                palette: &mut palette,
                textures: &mut scene.textures,
                default: grey,
                mtl: true,
                dir: Some(dir),
                window: opts.window,
            };
            mesh::read(input, kind, name, &mut out)?;
            auto::frame_mesh(&mut scene, sink.bounds())?;
            Ok(scene)
        }
    }
}
