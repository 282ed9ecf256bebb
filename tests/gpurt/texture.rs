//! Texture coordinates: OBJ's `vt` and glTF's `TEXCOORD_0` read, carried to the hit and
//! interpolated there the same way by both renderers, and shown by the `uv` AOV: against
//! the coordinates worked out independently through the camera, and one image from the
//! same quad written as OBJ and as glTF. Textures: a checkerboard on the quad against the
//! bilinear filter written out again, on both renderers, and lit under every variant.

use glam::{DVec2, DVec3, Vec3};
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::AOV_UV;
use gpurt::pack;
use gpurt::scene::{self, Scene, Texture, Wrap};

use crate::common::oracle::Camera;
use crate::common::versus::{self, Gpu};
use crate::texture_files;

/// The quad x, y in [-1, 1] at z = 0, its corners' texture coordinates running over
/// [0, 2] in u and [0.5, 1.5] in v (beyond [0, 1], as tiled textures are), seen at a slant.
pub(crate) const VIEW: &str = "v from 0.6 -0.8 3 at 0 0 0 up 0 1 0 angle 50 resolution 48 40\nb 0 0 0\nl 0 0 5\nf 1 1 1 1 0 1 0 1\n";
const OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
                   vt 0 0.5\nvt 2 0.5\nvt 2 1.5\nvt 0 1.5\nf 1/1 2/2 3/3 4/4\n";

/// The coordinates the quad has at (x, y): the bilinear map its corners give, which is
/// affine on each of its two triangles since the corners' coordinates are.
fn analytic(x: f64, y: f64) -> DVec2 {
    DVec2::new(x + 1.0, 0.5 + 0.5 * (y + 1.0))
}

/// The scene of `VIEW` with the triangles of the mesh file `name` holding `text` (read as
/// a file of its own, then put under `VIEW`'s camera).
fn scene_with(text: &str, name: &str) -> Scene {
    let dir = crate::common::temp_dir("uv");
    std::fs::write(dir.join(name), text).unwrap();
    let mesh = scene::load(&dir.join(name)).expect("the mesh reads");
    let mut s = scene::nff::parse(VIEW.as_bytes(), "uv.nff", &dir).expect("parses");
    s.triangles = mesh.triangles;
    s
}

fn render_uv(scene: &Scene, gpu: Option<&Gpu>) -> Film {
    let opts = RenderOptions {
        aov: AOV_UV,
        ..RenderOptions::for_camera(&scene.camera)
    };
    render(scene, gpu, opts)
}

pub(crate) fn render(scene: &Scene, gpu: Option<&Gpu>, opts: RenderOptions) -> Film {
    let buffers = pack::pack(scene.clone()).expect("packs");
    versus::render_on(&buffers, &frame::globals(&buffers, &opts), gpu)
}

/// Every pixel whose ray meets the quad clearly inside (not within 1% of its rim or of
/// the diagonal the triangles share) against `analytic`, within 1e-5; most of the image
/// is the quad; the same quad with two corners' coordinates swapped fails it.
fn check_uv(gpu: Option<&Gpu>) {
    let scene = scene_with(OBJ, "quad.obj");
    let cam = Camera::of(&scene);
    let inside: Vec<((u32, u32), DVec2)> = cam
        .pixels()
        .filter_map(|(x, y)| {
            let d = cam.dir(x, y);
            let t = -cam.from.z / d.z;
            let p = cam.from + t * d;
            let clear = p.x.abs() < 0.99 && p.y.abs() < 0.99 && (p.x - p.y).abs() > 0.02;
            (t > 0.0 && clear).then(|| ((x, y), analytic(p.x, p.y)))
        })
        .collect();
    assert!(inside.len() > 600, "{} pixels on the quad", inside.len());
    let worst = |film: &Film| {
        inside
            .iter()
            .map(|&((x, y), want)| {
                let got = DVec3::from(film.get(x, y).map(f64::from));
                (got - want.extend(0.0)).abs().max_element()
            })
            .fold(0.0, f64::max)
    };
    let off = worst(&render_uv(&scene, gpu));
    assert!(off < 1e-5, "{off} off the coordinates through the camera");
    let swapped = scene_with(
        &OBJ.replace("vt 2 0.5\nvt 2 1.5", "vt 2 1.5\nvt 2 0.5"),
        "swapped.obj",
    );
    let off = worst(&render_uv(&swapped, gpu));
    assert!(off > 0.1, "swapped coordinates pass ({off})");
}

#[test]
fn the_uv_aov_is_the_coordinates_through_the_camera_on_the_cpu() {
    check_uv(None);
}

#[test]
fn the_uv_aov_is_the_coordinates_through_the_camera_on_the_gpu() {
    let Some(g) = versus::gpu() else {
        return;
    };
    check_uv(Some(g));
}

