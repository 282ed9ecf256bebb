//! Scenes: the data model (`model`, plain data produced by the readers and consumed by
//! `pack`), its bounds, reading files (`io`), and the readers.
//!
//! Readers (`nff`, `stl`, `obj`) take text or bytes plus a display name for error
//! messages; `load` reads a file from disk (gzip-aware) and picks the reader by extension.

pub mod auto;
pub mod bounds;
pub mod io;
pub mod lex;
pub mod mesh;
pub mod model;
pub mod nff;
pub mod obj;
pub mod stl;
pub mod triangulate;

use std::path::Path;

pub use bounds::{Bounded, Bounds};
pub use model::{
    BoxPrim, Camera, Cone, Light, Material, MaterialId, Mesh, Plane, Scene, Sphere, Triangle,
    nff_default_camera, unit,
};

use crate::error::Result;
use io::{FileKind, read_file};

/// Loads a scene file: NFF (with our extensions), or a bare STL/OBJ mesh that gets an
/// automatic camera, light, material and ground plane.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = read_file(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    parse(
        &bytes,
        FileKind::of(path),
        &path.display().to_string(),
        base,
    )
}

/// Reads a scene from a file's (decompressed) bytes with the reader for `kind`: what
/// `load` does after reading, for callers that hold the bytes (a string in Python, a
/// dropped file in the browser). `name` names the scene in messages; an NFF `mesh`
/// include is looked for under `base`.
pub fn parse(bytes: &[u8], kind: FileKind, name: &str, base: &Path) -> Result<Scene> {
    match kind {
        FileKind::Nff => nff::parse(bytes, name, base),
        kind => {
            let mesh = mesh::parse_mesh(bytes, kind, name)?;
            let mut scene = auto::scene_for_mesh(name, mesh.triangles)?;
            scene.warnings.extend(mesh.warnings);
            Ok(scene)
        }
    }
}
