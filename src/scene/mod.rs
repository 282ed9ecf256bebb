//! The scene model: plain data produced by the readers and consumed by `pack`.
//!
//! Readers (`nff`, `stl`, `obj`) take text or bytes plus a display name for error
//! messages; `load` reads a file from disk (gzip-aware) and picks the reader by extension.
//! Primitives carry a `MaterialId` that indexes `Scene::materials` directly, so the same
//! index is used on the GPU.

pub mod auto;
pub mod lex;
pub mod mesh;
pub mod nff;
pub mod obj;
pub mod stl;
pub mod triangulate;

use glam::Vec3;
use std::path::Path;

use crate::error::{Error, Result};
use crate::limits::{HELD_BYTES, MAX_FILE_BYTES};

/// Index into `Scene::materials`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MaterialId(pub u32);

/// Which way eye rays leave the camera, in NFF terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub from: Vec3,
    pub at: Vec3,
    pub up: Vec3,
    /// Full vertical field of view in degrees between the centres of the outermost pixel rows.
    pub angle: f32,
    /// Near distance for eye rays.
    pub hither: f32,
    pub width: u32,
    pub height: u32,
    /// Thin-lens aperture diameter (0 = pinhole). Extension `aperture a`.
    pub aperture: f32,
    /// Thin-lens focal distance; `None` means `|at - from|`. Extension `focal d`.
    pub focal: Option<f32>,
}

/// The camera a scene has before its `v` is read.
pub fn nff_default_camera() -> Camera {
    Camera {
        from: Vec3::ZERO,
        at: Vec3::NEG_Z,
        up: Vec3::Y,
        angle: 45.0,
        hither: 0.0,
        width: 512,
        height: 512,
        aperture: 0.0,
        focal: None,
    }
}

impl Camera {
    /// Distance at which the thin lens is in focus.
    pub fn focal_distance(&self) -> f32 {
        self.focal.unwrap_or_else(|| (self.at - self.from).length())
    }
}

/// NFF `f r g b Kd Ks Shine T ior`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub color: Vec3,
    pub kd: f32,
    pub ks: f32,
    pub shine: f32,
    pub t: f32,
    pub ior: f32,
}

impl Material {
    /// Used for primitives that come before the first `f` (documented in docs/scene-format.md).
    pub const DEFAULT: Material = Material {
        color: Vec3::ONE,
        kd: 1.0,
        ks: 0.0,
        shine: 1.0,
        t: 0.0,
        ior: 1.0,
    };
    /// Neutral grey given to a bare mesh rendered without a scene file.
    pub const NEUTRAL_GREY: Material = Material {
        color: Vec3::splat(0.8),
        kd: 0.8,
        ks: 0.1,
        shine: 30.0,
        t: 0.0,
        ior: 1.0,
    };
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// `l x y z [r g b]`; `color: None` gets the SPD intensity `1/sqrt(n_lights)`.
    Point { position: Vec3, color: Option<Vec3> },
    /// `dl dx dy dz [r g b]`: light travelling along `direction` (from the light towards the scene).
    Directional {
        direction: Vec3,
        color: Option<Vec3>,
    },
    /// `al cx cy cz ux uy uz vx vy vz r g b nu nv`: a rectangle `corner + a*u + b*v`,
    /// sampled `nu x nv` times per shading point (stratified, jittered).
    Area {
        corner: Vec3,
        u: Vec3,
        v: Vec3,
        color: Vec3,
        samples: [u32; 2],
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    /// Negative in NFF means "inside visible"; every surface is rendered two-sided, so
    /// readers store the absolute value.
    pub radius: f32,
    pub material: MaterialId,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    pub v: [Vec3; 3],
    /// Shading normals per vertex (`pp` patches, STL facet normals, OBJ normals). Boxed:
    /// most triangles have none, and a flat triangle then takes 48 bytes instead of 80
    /// (8.4 million of them in mount-11).
    pub n: Option<Box<[Vec3; 3]>>,
    pub material: MaterialId,
}

impl Triangle {
    /// Twice-area vector (cross product of the edges); zero for degenerate triangles.
    pub fn cross(&self) -> Vec3 {
        (self.v[1] - self.v[0]).cross(self.v[2] - self.v[0])
    }
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }
}

/// Infinite plane (`pl` of the P3D dialect).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    pub material: MaterialId,
}

/// NFF `c`: a truncated cone or cylinder between two cap centres; sides only, no caps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    pub base: Vec3,
    pub base_radius: f32,
    pub apex: Vec3,
    pub apex_radius: f32,
    pub material: MaterialId,
}

/// P3D `aabb x0 x1 y0 y1 z0 z1`: an axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxPrim {
    pub min: Vec3,
    pub max: Vec3,
    pub material: MaterialId,
}

