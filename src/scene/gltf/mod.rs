//! glTF 2.0 (`.gltf` with its buffers as files beside it or as data URIs, and `.glb`):
//! the default scene (else the first), its node hierarchy with each node's TRS or matrix,
//! the triangles of its meshes (indexed or not; strips and fans made triangles; points and
//! lines skipped with a warning), positions, normals and texture coordinates; materials on
//! the Whitted model with their base colour textures (`material`); the first perspective camera met as the view, and `KHR_lights_punctual`
//! point and directional lights (spot lights as point lights, with a warning). A file
//! with no camera is framed as a bare mesh is, and one with no light gets its light.
//!
//! Read with the `gltf` crate (JSON, `.glb` chunks, validation, accessor iteration); its
//! buffers resolved and its accessors checked here (`buffers`). glTF is not a stream: the
//! file and its buffers are held while the triangles go to the sink.

mod buffers;
mod material;

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use glam::{Affine2, Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::auto;
use super::io::{Input, read_error};
use super::model::{Light, MaterialId, Scene, nff_default_camera, unit};
use super::palette::Palette;
use super::sink::Sink;
use crate::util::error::{Error, Result};
use crate::util::limits::{MAX_FILE_BYTES, MAX_GLTF_JSON_BYTES, MAX_PRIMITIVES};

/// Node instances visited at most: a hierarchy that shares nodes can name exponentially
/// many, and one that loops, endlessly.
const MAX_INSTANCES: usize = 1 << 24;

/// Reads a glTF file (JSON or binary) into `sink` and a scene; `dir` is where buffers
/// named by relative paths are looked for.
pub fn read(mut input: Input, name: &str, dir: &Path, sink: &mut dyn Sink) -> Result<Scene> {
    let err = |msg: String| Error::Scene {
        file: name.to_string(),
        msg,
    };
    // JSON is read up to its bound and no further; a `.glb`'s binary chunk up to a file's.
    let mut bytes = Vec::new();
    let reader = &mut input.reader;
    let read = |reader: &mut dyn Read, limit: u64, bytes: &mut Vec<u8>| {
        reader
            .take(limit)
            .read_to_end(bytes)
            .map_err(|e| read_error(name, e))
    };
    read(reader, MAX_GLTF_JSON_BYTES + 1, &mut bytes)?;
    let json_bytes = if bytes.starts_with(b"glTF") {
        read(reader, MAX_FILE_BYTES - bytes.len() as u64, &mut bytes)?;
        bytes
            .get(12..16)
            .map_or(0, |b| u32::from_le_bytes(b.try_into().unwrap()).into())
    } else {
        bytes.len() as u64
    };
    if json_bytes > MAX_GLTF_JSON_BYTES {
        return Err(err(format!(
            "more than {} MiB of glTF JSON, which gpurt reads whole: a buffer this large belongs in a .bin file beside the model or a .glb's binary chunk, not a data URI",
            MAX_GLTF_JSON_BYTES >> 20
        )));
    }
    let (doc, blob) = document(&bytes, name)?;
    drop(bytes);
    let buffers = buffers::resolve(&doc, blob, name, Some(dir))?;
    let mut scene = Scene::new(name, nff_default_camera());
    // A model's usual backdrop (the bare meshes'), not NFF's black.
    scene.background = auto::BACKGROUND;
    let mut r = Reader {
        buffers,
        json: doc.as_json(),
        dir,
        materials: HashMap::new(),
        palette: Palette::default(),
        camera: None,
        instances: 0,
        err: &err,
    };
    let Some(root) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err(err("no scene".into()));
    };
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        root.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    stack.reverse();
    while let Some((node, parent, depth)) = stack.pop() {
        r.instances += 1;
        if depth > doc.nodes().len() || r.instances > MAX_INSTANCES {
            let why = if depth > doc.nodes().len() {
                "a cycle in the node hierarchy"
            } else {
                "more node instances than gpurt reads"
            };
            return Err(err(format!("{why} (at node {})", node.index())));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(err(format!(
                "node {}'s transform is not finite",
                node.index()
            )));
        }
        if let Some(mesh) = node.mesh() {
            r.mesh(&mesh, world, &mut scene, sink)?;
        }
        if let Some(cam) = node.camera() {
            r.view(&cam, world, &mut scene);
        }
        if let Some(light) = node.light() {
            light_of(&light, world, &mut scene);
        }
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world, depth + 1)));
    }
    let lights = std::mem::take(&mut scene.lights);
    if r.camera.is_none() {
        auto::frame_mesh(&mut scene, sink.bounds())?;
    } else if sink.bounds().is_empty() {
        return Err(err("the scene has no triangles".into()));
    }
    if !lights.is_empty() || scene.emits() {
        // The file's lights (and emitters) instead of the framing's.
        scene.lights = lights;
    } else if r.camera.is_some() {
        scene.lights.push(Light::Point {
            position: scene.camera.from,
            color: Some(Vec3::ONE),
        });
    }
    Ok(scene)
}