/// The same quad with the same coordinates from OBJ and from glTF: the same triangles
/// with the same coordinates at their corners, so the same `uv` image.
#[test]
fn obj_and_gltf_of_one_quad_give_one_uv_image() {
    let from_obj = scene_with(OBJ, "quad.obj");
    let from_gltf = scene_with(&texture_files::gltf_quad(None, &[]).0, "quad.gltf");
    let (a, b) = (&from_obj.triangles, &from_gltf.triangles);
    assert_eq!(a.len(), 2);
    assert_eq!(
        a.iter().map(|t| (t.v, t.uv.clone())).collect::<Vec<_>>(),
        b.iter().map(|t| (t.v, t.uv.clone())).collect::<Vec<_>>()
    );
    let (a, b) = (render_uv(&from_obj, None), render_uv(&from_gltf, None));
    let cam = Camera::of(&from_obj);
    assert!(
        cam.pixels().any(|(x, y)| a.get(x, y)[0] > 1.0),
        "u beyond 1 seen"
    );
    assert!(cam.pixels().all(|(x, y)| a.get(x, y) == b.get(x, y)));
}

/// A 4 x 4 checkerboard, white and blue, that repeats.
fn checker() -> Texture {
    let texels = (0..16)
        .map(|k| {
            if (k % 4 + k / 4) % 2 == 0 {
                Vec3::ONE
            } else {
                Vec3::new(0.1, 0.2, 0.6)
            }
        })
        .collect();
    Texture {
        name: "checker".into(),
        width: 4,
        height: 4,
        texels,
        wrap: [Wrap::Repeat; 2],
    }
}

/// Texture `t` filtered bilinearly at `uv` (v up, rows from the top, texel centres at
/// half-texels, repeating), in f64: the filter written out again from its definition.
pub(crate) fn filtered_at(t: &Texture, uv: DVec2, flip: bool) -> DVec3 {
    let (w, h) = (f64::from(t.width), f64::from(t.height));
    let x = uv.x.rem_euclid(1.0) * w - 0.5;
    let v = if flip { uv.y } else { 1.0 - uv.y };
    let y = v.rem_euclid(1.0) * h - 0.5;
    let at = |i: f64, j: f64| {
        let (i, j) = (i.rem_euclid(w) as u32, j.rem_euclid(h) as u32);
        t.texels[(j * t.width + i) as usize].as_dvec3()
    };
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
    let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The quad under ambient light alone (1, with Kd 1 and no lights), so that a pixel is
/// its texture's colour there.
fn textured_quad() -> Scene {
    let mut s = scene_with(OBJ, "quad.obj");
    s.lights.clear();
    s.ambient = Some(Vec3::ONE);
    s.textures.push(checker());
    for m in &mut s.materials {
        m.texture = Some(0);
    }
    s
}

/// Every pixel of the checkered quad clearly inside it against the checkerboard filtered
/// at the coordinates through the camera, within 1e-4; the board flipped upside down
/// fails it.
fn check_checker(gpu: Option<&Gpu>) {
    let scene = textured_quad();
    let film = render(&scene, gpu, RenderOptions::for_camera(&scene.camera));
    check_texture_on_quad(&scene, &film, &checker(), |uv| uv);
}

/// Every pixel of the quad of `VIEW` in `film` (clearly inside it) against texture `t`
/// filtered at `map` of the coordinates through the camera (`analytic`), within 1e-4;
/// the texture flipped upside down must fail it.
pub(crate) fn check_texture_on_quad(
    scene: &Scene,
    film: &Film,
    texture: &Texture,
    map: impl Fn(DVec2) -> DVec2,
) {
    let cam = Camera::of(scene);
    let (mut worst, mut flipped, mut n) = (0.0f64, 0.0f64, 0);
    for (x, y) in cam.pixels() {
        let d = cam.dir(x, y);
        let t = -cam.from.z / d.z;
        let p = cam.from + t * d;
        if !(t > 0.0 && p.x.abs() < 0.99 && p.y.abs() < 0.99 && (p.x - p.y).abs() > 0.02) {
            continue;
        }
        let uv = map(analytic(p.x, p.y));
        let got = DVec3::from(film.get(x, y).map(f64::from));
        worst = worst.max((got - filtered_at(texture, uv, false)).abs().max_element());
        flipped = flipped.max((got - filtered_at(texture, uv, true)).abs().max_element());
        n += 1;
    }
    assert!(n > 600, "{n} pixels on the quad");
    assert!(worst < 1e-4, "{worst} off the checkerboard");
    assert!(flipped > 0.1, "the board upside down passes ({flipped})");
}

#[test]
fn a_checkerboard_is_filtered_as_defined_on_the_cpu() {
    check_checker(None);
}

#[test]
fn a_checkerboard_is_filtered_as_defined_on_the_gpu() {
    let Some(g) = versus::gpu() else {
        return;
    };
    check_checker(Some(g));
    // And lit: the GPU equals the CPU under every variant, at 1 and 4 spp.
    let mut lit = textured_quad();
    lit.lights.push(gpurt::scene::Light::Point {
        position: Vec3::new(1.0, -1.0, 3.0),
        color: None,
    });
    lit.ambient = None;
    versus::check_all(versus::check_variants(g, "checker", &lit));
}
