//! The viewer's camera sync: the wireframe's matrix path and the ray tracer's ray path
//! show a scene from one camera, proved point by point.

use glam::{Vec2, Vec3};
use gpurt::cpu::fast::wide_ray::closest_hit;
use gpurt::cpu::pixel::camera_ray;
use gpurt::cpu::types::{Bindings, Ray};
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::{GpuGlobals, NO_HIT, PRIM_TRIANGLE};
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene;
use gpurt::view::wireframe::{self, Wireframe};
use image::RgbImage;

use crate::common::{XorShift, gpu_context, own_scenes};

/// mesh.nff (three placed STL icosahedra and polygons) at an odd, non-square size.
fn mesh_frame() -> (SceneBuffers, GpuGlobals) {
    let buffers =
        pack::pack(scene::load(&own_scenes().join("mesh.nff")).expect("loads")).expect("packs");
    let opts = RenderOptions {
        width: 401,
        height: 283,
        ..RenderOptions::for_camera(&buffers.camera)
    };
    let g = frame::globals(&buffers, &opts);
    (buffers, g)
}

/// How far (in pixels at the point's distance) the primary ray through pixel centre
/// `pixel` passes from `p`.
fn miss_in_pixels(g: &GpuGlobals, pixel: Vec2, p: Vec3) -> f32 {
    let ray = camera_ray(g, pixel.x, pixel.y, &mut 0);
    let d = p - ray.origin;
    let along = d.dot(ray.dir);
    let off = (d - along * ray.dir).length();
    off / (along * g.pixel_pitch)
}

#[test]
fn projected_points_lie_on_the_primary_ray_of_their_pixel() {
    let (buffers, g) = mesh_frame();
    let (near, far) = wireframe::depth_range(&buffers.bounds, buffers.camera.at, &g);
    let vp = wireframe::view_projection(&g, near, far);
    let mut rng = XorShift(0x9e3779b97f4a7c15);
    let mut checked = 0;
    while checked < 2000 {
        // A point in view: along the ray of a random spot of the image, at a random depth.
        let spot = Vec2::new(rng.unit() * g.width as f32, rng.unit() * g.height as f32);
        let depth = 10.0 * near + (far - near) * rng.unit().powi(3);
        let ray = camera_ray(&g, spot.x, spot.y, &mut 0);
        let p = ray.origin + ray.dir * depth;
        let px = wireframe::project(&vp, &g, p).expect("in front of the eye");
        // The matrix puts the point where its ray started, to a fiftieth of a pixel (f32
        // rounding of points near the eye)...
        assert!((px - spot).length() < 0.02, "{p}: matrix {px}, ray {spot}");
        // ...and the ray through the centre of that pixel passes within a pixel of it.
        let centre = px.floor() + Vec2::splat(0.5);
        let miss = miss_in_pixels(&g, centre, p);
        assert!(
            miss <= 0.75,
            "{p}: the ray of pixel {centre} misses by {miss} pixels"
        );
        checked += 1;
    }
}

/// The pixels of `image` the wireframe lit.
fn lit(image: &RgbImage, x: i64, y: i64) -> bool {
    let (w, h) = image.dimensions();
    (-1..=1).any(|dy| {
        (-1..=1).any(|dx| {
            let (x, y) = (x + dx, y + dy);
            x >= 0
                && y >= 0
                && (x as u32) < w
                && (y as u32) < h
                && image.get_pixel(x as u32, y as u32).0[1] > 128
        })
    })
}

/// Triangle vertices the ray tracer sees (the primary ray through the vertex's spot on
/// the image reaches it before anything else), with where the matrix projects them.
fn visible_vertices(buffers: &SceneBuffers, g: &GpuGlobals) -> Vec<Vec2> {
    let (near, far) = wireframe::depth_range(&buffers.bounds, buffers.camera.at, g);
    let vp = wireframe::view_projection(g, near, far);
    let b = Bindings::new(buffers, g);
    let mut out = Vec::new();
    for p in buffers.prims.iter().filter(|p| p.kind() == PRIM_TRIANGLE) {
        for v in [p.p0, p.p0 + p.p1, p.p0 + p.p2] {
            let Some(px) = wireframe::project(&vp, g, v) else {
                continue;
            };
            let inside = px.x >= 1.0
                && px.y >= 1.0
                && px.x < g.width as f32 - 1.0
                && px.y < g.height as f32 - 1.0;
            if !inside {
                continue;
            }
            let dir = (v - g.cam_pos).normalize();
            let dist = (v - g.cam_pos).length();
            let ray = Ray {
                origin: g.cam_pos,
                dir,
            };
            let hit = closest_hit(&b, &ray, g.hither, NO_HIT);
            if hit.t >= dist * (1.0 - 1e-4) {
                out.push(px);
            }
        }
    }
    out
}

#[test]
fn every_vertex_the_ray_tracer_sees_is_where_the_wireframe_draws_it() {
    let Some(ctx) = gpu_context() else { return };
    let (buffers, g) = mesh_frame();
    let seen = visible_vertices(&buffers, &g);
    assert!(seen.len() >= 20, "only {} vertices in view", seen.len());
    let wire = Wireframe::new(&ctx.device, &buffers, wireframe::IMAGE_FORMAT).expect("pipeline");
    let image = wire
        .draw_image(&ctx.device, &ctx.queue, &g, None)
        .expect("draws");
    let missing: Vec<_> = seen
        .iter()
        .filter(|px| !lit(&image, px.x.floor() as i64, px.y.floor() as i64))
        .collect();
    assert!(
        missing.is_empty(),
        "{} of {} vertices not drawn: {missing:?}",
        missing.len(),
        seen.len()
    );

    // The check can fail: a wireframe drawn from an eye moved by a few pixels' worth
    // misses most of the vertices.
    let mut moved = g;
    let distance = (buffers.camera.at - g.cam_pos).length();
    moved.cam_pos += (g.cam_right + g.cam_up) * 4.0 * distance * g.pixel_pitch;
    let shifted = wire
        .draw_image(&ctx.device, &ctx.queue, &moved, None)
        .expect("draws");
    let found = seen
        .iter()
        .filter(|px| lit(&shifted, px.x.floor() as i64, px.y.floor() as i64))
        .count();
    assert!(
        found < seen.len() / 2,
        "a shifted wireframe still covers {found} of {} vertices",
        seen.len()
    );
}