/// The file's document, validated, and its binary chunk. The crate's validation looks up
/// a primitive's POSITION accessor before checking that it exists (gltf-json 1.4.1,
/// `primitive_validate_hook`), and panics on a file whose index is past the accessors,
/// and its `.glb` reader on a header shorter than itself: such files are refused here
/// first.
fn document(bytes: &[u8], name: &str) -> Result<(gltf::Document, Option<Vec<u8>>)> {
    // The crate subtracts the header's size from the length it declares unchecked.
    if let Some(head) = bytes.strip_prefix(b"glTF") {
        let declared = head
            .get(4..8)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()));
        if declared.is_none_or(|n| n < 12) {
            return Err(Error::Binary {
                file: name.to_string(),
                offset: 8,
                msg: "a .glb header whose length is not that of a file (at least 12 bytes)".into(),
            });
        }
    }
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| parse_error(name, bytes, e))?;
    let json = document.into_json();
    for (i, mesh) in json.meshes.iter().enumerate() {
        for (k, p) in mesh.primitives.iter().enumerate() {
            if let Some(a) = p
                .attributes
                .values()
                .find(|a| a.value() >= json.accessors.len())
            {
                return Err(Error::Scene {
                    file: name.to_string(),
                    msg: format!("mesh {i} primitive {k} names accessor {a}, which does not exist"),
                });
            }
        }
    }
    let doc = gltf::Document::from_json(json).map_err(|e| parse_error(name, bytes, e))?;
    Ok((doc, blob))
}

/// A JSON error at its line and column; others (the `.glb` container, validation) as
/// the crate words them.
fn parse_error(name: &str, bytes: &[u8], e: gltf::Error) -> Error {
    match e {
        gltf::Error::Deserialize(j) if !bytes.starts_with(b"glTF") => Error::Parse {
            file: name.to_string(),
            line: j.line() as u32,
            col: j.column() as u32,
            msg: format!("not glTF JSON: {j}"),
            excerpt: None,
        },
        other => Error::Scene {
            file: name.to_string(),
            msg: format!("not a glTF file gpurt can read: {other}"),
        },
    }
}

struct Reader<'a> {
    buffers: Vec<Vec<u8>>,
    json: &'a gltf::json::Root,
    /// The model's folder, where images named by relative URIs are.
    dir: &'a Path,
    /// What each glTF material gave (by index; `None` the default material): the scene's
    /// material and the map of TEXCOORD_0 onto its texture.
    materials: HashMap<Option<usize>, (MaterialId, Affine2)>,
    palette: Palette,
    camera: Option<usize>,
    instances: usize,
    err: &'a dyn Fn(String) -> Error,
}

