//! The scene's data model: plain data that the readers produce and `pack` consumes (the
//! scene, its camera, lights, materials and primitives, and a mesh file's triangles). Kept
//! apart from the readers so that every reader, and everything that reads a scene, shares
//! one definition without depending on a reader (`Mesh` in `mesh.rs` once made `mesh` and
//! `obj` import each other).
//!
//! Primitives carry a `MaterialId` that indexes `Scene::materials` directly, so the same
//! index is used on the GPU.

use glam::{DAffine3, DVec3, Vec2, Vec3};

use super::spline::{self, PositionSpline, RotationSpline, VisibilityKey};

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
    /// The box (min, max) this camera frames, for a bare mesh (`auto`): a render of
    /// another resolution frames it again for its own aspect ratio. `None` for a view
    /// the scene gives.
    pub fit: Option<[Vec3; 2]>,
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
        fit: None,
    }
}

impl Camera {
    /// Distance at which the thin lens is in focus.
    pub fn focal_distance(&self) -> f32 {
        self.focal.unwrap_or_else(|| (self.at - self.from).length())
    }

    /// What makes this view give no image, if anything: the one check of a camera that
    /// the NFF `v` block and the library's callers (the Python and browser cameras) share.
    pub fn view_problem(&self) -> Option<&'static str> {
        if !(self.from.is_finite() && self.at.is_finite() && self.up.is_finite()) {
            return Some("degenerate view: a coordinate is not finite");
        }
        let dir = self.at - self.from;
        if dir.length_squared() == 0.0 {
            return Some("degenerate view: 'from' and 'at' are the same point");
        }
        let side = dir.normalize().cross(self.up.normalize_or_zero());
        if side.length() < 1e-6 {
            return Some("degenerate view: 'up' is zero or parallel to the view direction");
        }
        None
    }
}

/// NFF `f r g b Kd Ks Shine T ior`, and what the surface emits (OBJ's `Ke`, glTF's
/// emissive): the radiance seen on its front, whose triangles are then lights
/// (docs/model.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub color: Vec3,
    pub kd: f32,
    pub ks: f32,
    pub shine: f32,
    pub t: f32,
    pub ior: f32,
    pub emission: Vec3,
    /// The image its colour is multiplied by where its surfaces have texture coordinates
    /// (`Scene::textures`): OBJ's `map_Kd`, glTF's `baseColorTexture`.
    pub texture: Option<u32>,
    /// The colour the scene's ambient light is multiplied by, where the material gives
    /// its own (AFF's `fm`); `None`: `kd` times `color`, as NFF's `f` has it.
    pub ambient: Option<Vec3>,
}

impl Material {
    /// Whether the surface emits light: its triangles are then lights.
    pub fn emits(&self) -> bool {
        self.emission != Vec3::ZERO
    }

    /// Used for primitives that come before the first `f` (documented in docs/scene-format.md).
    pub const DEFAULT: Material = Material {
        color: Vec3::ONE,
        kd: 1.0,
        ks: 0.0,
        shine: 1.0,
        t: 0.0,
        ior: 1.0,
        emission: Vec3::ZERO,
        texture: None,
        ambient: None,
    };
    /// Neutral grey given to a bare mesh rendered without a scene file.
    pub const NEUTRAL_GREY: Material = Material {
        color: Vec3::splat(0.8),
        kd: 0.8,
        ks: 0.1,
        shine: 30.0,
        t: 0.0,
        ior: 1.0,
        emission: Vec3::ZERO,
        texture: None,
        ambient: None,
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
    /// Texture coordinates per vertex (OBJ's `vt`, glTF's `TEXCOORD_0`), boxed as `n` is.
    pub uv: Option<Box<[Vec2; 3]>>,
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

/// An image a material's colour is multiplied by: linear RGB (decoded from sRGB where
/// its format says so), row by row from the top, and how it repeats beyond [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from, for messages and `gpurt info`.
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    /// How u and v wrap.
    pub wrap: [Wrap; 2],
}

/// What a texture coordinate beyond [0, 1] reads (glTF's sampler wrap modes; OBJ repeats).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Mirror,
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
    /// The images materials name (`Material::texture`).
    pub textures: Vec<Texture>,
    pub spheres: Vec<Sphere>,
    pub triangles: Vec<Triangle>,
    pub planes: Vec<Plane>,
    pub cones: Vec<Cone>,
    pub boxes: Vec<BoxPrim>,
    /// Non-fatal problems (e.g. dropped degenerate polygons), each naming its line.
    pub warnings: Vec<String>,
    /// What moves, in an AFF scene (`None` in a still one).
    pub animation: Option<Box<Animation>>,
}

