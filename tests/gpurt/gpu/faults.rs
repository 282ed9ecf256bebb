//! Faults and limits: a scene larger than the device allows is refused with the limit
//! named, a validation error inside wgpu names its cause, and a device lost before or
//! during a render is an error, never a panic or an image.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use glam::Vec3;
use gpurt::agreement::noise_floor;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu::GpuRenderer;
use gpurt::gpu::shaders::Fetch;
use gpurt::pack;
use gpurt::scene::Scene;

use crate::common::versus::{Gpu, compare, features_scene, gpu, opts};

/// Opens a second device on the test adapter with some limits lowered.
fn device_with(g: &Gpu, limits: wgpu::Limits) -> (wgpu::Device, wgpu::Queue) {
    pollster::block_on(g.ctx.adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: limits,
        ..Default::default()
    }))
    .expect("device with lowered limits")
}

/// The features scene plus `n` tiny triangles with shading normals.
fn with_triangles(n: usize) -> Scene {
    let mut scene = features_scene("");
    let material = scene.spheres[0].material;
    for i in 0..n {
        let x = i as f32 * 1e-4;
        scene.triangles.push(gpurt::scene::Triangle {
            v: [
                glam::Vec3::new(x, 3.0, 0.0),
                glam::Vec3::new(x + 1e-4, 3.0, 0.0),
                glam::Vec3::new(x, 3.0, 1e-4),
            ],
            n: Some(Box::new([glam::Vec3::Y; 3])),
            material,
            uv: None,
        });
    }
    scene
}

/// The features scene with a wall of `n` triangles behind it, facing the camera, whose
/// shading normals lean away from the wall's own by an angle that changes across it: the
/// normals a renderer reads show in its image.
fn with_a_wall_of_normals(n: usize) -> Scene {
    let mut scene = features_scene("");
    let material = scene.spheres[0].material;
    let (columns, rows) = (150, n / 300);
    let (dx, dz) = (6.0 / columns as f32, 3.0 / rows as f32);
    let normal = |x: f32, z: f32| Vec3::new(0.6 * (2.0 * x).sin(), -1.0, 0.6 * (3.0 * z).cos());
    for (i, j) in (0..rows).flat_map(|j| (0..columns).map(move |i| (i, j))) {
        let (x, z) = (-3.0 + i as f32 * dx, j as f32 * dz);
        let corners = [(x, z), (x + dx, z), (x + dx, z + dz), (x, z + dz)];
        for [a, b, c] in [[0, 1, 2], [0, 2, 3]] {
            let [a, b, c] = [corners[a], corners[b], corners[c]];
            scene.triangles.push(gpurt::scene::Triangle {
                v: [a, b, c].map(|(x, z)| Vec3::new(x, 2.5, z)),
                n: Some(Box::new([a, b, c].map(|(x, z)| normal(x, z).normalize()))),
                material,
                uv: None,
            });
        }
    }
    assert_eq!(scene.triangles.len(), n);
    scene
}

/// Renders `scene` at the test size with `renderer` on `device`.
fn render_with(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    renderer: &GpuRenderer,
    scene: &Scene,
) -> gpurt::Result<()> {
    let buffers = pack::pack(scene.clone()).expect("packs");
    let globals = frame::globals(&buffers, &opts(scene));
    let never = AtomicBool::new(false);
    renderer
        .render(device, queue, &buffers, &globals, &|_| {}, &never)
        .map(|_| ())
}

/// The error a renderer reading the scene as `fetch` says gives for `scene`.
fn refusal(device: &wgpu::Device, queue: &wgpu::Queue, fetch: Fetch, scene: &Scene) -> String {
    let renderer = GpuRenderer::fetching(device, None, fetch).expect("shader module");
    render_with(device, queue, &renderer, scene)
        .expect_err("oversized scene must be refused")
        .to_string()
}

