//! Bare meshes as scenes: an OBJ's `.mtl` colours where they should be on both backends,
//! and the automatic framing, which fits a mesh's projected box to `auto::FILL` of the
//! frame for any aspect ratio, as the renderers' own camera sees it.

use glam::Vec3;
use gpurt::frame::{self, Overrides, RenderOptions};
use gpurt::gpu_types::GpuGlobals;
use gpurt::pack;
use gpurt::scene::{self, auto};

use crate::common::versus::{self, compare, render_both};
use crate::common::workdir;
use crate::parse::materials::{MTL, obj};

/// Where the renderers' camera puts point `p`: image coordinates, y down (shading.md).
fn project(g: &GpuGlobals, p: Vec3) -> (f32, f32) {
    let d = p - g.cam_pos;
    let z = d.dot(g.cam_forward);
    let x = d.dot(g.cam_right) / z / g.pixel_pitch;
    let y = d.dot(g.cam_up) / z / g.pixel_pitch;
    (g.width as f32 * 0.5 + x, g.height as f32 * 0.5 - y)
}

#[test]
fn two_obj_materials_show_their_colours_on_both_backends() {
    let Some(g) = versus::gpu() else { return };
    let d = workdir("bare-mtl");
    std::fs::write(d.join("two.mtl"), MTL).unwrap();
    std::fs::write(d.join("two.obj"), obj("two.mtl")).unwrap();
    let scene = scene::load(&d.join("two.obj")).unwrap();
    let buffers = pack::pack(scene.clone()).unwrap();
    let opts = RenderOptions::for_camera(&buffers.camera).with_overrides(&Overrides {
        width: Some(96),
        height: Some(72),
        ..Overrides::default()
    });
    let globals = g.renderer.frame(&buffers, &frame::globals(&buffers, &opts));
    let (cpu, gpu) = render_both(g, &scene, &buffers, &globals);
    let (cpu, gpu) = (cpu.to_rgb8(), gpu.to_rgb8());
    compare("bare-mtl", &cpu, &gpu, || Ok(0.0)).unwrap();
    // The middle of each quad: red on the left, green on the right (the background is
    // bluish and the ground grey, so neither passes for either).
    let pixel = |img: &image::RgbImage, p: Vec3| {
        let (x, y) = project(&globals, p);
        img.get_pixel(x as u32, y as u32).0.map(f32::from)
    };
    for img in [&cpu, &gpu] {
        let [r, gr, b] = pixel(img, Vec3::new(-1.0, 1.0, 0.0));
        assert!(
            r > 2.0 * gr && r > 2.0 * b && r > 60.0,
            "left quad {r} {gr} {b}"
        );
        let [r, gr, b] = pixel(img, Vec3::new(1.0, 1.0, 0.0));
        assert!(
            gr > 2.0 * r && gr > 2.0 * b && gr > 60.0,
            "right quad {r} {gr} {b}"
        );
    }
    // The check has teeth: without the library both quads are grey.
    std::fs::write(d.join("grey.obj"), obj("none.mtl")).unwrap();
    let grey = pack::pack(scene::load(&d.join("grey.obj")).unwrap()).unwrap();
    let globals = frame::globals(&grey, &opts);
    let never = std::sync::atomic::AtomicBool::new(false);
    let (film, _) = gpurt::cpu::render(&grey, &globals, &|_| {}, &never).unwrap();
    let [r, gr, b] = pixel(&film.to_rgb8(), Vec3::new(-1.0, 1.0, 0.0));
    assert!(r < 2.0 * gr && r < 2.0 * b, "grey {r} {gr} {b}");
}

/// A long flat box (`size`), as an ASCII STL (z-up) or an OBJ (y-up), in a workdir.
fn long_flat(name: &str, size: Vec3) -> std::path::PathBuf {
    let d = workdir(&format!("frame-{name}"));
    let path = d.join(name);
    let corner =
        |i: usize| size * Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32);
    // The six faces by their corner indices, as quads.
    let faces = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let text = if name.ends_with(".obj") {
        let mut s: String = (0..8)
            .map(|i| {
                let c = corner(i);
                format!("v {} {} {}\n", c.x, c.y, c.z)
            })
            .collect();
        for f in faces {
            s += &format!("f {} {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1, f[3] + 1);
        }
        s
    } else {
        let mut s = String::from("solid box\n");
        for f in faces {
            for t in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
                s += "facet normal 0 0 0\nouter loop\n";
                for i in t {
                    let c = corner(i);
                    s += &format!("vertex {} {} {}\n", c.x, c.y, c.z);
                }
                s += "endloop\nendfacet\n";
            }
        }
        s + "endsolid box\n"
    };
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_long_flat_mesh_fills_most_of_the_frame_at_any_aspect_ratio() {
    let cases = [
        ("long.stl", Vec3::new(20.0, 1.0, 0.2)),
        ("deep.stl", Vec3::new(0.5, 30.0, 0.1)),
        ("tall.obj", Vec3::new(0.3, 12.0, 0.3)),
        ("plank.obj", Vec3::new(10.0, 0.1, 2.0)),
    ];
    for (name, size) in cases {
        let path = long_flat(name, size);
        let buffers = pack::pack(scene::load(&path).unwrap()).unwrap();
        for (w, h) in [(512, 512), (640, 360), (200, 800), (1000, 100), (33, 17)] {
            let opts = RenderOptions::for_camera(&buffers.camera).with_overrides(&Overrides {
                width: Some(w),
                height: Some(h),
                ..Overrides::default()
            });
            let g = frame::globals(&buffers, &opts);
            let (mut x0, mut x1, mut y0, mut y1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
            for i in 0..8 {
                let c = size * Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32);
                let (x, y) = project(&g, c);
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
            let at = format!("{name} at {w}x{h}: x {x0:.1}..{x1:.1}, y {y0:.1}..{y1:.1}");
            // Inside the frame, centred, and filling FILL of it where it reaches furthest.
            assert!(
                x0 > 0.0 && y0 > 0.0 && x1 < w as f32 && y1 < h as f32,
                "{at}"
            );
            let fill = ((x1 - x0) / w as f32).max((y1 - y0) / h as f32);
            assert!((0.85..=0.90).contains(&fill), "{at}: fills {fill}");
            let off =
                ((x0 + x1 - w as f32).abs() / w as f32).max((y0 + y1 - h as f32).abs() / h as f32);
            assert!(off < 0.02, "{at}: off centre by {off}");
            assert!((fill - auto::FILL).abs() < 0.02, "{at}: fills {fill}");
        }
    }
}