impl Reader<'_> {
    /// The scene's material for glTF material `m` (with its texture, read the first time
    /// it is named), and the map of TEXCOORD_0 onto the texture (`FLIP_V` without one).
    fn material(&mut self, m: gltf::Material, scene: &mut Scene) -> (MaterialId, Affine2) {
        if let Some(&known) = self.materials.get(&m.index()) {
            return known;
        }
        let mut whitted = material::whitted(&m);
        let images = material::Images {
            file: &scene.name,
            json: self.json,
            buffers: &self.buffers,
            dir: Some(self.dir),
        };
        let mut uv = material::FLIP_V;
        if let Some((texture, map)) =
            images.base_color(&m, &mut scene.textures, &mut scene.warnings)
        {
            (whitted.texture, uv) = (Some(texture), map);
        }
        let known = (self.palette.id(&mut scene.materials, whitted), uv);
        self.materials.insert(m.index(), known);
        known
    }

    /// The triangles of `mesh` placed by `world`, into `sink`.
    fn mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world: Mat4,
        scene: &mut Scene,
        sink: &mut dyn Sink,
    ) -> Result<()> {
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        for (k, prim) in mesh.primitives().enumerate() {
            let named = format!("mesh {} primitive {k}", mesh.index());
            let what = |s: &str| format!("{named} {s}");
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                scene.warnings.push(format!(
                    "{}: {named} skipped: gpurt renders triangles, not {mode:?}",
                    scene.name
                ));
                continue;
            }
            let Some(pos) = prim.get(&gltf::Semantic::Positions) else {
                return Err((self.err)(what("has no POSITION")));
            };
            buffers::check(
                &pos,
                Dimensions::Vec3,
                &[DataType::F32],
                &self.buffers,
                &what("POSITION"),
                self.err,
            )?;
            let normals = prim.get(&gltf::Semantic::Normals);
            if let Some(n) = &normals {
                buffers::check(
                    n,
                    Dimensions::Vec3,
                    &[DataType::F32],
                    &self.buffers,
                    &what("NORMAL"),
                    self.err,
                )?;
                if n.count() != pos.count() {
                    return Err((self.err)(what(
                        "has a NORMAL count other than its POSITION count",
                    )));
                }
            }
            if let Some(t) = prim.get(&gltf::Semantic::TexCoords(0)) {
                // Floats, or normalised bytes and shorts.
                let types = [DataType::F32, DataType::U8, DataType::U16];
                let what = what("TEXCOORD_0");
                buffers::check(&t, Dimensions::Vec2, &types, &self.buffers, &what, self.err)?;
                if t.count() != pos.count() {
                    return Err((self.err)(
                        what + " has a count other than its POSITION count",
                    ));
                }
            }
            if let Some(ix) = prim.indices() {
                let types = [DataType::U8, DataType::U16, DataType::U32];
                buffers::check(
                    &ix,
                    Dimensions::Scalar,
                    &types,
                    &self.buffers,
                    &what("indices"),
                    self.err,
                )?;
            }
            // Nothing to draw (and the crate's reader cannot take an empty accessor).
            if pos.count() == 0 || prim.indices().is_some_and(|ix| ix.count() == 0) {
                continue;
            }
            let (material, uv_map) = self.material(prim.material(), scene);
            let buffers = &self.buffers;
            let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let points: Vec<Vec3> = match reader.read_positions() {
                Some(p) => p.map(|p| world.transform_point3(Vec3::from(p))).collect(),
                None => Vec::new(),
            };
            let normals: Vec<Vec3> = match reader.read_normals() {
                Some(n) => n
                    .map(|n| unit(normal_matrix * Vec3::from(n)).unwrap_or(Vec3::ZERO))
                    .collect(),
                None => Vec::new(),
            };
            let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
                Some(t) => t
                    .into_f32()
                    .map(|t| uv_map.transform_point2(Vec2::from(t)))
                    .collect(),
                None => Vec::new(),
            };
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..points.len() as u32).collect(),
            };
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= points.len()) {
                return Err((self.err)(what(&format!(
                    "refers to vertex {bad}; it has {}",
                    points.len()
                ))));
            }
            // A mirroring transform turns the winding (glTF's rule): turned back, the front
            // stays the side it was (an emitter's light leaves from it).
            let mirrored = world.determinant() < 0.0;
            let corners = |[a, b, c]: [u32; 3]| {
                let t = if mirrored { [a, c, b] } else { [a, b, c] };
                t.map(|i| i as usize)
            };
            let mut emit = |[a, b, c]: [usize; 3]| -> Result<()> {
                if sink.count() >= MAX_PRIMITIVES {
                    return Err((self.err)(format!("more than {MAX_PRIMITIVES} triangles")));
                }
                let v = [points[a], points[b], points[c]];
                if !v.iter().all(|p| p.is_finite()) {
                    return Err((self.err)(what("has a vertex that is not finite")));
                }
                let n = (!normals.is_empty())
                    .then(|| [normals[a], normals[b], normals[c]])
                    .filter(|n| n.iter().all(|n| *n != Vec3::ZERO));
                let uv = (uvs.len() == points.len()).then(|| [uvs[a], uvs[b], uvs[c]]);
                sink.triangle(v, n, uv, material);
                Ok(())
            };
            let n = indices.len();
            match mode {
                Mode::Triangles => {
                    for t in indices.chunks_exact(3) {
                        emit(corners([t[0], t[1], t[2]]))?;
                    }
                }
                // Every other triangle of a strip turned, so that all keep one winding.
                Mode::TriangleStrip => {
                    for i in 2..n {
                        let t = if i % 2 == 0 {
                            [indices[i - 2], indices[i - 1], indices[i]]
                        } else {
                            [indices[i - 1], indices[i - 2], indices[i]]
                        };
                        emit(corners(t))?;
                    }
                }
                _ => {
                    for i in 2..n {
                        emit(corners([indices[0], indices[i - 1], indices[i]]))?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The first perspective camera met becomes the view; later ones are not read.
    fn view(&mut self, cam: &gltf::Camera, world: Mat4, scene: &mut Scene) {
        let gltf::camera::Projection::Perspective(p) = cam.projection() else {
            return;
        };
        if self.camera.is_some() {
            return;
        }
        self.camera = Some(cam.index());
        let from = world.transform_point3(Vec3::ZERO);
        let ahead = unit(world.transform_vector3(Vec3::NEG_Z)).unwrap_or(Vec3::NEG_Z);
        let up = unit(world.transform_vector3(Vec3::Y)).unwrap_or(Vec3::Y);
        let c = &mut scene.camera;
        c.from = from;
        c.at = from + ahead;
        c.up = up;
        c.angle = p.yfov().to_degrees().clamp(1.0, 170.0);
        c.hither = p.znear().max(0.0);
        let aspect = p
            .aspect_ratio()
            .filter(|a| a.is_finite() && *a > 0.0)
            .unwrap_or(1.0);
        (c.width, c.height) = ((512.0 * aspect).round().clamp(1.0, 16384.0) as u32, 512);
        c.fit = None;
    }
}

/// A `KHR_lights_punctual` light at its node: its colour (intensity is not read: the
/// Whitted model's lights do not fall off with distance).
fn light_of(light: &gltf::khr_lights_punctual::Light, world: Mat4, scene: &mut Scene) {
    use gltf::khr_lights_punctual::Kind;
    let color = Some(Vec3::from(light.color()).clamp(Vec3::ZERO, Vec3::splat(1e6)));
    let position = world.transform_point3(Vec3::ZERO);
    match light.kind() {
        Kind::Directional => {
            let direction = unit(world.transform_vector3(Vec3::NEG_Z)).unwrap_or(Vec3::NEG_Z);
            scene.lights.push(Light::Directional { direction, color });
        }
        Kind::Point => scene.lights.push(Light::Point { position, color }),
        Kind::Spot { .. } => {
            scene.warnings.push(format!(
                "{}: spot light {} read as a point light (its cone is not)",
                scene.name,
                light.index()
            ));
            scene.lights.push(Light::Point { position, color });
        }
    }
}
