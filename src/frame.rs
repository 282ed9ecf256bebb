//! A frame of a packed scene: the render options (size, samples, depth, ambient, AOV,
//! seed, shading model), and the `GpuGlobals` both renderers read, built from the scene's camera and the
//! options. Their defaults and limits are in `limits`.

use glam::Vec3;

use crate::gpu_types::*;
use crate::pack::SceneBuffers;
use crate::scene::{Camera, auto};
use crate::util::limits::{DEFAULT_AMBIENT, DEFAULT_DEPTH, DEFAULT_SPP};

/// How to render: everything that is not the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    /// Overrides the scene's `am` and the default.
    pub ambient: Option<Vec3>,
    pub aov: u32,
    pub seed: u32,
    pub shading: Shading,
}

/// The model of the specular highlight (`--shading`); everything else in the shading
/// model is the same under both (docs/model.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Shading {
    /// `Ks * max(0, R.L)^Shine`, R the incoming ray mirrored about the normal: NFF's model.
    #[default]
    Phong,
    /// `Ks * max(0, N.H)^Shine`, `H = normalize(L + V)` with V towards the viewer, the
    /// exponent as the file gives it: the model of the IST P3D course's tracer.
    BlinnPhong,
}

impl Shading {
    /// Every model, in the order `--help` lists them.
    pub const ALL: [Shading; 2] = [Shading::Phong, Shading::BlinnPhong];

    /// The name `--shading` takes.
    pub fn name(self) -> &'static str {
        match self {
            Shading::Phong => "phong",
            Shading::BlinnPhong => "blinn-phong",
        }
    }

    /// The model called `name`.
    pub fn from_name(name: &str) -> Option<Shading> {
        Shading::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Its `GpuGlobals::shading` code, `SHADING_*`.
    pub fn code(self) -> u32 {
        match self {
            Shading::Phong => SHADING_PHONG,
            Shading::BlinnPhong => SHADING_BLINN_PHONG,
        }
    }
}

impl RenderOptions {
    /// Camera samples the frame traces: pixels times samples per pixel.
    pub fn samples(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * u64::from(self.spp)
    }

    /// The camera's own resolution and the defaults: `DEFAULT_SPP`, `DEFAULT_DEPTH`, the
    /// scene's ambient, colour output.
    pub fn for_camera(camera: &Camera) -> Self {
        RenderOptions {
            width: camera.width,
            height: camera.height,
            spp: DEFAULT_SPP,
            max_depth: DEFAULT_DEPTH,
            ambient: None,
            aov: AOV_COLOR,
            seed: 0,
            shading: Shading::Phong,
        }
    }

    /// These options with whatever `o` sets in their place: the one place where a
    /// caller's settings (the command line's, a batch's, the viewer's) meet a scene's
    /// camera and the defaults, as in `RenderOptions::for_camera(camera).with_overrides(o)`.
    pub fn with_overrides(self, o: &Overrides) -> Self {
        RenderOptions {
            width: o.width.unwrap_or(self.width),
            height: o.height.unwrap_or(self.height),
            spp: o.spp.unwrap_or(self.spp),
            max_depth: o.max_depth.unwrap_or(self.max_depth),
            ambient: o.ambient.or(self.ambient),
            aov: o.aov.unwrap_or(self.aov),
            seed: o.seed.unwrap_or(self.seed),
            shading: o.shading.unwrap_or(self.shading),
        }
    }
}

/// What a caller sets over a scene's camera and the defaults (`--width`, `--height`,
/// `--spp`, `--depth`, `--ambient`, `--aov`, `--seed`, `--shading`); `None` keeps the scene's value or
/// the default. A new width or height keeps the camera's vertical angle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub ambient: Option<Vec3>,
    pub aov: Option<u32>,
    pub seed: Option<u32>,
    pub shading: Option<Shading>,
}

/// Per-render constants: the camera basis of shading.md and the options.
/// A bare mesh's camera is framed again for the options' size (`auto::fitted`).
pub fn globals(buffers: &SceneBuffers, opts: &RenderOptions) -> GpuGlobals {
    let camera = auto::fitted(&buffers.camera, opts.width, opts.height);
    globals_from(buffers, &camera, opts)
}