/// A whole scene as read from one file.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Display name used in messages (usually the path).
    pub name: String,
    pub camera: Camera,
    pub background: Vec3,
    /// `am r g b`; `None` means the renderer's default.
    pub ambient: Option<Vec3>,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub spheres: Vec<Sphere>,
    pub triangles: Vec<Triangle>,
    pub planes: Vec<Plane>,
    pub cones: Vec<Cone>,
    pub boxes: Vec<BoxPrim>,
    /// Non-fatal problems (e.g. dropped degenerate polygons), each naming its line.
    pub warnings: Vec<String>,
}

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds {
    pub const EMPTY: Bounds = Bounds {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn union(mut self, o: Bounds) -> Bounds {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
        self
    }
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
}

impl Sphere {
    pub fn bounds(&self) -> Bounds {
        let r = Vec3::splat(self.radius.abs());
        Bounds {
            min: self.center - r,
            max: self.center + r,
        }
    }
}

impl Triangle {
    pub fn bounds(&self) -> Bounds {
        Bounds {
            min: self.v[0].min(self.v[1]).min(self.v[2]),
            max: self.v[0].max(self.v[1]).max(self.v[2]),
        }
    }
}

impl Cone {
    /// Bounds of the two cap discs (a slight over-estimate, always conservative).
    pub fn bounds(&self) -> Bounds {
        let axis = (self.apex - self.base).normalize_or_zero();
        // Extent of a unit disc perpendicular to `axis`, per coordinate axis.
        let disc = (Vec3::ONE - axis * axis).max(Vec3::ZERO).powf(0.5);
        let rb = disc * self.base_radius.abs();
        let ra = disc * self.apex_radius.abs();
        Bounds {
            min: (self.base - rb).min(self.apex - ra),
            max: (self.base + rb).max(self.apex + ra),
        }
    }
}

impl BoxPrim {
    pub fn bounds(&self) -> Bounds {
        Bounds {
            min: self.min,
            max: self.max,
        }
    }
}

/// A bounded primitive of a scene (`Scene::bounded_prims`).
#[derive(Clone, Copy, Debug)]
pub enum Bounded<'a> {
    Sphere(&'a Sphere),
    Triangle(&'a Triangle),
    Cone(&'a Cone),
    Box(&'a BoxPrim),
}

impl Bounded<'_> {
    pub fn bounds(&self) -> Bounds {
        match self {
            Bounded::Sphere(s) => s.bounds(),
            Bounded::Triangle(t) => t.bounds(),
            Bounded::Cone(c) => c.bounds(),
            Bounded::Box(b) => b.bounds(),
        }
    }
}

impl Scene {
    /// An empty scene with the given camera.
    pub fn new(name: impl Into<String>, camera: Camera) -> Self {
        Scene {
            name: name.into(),
            camera,
            background: Vec3::ZERO,
            ambient: None,
            lights: Vec::new(),
            materials: Vec::new(),
            spheres: Vec::new(),
            triangles: Vec::new(),
            planes: Vec::new(),
            cones: Vec::new(),
            boxes: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// Bounds of every bounded primitive (planes are infinite and excluded).
    pub fn bounds(&self) -> Bounds {
        self.bounded_prims()
            .fold(Bounds::EMPTY, |b, p| b.union(p.bounds()))
    }

    /// Every bounded primitive in the one order the BVH is built over and the packed
    /// buffers, the tests and the benchmarks index them by: spheres, triangles, cones,
    /// boxes.
    pub fn bounded_prims(&self) -> impl Iterator<Item = Bounded<'_>> {
        let spheres = self.spheres.iter().map(Bounded::Sphere);
        let triangles = self.triangles.iter().map(Bounded::Triangle);
        let cones = self.cones.iter().map(Bounded::Cone);
        let boxes = self.boxes.iter().map(Bounded::Box);
        spheres.chain(triangles).chain(cones).chain(boxes)
    }

    /// Number of bounded primitives (what the BVH is built over).
    pub fn bounded_count(&self) -> usize {
        self.spheres.len() + self.triangles.len() + self.cones.len() + self.boxes.len()
    }
}

/// `n` scaled to unit length, or `None` when it has no direction (zero or not finite).
/// It is divided by its largest component first, so that a vector whose squared length
/// overflows or underflows f32 (components beyond about 1e19 or below 1e-19) is still
/// normalised: `Vec3::normalize` turns `(3e38, 0, 0)` into zero, and zero shading normals
/// into NaN pixels.
pub fn unit(n: Vec3) -> Option<Vec3> {
    let largest = n.abs().max_element();
    if !n.is_finite() || largest == 0.0 {
        return None;
    }
    Some((n / largest).normalize())
}

/// What a file holds, from its extension (after stripping `.gz`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    Nff,
    Stl,
    Obj,
}

impl FileKind {
    pub fn of(path: &Path) -> FileKind {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        if name.ends_with(".stl") {
            FileKind::Stl
        } else if name.ends_with(".obj") {
            FileKind::Obj
        } else {
            FileKind::Nff
        }
    }
}

/// Reads a file whole, decompressing it when it starts with the gzip magic bytes.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    let not_a_file = |what: &str| Error::Scene {
        file: path.display().to_string(),
        msg: format!("is {what}, not a regular file"),
    };
    // Checked before opening: opening a fifo waits for a writer, and a device such as
    // /dev/zero never ends.
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(not_a_file("a directory"));
    }
    if !meta.is_file() {
        return Err(not_a_file("a device, fifo or socket"));
    }
    let mut raw = Vec::with_capacity(meta.len().min(MAX_FILE_BYTES) as usize);
    // Bounded even so: a file that grows while it is read stops at the limit.
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut raw))
        .map_err(|e| Error::io(path, e))?;
    if raw.len() as u64 > MAX_FILE_BYTES {
        return Err(Error::Scene {
            file: path.display().to_string(),
            msg: format!("is larger than {} GiB", MAX_FILE_BYTES >> 30),
        });
    }
    decompress(raw, path, MAX_FILE_BYTES)
}

