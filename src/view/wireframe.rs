//! The wireframe: the edges of a packed scene drawn as lines by a wgpu render pipeline
//! (`shaders/wireframe.wgsl`), through a view-projection matrix built from the same
//! `GpuGlobals` the ray tracer's primary rays come from, so that both show the scene from
//! one camera: same eye, basis, field of view (the pixel pitch), aspect ratio and near
//! plane. `project` is the vertex stage on the CPU, for the tests that prove the sync.
//!
//! The primary ray of pixel (x, y) goes through `cam_forward + sx cam_right + sy cam_up`
//! with `sx = (x - W/2) pitch` and `sy = (H/2 - y) pitch` (`cpu::pixel::camera_ray`). A
//! point at camera coordinates (u, v, z) lies on the ray of x = W/2 + u / (z pitch) and
//! y = H/2 - v / (z pitch); the matrix below gives exactly that after the perspective
//! divide and the viewport transform, which puts pixel centres at half-integers as the
//! ray tracer does.

use glam::{Mat4, Vec2, Vec3, Vec4};
use image::RgbImage;

use super::readback::TextureReadback;
use crate::gpu::device::{Device, Gpu};
use crate::gpu_types::{GpuGlobals, PRIM_BOX, PRIM_CONE, PRIM_SPHERE, PRIM_TRIANGLE};
use crate::pack::SceneBuffers;
use crate::scene::Bounds;
use crate::util::error::{Error, Result};

/// Most line segments drawn; a scene with more draws every k-th primitive (the viewer's
/// wireframe is for finding a view, not for counting edges). 4M segments take a 96 MiB
/// vertex buffer.
pub const SEGMENT_BUDGET: usize = 4 << 20;

/// Segments per circle of a sphere or cone outline, at most and at least (many spheres
/// get fewer each, to stay within the budget).
const CIRCLE_SEGMENTS: (usize, usize) = (24, 6);

/// Lines of the grid drawn on each infinite plane, in each direction.
const PLANE_GRID_LINES: usize = 11;

/// The colour of the lines: multiples of 1/255, so that every format stores them exactly.
pub const LINE_COLOR: [f32; 4] = [0.2, 1.0, 0.4, 1.0];

/// The uniform of `wireframe.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameUniform {
    view_proj: [[f32; 4]; 4],
    color: [f32; 4],
}