/// A scene larger than a storage binding or a texture the device allows is refused with a
/// message that names the limit and what needed more, never rendered as a black image:
/// under either way of reading the nodes, primitives and normals (textures, which grow by
/// layers, or storage buffers, whose refusal names the textures as the way out), whatever
/// the adapter's default.
#[test]
fn oversized_scene_is_refused_with_the_limit_named() {
    let Some(g) = gpu() else {
        return;
    };
    // 1 MiB holds the 256x256 output tile; 64 bytes a light, 17000 lights need 1.04 MiB.
    let mib = 1 << 20;
    let (device, queue) = device_with(
        g,
        wgpu::Limits {
            max_storage_buffer_binding_size: mib,
            ..g.ctx.adapter.limits()
        },
    );
    let mut lit = features_scene("");
    lit.lights
        .extend((0..17_000).map(|i| gpurt::scene::Light::Point {
            position: glam::Vec3::new(i as f32, 0.0, 10.0),
            color: None,
        }));
    for fetch in [Fetch::Textures, Fetch::Buffers] {
        let msg = refusal(&device, &queue, fetch, &lit);
        assert!(
            msg.contains("lights")
                && msg.contains("max_storage_buffer_binding_size")
                && msg.contains(&mib.to_string()),
            "{msg}"
        );
    }
    // Read from storage buffers, a wall of 30000 triangles is refused under that 1 MiB
    // limit (their primitives take 1.4 MB, 48 bytes each), the message naming the textures
    // as the way out.
    let wall = with_a_wall_of_normals(30_000);
    let msg = refusal(&device, &queue, Fetch::Buffers, &wall);
    assert!(
        msg.contains("primitives need")
            && msg.contains("bytes in one storage buffer")
            && msg.contains("max_storage_buffer_binding_size is 1048576")
            && msg.contains("GPURT_FETCH=textures"),
        "{msg}"
    );
    // In a texture array, like nodes and primitives, they render under that limit, to the
    // CPU's image, which differs without them (so it is the normals that agree).
    let renderer = GpuRenderer::fetching(&device, None, Fetch::Textures).expect("shader module");
    let never = AtomicBool::new(false);
    let frame_of = |scene: &Scene| {
        let buffers = pack::pack(scene.clone()).expect("packs");
        let globals = renderer.frame(&buffers, &frame::globals(&buffers, &opts(scene)));
        (buffers, globals)
    };
    let cpu_image = |buffers, globals| {
        let (film, _) = gpurt::cpu::render(buffers, globals, &|_| {}, &never).expect("renders");
        film.to_rgb8()
    };
    let (buffers, globals) = frame_of(&wall);
    let cpu = cpu_image(&buffers, &globals);
    let floor = || noise_floor(&buffers, &globals, &cpu);
    let (gpu, _) = renderer
        .render(&device, &queue, &buffers, &globals, &|_| {}, &never)
        .expect("normals beyond a storage binding render");
    compare("normals in layers", &cpu, &gpu.to_rgb8(), floor).unwrap_or_else(|e| panic!("{e}"));
    let mut flat = wall;
    flat.triangles.iter_mut().for_each(|t| t.n = None);
    let (flat_buffers, flat_globals) = frame_of(&flat);
    let flat = cpu_image(&flat_buffers, &flat_globals);
    assert!(
        compare("normals-control-flat", &cpu, &flat, floor).is_err(),
        "the wall looks the same without its normals"
    );
    // Nodes and primitives travel as texture arrays 4096 texels wide.
    let (device, queue) = device_with(
        g,
        wgpu::Limits {
            max_texture_dimension_2d: 16,
            ..g.ctx.adapter.limits()
        },
    );
    let msg = refusal(&device, &queue, Fetch::Textures, &with_triangles(30_000));
    assert!(
        msg.contains("4096 texels wide") && msg.contains("max_texture_dimension_2d is 16"),
        "{msg}"
    );
    // 30000 primitives of three texels need 22 rows: 11 layers of 2 rows, where the
    // device allows 8.
    let (device, queue) = device_with(
        g,
        wgpu::Limits {
            max_texture_array_layers: 8,
            ..g.ctx.adapter.limits()
        },
    );
    let renderer = GpuRenderer::fetching(&device, None, Fetch::Textures)
        .expect("shader module")
        .with_layer_rows(2);
    let msg = render_with(&device, &queue, &renderer, &with_triangles(30_000))
        .expect_err("a scene over more layers than allowed must be refused")
        .to_string();
    assert!(
        msg.contains("primitives need 11 texture layers of 2 rows")
            && msg.contains("max_texture_array_layers is 8"),
        "{msg}"
    );
}