/// `raw` as `read_file` returns it for a file at `path`: decompressed when it starts with
/// the gzip magic bytes (every member, as gzip does), unchanged otherwise. A file that
/// decompresses to more than `limit` bytes is an error (`read_file` uses `MAX_FILE_BYTES`),
/// found holding at most `HELD_BYTES` of it.
pub fn decompress(raw: Vec<u8>, path: &Path, limit: u64) -> Result<Vec<u8>> {
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Ok(raw);
    }
    let io = |e| Error::io(path, e);
    // The gzip trailer ends with the decompressed size mod 2^32 (ISIZE): exact for the usual
    // one-member file, so the output is allocated once instead of doubling its way up (which
    // would hold up to twice the scene's bytes at the peak). Deflate cannot expand more than
    // about 1032:1, which bounds a lying trailer.
    let isize = raw.len().checked_sub(4).map_or(0, |i| {
        u32::from_le_bytes(raw[i..].try_into().unwrap()) as u64
    });
    let held = limit.min(HELD_BYTES);
    let hint = isize.min(raw.len() as u64 * 1032).min(held);
    let mut out = Vec::with_capacity(hint as usize + 64);
    let mut total = inflate(&raw, &mut out, held + 1).map_err(io)?;
    if total > held {
        // Larger than is held before the size is known: count it all first.
        total = inflate(&raw, &mut std::io::sink(), limit + 1).map_err(io)?;
        if total <= limit {
            out = Vec::with_capacity(total as usize);
            inflate(&raw, &mut out, total).map_err(io)?;
        }
    }
    if total > limit {
        let msg = if limit >= 1 << 30 && limit.is_multiple_of(1 << 30) {
            format!("decompresses to more than {} GiB", limit >> 30)
        } else {
            format!("decompresses to more than {limit} bytes")
        };
        return Err(Error::Scene {
            file: path.display().to_string(),
            msg,
        });
    }
    Ok(out)
}

/// Writes the gzip members of `raw` to `out`, member after member as gzip does, stopping
/// after `room` bytes; returns the bytes written. Zero bytes after the last member are
/// padding (tape blocks, `dd`), which `gzip -t` accepts too.
fn inflate(raw: &[u8], out: &mut impl std::io::Write, room: u64) -> std::io::Result<u64> {
    use std::io::Read;
    let (mut rest, mut written) = (raw, 0);
    while written < room && !rest.iter().all(|&b| b == 0) {
        let mut member = flate2::bufread::GzDecoder::new(rest);
        written += std::io::copy(&mut (&mut member).take(room - written), out)?;
        rest = member.into_inner();
    }
    Ok(written)
}

/// Loads a scene file: NFF (with our extensions), or a bare STL/OBJ mesh that gets an
/// automatic camera, light, material and ground plane.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = read_file(path)?;
    let name = path.display().to_string();
    match FileKind::of(path) {
        FileKind::Nff => {
            let base = path.parent().unwrap_or(Path::new("."));
            nff::parse(&bytes, &name, base)
        }
        kind => {
            let mesh = mesh::parse_mesh(&bytes, kind, &name)?;
            let mut scene = auto::scene_for_mesh(&name, mesh.triangles)?;
            scene.warnings.extend(mesh.warnings);
            Ok(scene)
        }
    }
}
