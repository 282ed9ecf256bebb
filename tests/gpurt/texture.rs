//! Texture coordinates: OBJ's `vt` and glTF's `TEXCOORD_0` read, carried to the hit and
//! interpolated there the same way by both renderers, and shown by the `uv` AOV: against
//! the coordinates worked out independently through the camera, and one image from the
//! same quad written as OBJ and as glTF.

use std::sync::atomic::AtomicBool;

use base64::Engine;
use glam::{DVec2, DVec3};
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::AOV_UV;
use gpurt::pack;
use gpurt::scene::{self, Scene};

use crate::common::oracle::Camera;
use crate::common::versus::{self, Gpu};

/// The quad x, y in [-1, 1] at z = 0, its corners' texture coordinates running over
/// [0, 2] in u and [0.5, 1.5] in v (beyond [0, 1], as tiled textures are), seen at a slant.
const VIEW: &str = "v from 0.6 -0.8 3 at 0 0 0 up 0 1 0 angle 50 resolution 48 40\nb 0 0 0\nl 0 0 5\nf 1 1 1 1 0 1 0 1\n";
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
    let buffers = pack::pack(scene.clone()).expect("packs");
    let globals = frame::globals(&buffers, &opts);
    let never = AtomicBool::new(false);
    match gpu {
        None => gpurt::cpu::render(&buffers, &globals, &|_| {}, &never).map(|r| r.0),
        Some(g) => g
            .renderer
            .render(
                &g.ctx.device,
                &g.ctx.queue,
                &buffers,
                &globals,
                &|_| {},
                &never,
            )
            .map(|r| r.0),
    }
    .expect("renders")
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

/// The quad as glTF: the OBJ's corners and coordinates, its two triangles as the OBJ's
/// quad is split ((3, 0, 1) and (3, 1, 2)), in a data URI.
fn gltf_quad() -> String {
    let pos: [[f32; 3]; 4] = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let uv: [[f32; 2]; 4] = [[0.0, 0.5], [2.0, 0.5], [2.0, 1.5], [0.0, 1.5]];
    let ix: [u16; 6] = [3, 0, 1, 3, 1, 2];
    let mut bytes: Vec<u8> = bytemuck::cast_slice(&pos).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&uv));
    bytes.extend_from_slice(bytemuck::cast_slice(&ix));
    let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12}
        ],
        "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{data}")}]
    })
    .to_string()
}

/// The same quad with the same coordinates from OBJ and from glTF: the same triangles
/// with the same coordinates at their corners, so the same `uv` image.
#[test]
fn obj_and_gltf_of_one_quad_give_one_uv_image() {
    let from_obj = scene_with(OBJ, "quad.obj");
    let from_gltf = scene_with(&gltf_quad(), "quad.gltf");
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