impl Scene {
    /// Whether one of the scene's materials emits (`Material::emits`): its triangles
    /// light the scene (a reader that frames a bare mesh then adds no light of its own).
    pub fn emits(&self) -> bool {
        self.materials.iter().any(Material::emits)
    }

    /// An empty scene with the given camera.
    pub fn new(name: impl Into<String>, camera: Camera) -> Self {
        Scene {
            name: name.into(),
            camera,
            background: Vec3::ZERO,
            ambient: None,
            lights: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            spheres: Vec::new(),
            triangles: Vec::new(),
            planes: Vec::new(),
            cones: Vec::new(),
            boxes: Vec::new(),
            warnings: Vec::new(),
            animation: None,
        }
    }
}

/// `n` scaled to unit length, or `None` when it has no direction (zero or not finite).
/// It is divided by its largest component first, so that a vector whose squared length
/// overflows or underflows f32 (components beyond about 1e19 or below 1e-19) is still
/// normalised: `Vec3::normalize` turns `(3e38, 0, 0)` into zero, and zero shading normals
/// into NaN pixels.
/// Bounded primitives as `Scene` holds them, kind by kind: what a reader's `Collect` sink
/// gathers (`sink`), and what a moving group holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Collect {
    pub(super) spheres: Vec<Sphere>,
    pub(super) triangles: Vec<Triangle>,
    pub(super) cones: Vec<Cone>,
    pub(super) boxes: Vec<BoxPrim>,
}

// Scenes that move (BART's AFF): the data the NFF reader produces; `animation` places
// them at a frame's time.

/// The animation's time range and frame count (the `a` statement): frame `i` of `frames`
/// is at `start + i (end - start) / (frames - 1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeRange {
    pub start: f64,
    pub end: f64,
    pub frames: u32,
}

impl TimeRange {
    /// The time of frame `frame` (counted from 0).
    pub fn time(&self, frame: u32) -> f64 {
        if self.frames <= 1 {
            return self.start;
        }
        self.start + (self.end - self.start) * f64::from(frame) / f64::from(self.frames - 1)
    }
}

/// A named transform's keyframes: each part absent is the identity.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Track {
    pub name: String,
    pub translation: Option<PositionSpline>,
    pub rotation: Option<RotationSpline>,
    pub scale: Option<PositionSpline>,
    pub visibility: Vec<VisibilityKey>,
}

impl Track {
    /// T * R * S at time `t`: scaled first, then turned, then moved.
    pub fn transform(&self, t: f64) -> DAffine3 {
        let translation = self.translation.as_ref().map_or(DVec3::ZERO, |s| s.at(t));
        let rotation = self
            .rotation
            .as_ref()
            .map_or(glam::DQuat::IDENTITY, |s| s.at(t));
        let scale = self.scale.as_ref().map_or(DVec3::ONE, |s| s.at(t));
        DAffine3::from_scale_rotation_translation(scale, rotation, translation)
    }

    pub fn visible(&self, t: f64) -> bool {
        spline::visible(&self.visibility, t)
    }
}

/// One transform of a chain: fixed (`xs`), or a named track's at the frame's time (`x`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Link {
    Fixed(DAffine3),
    Moving(usize),
}

/// What a block under an animated transform holds, in the block's own coordinates, and
/// the transforms that place it, outermost first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Group {
    pub chain: Vec<Link>,
    pub prims: Collect,
    pub planes: Vec<Plane>,
    pub lights: Vec<Light>,
}

/// A light that a track moves (`la name`): placed by the track's transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingLight {
    pub track: usize,
    pub light: Light,
}

/// Everything of a scene that moves.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animation {
    /// The `a` statement's range, when the scene has one.
    pub range: Option<TimeRange>,
    pub tracks: Vec<Track>,
    pub groups: Vec<Group>,
    pub lights: Vec<MovingLight>,
    /// The track named `camera`, which moves the camera.
    pub camera: Option<usize>,
}

pub fn unit(n: Vec3) -> Option<Vec3> {
    let largest = n.abs().max_element();
    if !n.is_finite() || largest == 0.0 {
        return None;
    }
    Some((n / largest).normalize())
}

/// A mesh file's triangles (material 0) and what was dropped from it, as
/// `FILE:LINE:COL: message`.
pub struct Mesh {
    pub triangles: Vec<Triangle>,
    pub warnings: Vec<String>,
}