/// The end points of every edge drawn, two per segment, in world space: triangle edges,
/// three circles (an equator and two meridians) per sphere, the two rims and four side
/// lines per cone, the twelve edges per box, and a grid around the scene on each plane.
pub fn segments(scene: &SceneBuffers) -> Vec<Vec3> {
    let count = |kind| scene.prims.iter().filter(|p| p.kind() == kind).count();
    let spheres = count(PRIM_SPHERE);
    let cones = count(PRIM_CONE);
    let round = 3 * spheres + 2 * cones;
    let circle = (SEGMENT_BUDGET / 2)
        .checked_div(round)
        .map_or(CIRCLE_SEGMENTS.0, |n| {
            n.clamp(CIRCLE_SEGMENTS.1, CIRCLE_SEGMENTS.0)
        });
    let needed = 3 * count(PRIM_TRIANGLE) + circle * round + 4 * cones + 12 * count(PRIM_BOX);
    let stride = needed.div_ceil(SEGMENT_BUDGET).max(1);
    let mut out = Vec::with_capacity(2 * needed.min(SEGMENT_BUDGET));
    let mut line = |a: Vec3, b: Vec3| out.extend([a, b]);
    for p in scene.prims.iter().step_by(stride) {
        match p.kind() {
            PRIM_TRIANGLE => {
                let (a, b, c) = (p.p0, p.p0 + p.p1, p.p0 + p.p2);
                line(a, b);
                line(b, c);
                line(c, a);
            }
            PRIM_SPHERE => {
                let r = p.f0.abs();
                for (u, v) in [(Vec3::X, Vec3::Y), (Vec3::X, Vec3::Z), (Vec3::Y, Vec3::Z)] {
                    circle_lines(p.p0, u * r, v * r, circle, &mut line);
                }
            }
            PRIM_CONE => {
                let axis = (p.p1 - p.p0).normalize_or(Vec3::Z);
                let (u, v) = axis.any_orthonormal_pair();
                circle_lines(p.p0, u * p.f0, v * p.f0, circle, &mut line);
                circle_lines(p.p1, u * p.f1, v * p.f1, circle, &mut line);
                for d in [u, v, -u, -v] {
                    line(p.p0 + d * p.f0, p.p1 + d * p.f1);
                }
            }
            PRIM_BOX => {
                let corner = |i: usize| {
                    Vec3::select(
                        glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                        p.p1,
                        p.p0,
                    )
                };
                for i in 0..8 {
                    for bit in [1, 2, 4] {
                        if i & bit == 0 {
                            line(corner(i), corner(i | bit));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    // Planes: a square grid as wide as the scene, centred where the scene projects.
    let (centre, size) = if scene.bounds.is_empty() {
        let c = &scene.camera;
        (c.at, (c.at - c.from).length().max(1.0))
    } else {
        (
            scene.bounds.center(),
            scene.bounds.extent().length().max(1e-3),
        )
    };
    for plane in &scene.planes {
        let n = plane.normal.normalize_or(Vec3::Z);
        let origin = centre - (centre.dot(n) - plane.d) * n;
        let (u, v) = n.any_orthonormal_pair();
        let half = 0.5 * size;
        for i in 0..PLANE_GRID_LINES {
            let t = -half + size * i as f32 / (PLANE_GRID_LINES - 1) as f32;
            line(origin + u * t - v * half, origin + u * t + v * half);
            line(origin + v * t - u * half, origin + v * t + u * half);
        }
    }
    out
}

/// Adds the `n` segments of the circle `centre + cos(t) u + sin(t) v`.
fn circle_lines(centre: Vec3, u: Vec3, v: Vec3, n: usize, line: &mut impl FnMut(Vec3, Vec3)) {
    let at = |i: usize| {
        let t = std::f32::consts::TAU * i as f32 / n as f32;
        centre + u * t.cos() + v * t.sin()
    };
    for i in 0..n {
        line(at(i), at(i + 1));
    }
}

/// The near and far distances of the wireframe's depth range: the camera's hither (or a
/// small fraction of the far distance when it is 0), and well beyond the farthest corner
/// of the scene's `bounds` (and of the plane grids); `focus` stands in for a scene of
/// planes only.
pub fn depth_range(bounds: &Bounds, focus: Vec3, g: &GpuGlobals) -> (f32, f32) {
    let reach = if bounds.is_empty() {
        (focus - g.cam_pos).length().max(1.0)
    } else {
        let b = bounds;
        let corners = (0..8).map(|i| {
            Vec3::new(
                if i & 1 != 0 { b.max.x } else { b.min.x },
                if i & 2 != 0 { b.max.y } else { b.min.y },
                if i & 4 != 0 { b.max.z } else { b.min.z },
            )
        });
        corners
            .map(|c| (c - g.cam_pos).length())
            .fold(0.0, f32::max)
            + b.extent().length()
    };
    let far = 4.0 * reach.max(1e-3);
    let near = if g.hither > 0.0 { g.hither } else { 1e-5 * far };
    (near.min(0.5 * far), far)
}

/// The view-projection matrix of the frame `g` describes (wgpu clip space: depth 0 at
/// `near`, 1 at `far`).
pub fn view_projection(g: &GpuGlobals, near: f32, far: f32) -> Mat4 {
    let e = g.cam_pos;
    let sx = 2.0 / (g.width as f32 * g.pixel_pitch);
    let sy = 2.0 / (g.height as f32 * g.pixel_pitch);
    let a = far / (far - near);
    let b = -near * far / (far - near);
    let row = |axis: Vec3, s: f32| Vec4::new(axis.x * s, axis.y * s, axis.z * s, -axis.dot(e) * s);
    let z = row(g.cam_forward, 1.0);
    Mat4::from_cols(
        row(g.cam_right, sx),
        row(g.cam_up, sy),
        z * a + Vec4::new(0.0, 0.0, 0.0, b),
        z,
    )
    .transpose()
}

/// Where `vs_main` puts a world point: pixel coordinates (x right, y down, pixel centres
/// at half-integers), or `None` behind the eye.
pub fn project(view_proj: &Mat4, g: &GpuGlobals, p: Vec3) -> Option<Vec2> {
    let clip = *view_proj * p.extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let ndc = clip.truncate() / clip.w;
    Some(Vec2::new(
        (ndc.x + 1.0) * 0.5 * g.width as f32,
        (1.0 - ndc.y) * 0.5 * g.height as f32,
    ))
}

/// A scene's wireframe on a device: the render pipeline and the vertex buffer.
pub struct Wireframe {
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    uniform: wgpu::Buffer,
    vertices: wgpu::Buffer,
    vertex_count: u32,
    /// What `depth_range` needs of the scene: its bounds and the camera's focus.
    bounds: Bounds,
    focus: Vec3,
}

/// The format the wireframe draws into when it makes an image itself.
pub const IMAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl Wireframe {
    /// Uploads a scene's edges and builds the pipeline for targets of `format`.
    pub fn new(
        device: &wgpu::Device,
        scene: &SceneBuffers,
        format: wgpu::TextureFormat,
    ) -> Result<Self> {
        let points = segments(scene);
        // Pipeline or buffer errors become `Error::Gpu`, not wgpu's panicking handler.
        let d = Device::new(device);
        d.scoped("building the wireframe", || {
            let uniform = d.uniform("wireframe frame", size_of::<FrameUniform>() as u64);
            let source = include_str!("../../shaders/wireframe.wgsl");
            let (pipeline, bind_group) = d.line_pipeline("wireframe", source, format, &uniform);
            // wgpu cannot make an empty buffer: an empty scene draws one degenerate segment.
            let flat: Vec<[f32; 3]> = if points.is_empty() {
                vec![[0.0; 3]; 2]
            } else {
                points.iter().map(|p| p.to_array()).collect()
            };
            let vertices = d.buffer_from(
                "wireframe vertices",
                bytemuck::cast_slice(&flat),
                wgpu::BufferUsages::VERTEX,
            );
            Wireframe {
                pipeline,
                bind_group,
                uniform,
                vertices,
                vertex_count: points.len() as u32,
                bounds: scene.bounds,
                focus: scene.camera.at,
            }
        })
    }

    /// Encodes the lines of the frame `g` into `target`, over what it holds.
    pub(crate) fn encode(
        &self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        g: &GpuGlobals,
    ) {
        let (near, far) = depth_range(&self.bounds, self.focus, g);
        let frame = FrameUniform {
            view_proj: view_projection(g, near, far).to_cols_array_2d(),
            color: LINE_COLOR,
        };
        gpu.write(&self.uniform, 0, bytemuck::bytes_of(&frame));
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("wireframe"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..self.vertex_count, 0..1);
    }

    /// Draws the frame `g` over `background` (its size), or over black, and reads the
    /// image back.
    pub fn draw_image(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        g: &GpuGlobals,
        background: Option<&RgbImage>,
    ) -> Result<RgbImage> {
        let (w, h) = (g.width, g.height);
        let gpu = Gpu::new(device, queue);
        let texture = gpu.image_texture("wireframe image", (w, h), IMAGE_FORMAT);
        let mut rgba = vec![0u8; (w * h * 4) as usize];
        if let Some(bg) = background {
            if bg.dimensions() != (w, h) {
                return Err(Error::Render(format!(
                    "a {w}x{h} wireframe cannot go over a {}x{} image",
                    bg.width(),
                    bg.height()
                )));
            }
            for (out, p) in rgba.chunks_mut(4).zip(bg.pixels()) {
                out[..3].copy_from_slice(&p.0);
            }
        }
        for px in rgba.chunks_mut(4) {
            px[3] = 255;
        }
        gpu.write_image(&texture, &rgba);
        let mut enc = gpu.encoder();
        let view = texture.create_view(&Default::default());
        self.encode(&gpu, &mut enc, &view, g);
        let readback = TextureReadback::encode(&gpu, &mut enc, &texture);
        gpu.run(enc);
        readback.read(&gpu, IMAGE_FORMAT)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wireframe_shader_validates() {
        let src = include_str!("../../shaders/wireframe.wgsl");
        let module = naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{e}"));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{e:?}"));
    }

    #[test]
    fn every_kind_of_primitive_has_edges_and_the_budget_holds() {
        let src = b"v from 0 -9 3 at 0 0 0 up 0 0 1 angle 40 resolution 8 8
            f 1 1 1 1 0 1 0 1
            s 0 0 0 1  c 0 0 0 1 0 0 2 0.5  p 3 0 0 0 1 0 0 0 1 0  aabb 1 2 1 2 1 2
            pl 5 5 -1  -5 5 -1  -5 -5 -1";
        let scene = crate::scene::nff::parse(src, "t", std::path::Path::new(".")).unwrap();
        let buffers = crate::pack::pack(scene).unwrap();
        let points = segments(&buffers);
        let circle = CIRCLE_SEGMENTS.0;
        let want = 3 + 3 * circle + (2 * circle + 4) + 12 + 2 * PLANE_GRID_LINES;
        assert_eq!(points.len(), 2 * want);
        assert!(points.iter().all(|p| p.is_finite()));
    }
}
