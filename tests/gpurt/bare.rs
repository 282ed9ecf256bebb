//! Bare meshes as scenes: an OBJ's `.mtl` colours where they should be on both backends.

use glam::Vec3;
use gpurt::frame::{self, Overrides, RenderOptions};
use gpurt::gpu_types::GpuGlobals;
use gpurt::pack;
use gpurt::scene;

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