/// A validation error inside wgpu (here a device whose workgroups are smaller than the
/// shader's 64 invocations, so the pipeline is invalid) is an error naming the step and
/// wgpu's cause, never a panic or a black image.
#[test]
fn a_validation_error_is_an_error_naming_its_cause() {
    let Some(g) = gpu() else {
        return;
    };
    let (device, queue) = device_with(
        g,
        wgpu::Limits {
            max_compute_workgroup_size_x: 32,
            max_compute_invocations_per_workgroup: 32,
            ..g.ctx.adapter.limits()
        },
    );
    let renderer = GpuRenderer::new(&device, None).expect("shader module");
    let msg = render_with(&device, &queue, &renderer, &features_scene(""))
        .expect_err("an invalid pipeline must not render")
        .to_string();
    println!("{msg}");
    assert!(
        msg.starts_with("GPU error: compiling the shader: ") && msg.contains("orkgroup"),
        "{msg}"
    );
}

/// A device lost mid-render (destroyed here, between the upload and the trace, and again
/// before an upload) ends the render with an error naming the GPU, never a panic or an
/// image.
#[test]
fn a_lost_device_is_an_error_not_an_image() {
    let Some(g) = gpu() else {
        return;
    };
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    let globals = frame::globals(&buffers, &opts(&scene));
    let never = AtomicBool::new(false);

    let (device, queue) = device_with(g, g.ctx.adapter.limits());
    let renderer = GpuRenderer::new(&device, None).expect("shader module");
    let uploaded = renderer
        .upload(&device, &queue, &buffers, &globals)
        .expect("uploads");
    device.destroy();
    let err = gpurt::gpu::trace(&device, &queue, &uploaded, &|_| {}, &never)
        .map(|_| ())
        .expect_err("a trace on a lost device fails");
    println!("trace on a lost device: {err}");
    assert!(err.to_string().starts_with("GPU error: "), "{err}");

    let (device, queue) = device_with(g, g.ctx.adapter.limits());
    let renderer = GpuRenderer::new(&device, None).expect("shader module");
    device.destroy();
    let err = renderer
        .render(&device, &queue, &buffers, &globals, &|_| {}, &never)
        .map(|_| ())
        .expect_err("a render on a lost device fails");
    println!("render on a lost device: {err}");
    assert!(err.to_string().starts_with("GPU error: "), "{err}");
}

/// A device lost while it renders (destroyed once the first band has been read back) ends
/// the render with an error naming the step, never a partial image. On every adapter: on
/// an H100 and H200s the suite with it stopped making progress, a deadlock in NVIDIA's
/// driver between EGL and Vulkan (docs/gpu.md, "A suite that stopped"), gone since gpurt
/// leaves GL out there.
#[test]
fn a_device_lost_half_way_is_an_error_not_an_image() {
    let Some(g) = gpu() else {
        return;
    };
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    let never = AtomicBool::new(false);
    // Bands of at most 1 MiB of output here: 256 rows of 256 pixels, four of them.
    let (device, queue) = device_with(
        g,
        wgpu::Limits {
            max_storage_buffer_binding_size: 1 << 20,
            ..g.ctx.adapter.limits()
        },
    );
    let renderer = GpuRenderer::new(&device, None).expect("shader module");
    let tall = RenderOptions {
        width: 256,
        height: 1024,
        ..opts(&scene)
    };
    let uploaded = renderer
        .upload(&device, &queue, &buffers, &frame::globals(&buffers, &tall))
        .expect("uploads");
    let passes = AtomicU32::new(0);
    let lose = |_| {
        passes.fetch_add(1, Ordering::Relaxed);
        device.destroy();
    };
    let err = gpurt::gpu::trace(&device, &queue, &uploaded, &lose, &never)
        .map(|_| ())
        .expect_err("a trace whose device is lost half-way fails");
    println!("device lost mid-trace: {err}");
    assert_eq!(
        passes.load(Ordering::Relaxed),
        1,
        "lost after the first band"
    );
    assert!(err.to_string().starts_with("GPU error: "), "{err}");
}