/// `globals` seen from another camera than the scene's (the viewer's).
pub fn globals_from(buffers: &SceneBuffers, c: &Camera, opts: &RenderOptions) -> GpuGlobals {
    let (forward, right, up) = camera_basis(c);
    let pixel_pitch = pixel_pitch(c.angle, opts.height);
    GpuGlobals {
        cam_pos: c.from,
        hither: c.hither,
        cam_forward: forward,
        pixel_pitch,
        cam_right: right,
        aperture: c.aperture,
        cam_up: up,
        focal: c.focal_distance(),
        background: buffers.background,
        epsilon: buffers.epsilon,
        ambient: opts
            .ambient
            .or(buffers.ambient)
            .unwrap_or(Vec3::splat(DEFAULT_AMBIENT)),
        max_depth: opts.max_depth,
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        seed: opts.seed,
        n_nodes: buffers.node_count() as u32,
        n_planes: buffers.planes.len() as u32,
        n_lights: buffers.lights.len() as u32,
        aov: opts.aov,
        // The GPU renderer puts its adapter's choice here (`GpuRenderer::traversal`).
        traversal: TRAVERSAL_SINGLE,
        counters: 0,
        wavefront: 0,
        shading: opts.shading.code(),
        textures_at: buffers.textures_at(),
        _pad: [0; 3],
    }
}

/// The camera's forward, right and up unit vectors (shading.md): right is perpendicular
/// to `up` and the view, and the camera's up is perpendicular to both.
pub fn camera_basis(c: &Camera) -> (Vec3, Vec3, Vec3) {
    let forward = (c.at - c.from).normalize();
    let right = forward.cross(c.up).normalize();
    (forward, right, right.cross(forward))
}

/// Pixel pitch at unit distance for a vertical `angle` (degrees) over `height` rows:
/// `angle` spans the centres of the top and bottom rows, H - 1 pitches.
pub fn pixel_pitch(angle: f32, height: u32) -> f32 {
    let rows = (height.max(2) - 1) as f32;
    2.0 * (angle.to_radians() * 0.5).tan() / rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pack::{EPSILON_REL, pack};
    use crate::scene::nff;

    #[test]
    fn camera_basis_and_pixel_pitch_follow_the_nff_angle() {
        let src = b"v from 0 -5 1 at 0 0 0 up 0 0 1 angle 40 resolution 8 8
            l 1 -2 3  f 1 0 0 1 0 1 0 1  s 0 0 0 1  s 2 0 0 0.5";
        let scene = nff::parse(src, "t.nff", std::path::Path::new(".")).unwrap();
        let b = pack(scene.clone()).unwrap();
        let g = globals(&b, &RenderOptions::for_camera(&scene.camera));
        // 40 degrees between the centres of the 8 rows: 7 pitches.
        let want = 2.0 * 20f32.to_radians().tan() / 7.0;
        assert!((g.pixel_pitch - want).abs() < 1e-7);
        assert!(g.cam_forward.dot(g.cam_right).abs() < 1e-6);
        assert!(g.cam_up.z > 0.9, "up stays up");
        assert!((b.epsilon - EPSILON_REL * scene.bounds().extent().length()).abs() < 1e-9);
    }

    #[test]
    fn overrides_replace_only_what_they_set() {
        let defaults = RenderOptions {
            width: 40,
            height: 30,
            spp: 1,
            max_depth: 5,
            ambient: None,
            aov: AOV_COLOR,
            seed: 0,
            shading: Shading::Phong,
        };
        assert_eq!(
            defaults.clone().with_overrides(&Overrides::default()),
            defaults
        );
        let o = Overrides {
            height: Some(7),
            spp: Some(9),
            ambient: Some(Vec3::splat(0.5)),
            seed: Some(3),
            shading: Some(Shading::BlinnPhong),
            ..Overrides::default()
        };
        let got = defaults.clone().with_overrides(&o);
        assert_eq!(
            got,
            RenderOptions {
                width: 40,
                height: 7,
                spp: 9,
                ambient: Some(Vec3::splat(0.5)),
                seed: 3,
                shading: Shading::BlinnPhong,
                ..defaults
            }
        );
    }
}
