//! GPU against the CPU reference, pixel by pixel, on every shared scene up to its default
//! size, every P3D file and every scene of our own; with samples per pixel, area lights,
//! the thin lens and each AOV; plus the comparer's own self-test.
//!
//! Without an adapter these tests skip with a message, unless `GPURT_REQUIRE_GPU=1`, where
//! they fail. Failures write the CPU image, the GPU image and a heat map to
//! `target/gpu-vs-cpu/`.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use gpurt::agreement::noise_floor;
use gpurt::compare::{self, DiffStats, Thresholds};
use gpurt::film::{self, Film};
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu::{GpuContext, GpuRenderer};
use gpurt::gpu_types::*;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::{self, Scene};
use image::RgbImage;

use crate::common::{files_with, own_scenes, shared_scenes};

/// Side of the comparison renders.
const SIZE: u32 = 128;

struct Gpu {
    ctx: GpuContext,
    renderer: GpuRenderer,
}

/// One device and compiled pipeline for the whole test binary.
fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    let gpu = GPU.get_or_init(|| {
        let required = std::env::var("GPURT_REQUIRE_GPU").is_ok_and(|v| v == "1");
        match gpurt::gpu::open(None) {
            Ok(ctx) => {
                let renderer = GpuRenderer::new(&ctx.device, None).expect("shader compiles");
                Ok(Gpu { ctx, renderer })
            }
            Err(e) if required => panic!("GPURT_REQUIRE_GPU=1 but: {e}"),
            Err(e) => Err(e.to_string()),
        }
    });
    match gpu {
        Ok(g) => {
            println!("GPU tests run on {}", g.ctx.describe());
            Some(g)
        }
        // Every GPU test says it skips, not only the first.
        Err(e) => {
            crate::common::skip(&format!("no GPU adapter: {e}"));
            None
        }
    }
}

fn render_both(
    g: &Gpu,
    scene: &Scene,
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
) -> (Film, Film) {
    let never = AtomicBool::new(false);
    let (cpu, _) = gpurt::cpu::render(buffers, globals, &|_| {}, &never).expect("CPU renders");
    let (gpu, _) = g
        .renderer
        .render(
            &g.ctx.device,
            &g.ctx.queue,
            buffers,
            globals,
            &|_| {},
            &never,
        )
        .unwrap_or_else(|e| panic!("{}: GPU render failed: {e}", scene.name));
    (cpu, gpu)
}

fn failure_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/gpu-vs-cpu")
}

/// Compares GPU and CPU images under `Thresholds::GPU_VS_CPU`, with the pixel-count limit
/// raised to the CPU's own noise floor where the plain limits fail (see
/// `Thresholds::check_allowing_noise`); on failure writes the images and returns a
/// message.
fn compare(
    label: &str,
    cpu: &RgbImage,
    gpu: &RgbImage,
    floor: impl FnOnce() -> gpurt::Result<f64>,
) -> Result<DiffStats, String> {
    let stats = compare::diff(cpu, gpu, Thresholds::GPU_VS_CPU.tolerance_255)
        .map_err(|e| format!("{label}: {e}"))?;
    let (floor, verdict) = Thresholds::GPU_VS_CPU
        .check_allowing_noise(&stats, floor)
        .map_err(|e| format!("{label}: {e}"))?;
    verdict
        .map_err(|why| match floor {
            Some(f) => format!(
                "{why}; the CPU's own one-ulp noise floor is {:.3}%",
                f * 100.0
            ),
            None => why,
        })
        .map(|()| stats)
        .map_err(|why| {
            let dir = failure_dir();
            let _ = std::fs::create_dir_all(&dir);
            let stem = label.trim().replace(['/', ' ', '.'], "_");
            let path = |suffix: &str| dir.join(format!("{stem}-{suffix}.png"));
            let _ = film::save_rgb8(cpu, &path("cpu"));
            let _ = film::save_rgb8(gpu, &path("actual"));
            if let Ok(heat) = compare::heat_map(cpu, gpu) {
                let _ = film::save_rgb8(&heat, &path("difference"));
            }
            format!("{label}: {why} ({stats}); images in {}", dir.display())
        })
}

/// One comparison's outcome: its label and statistics, or why it failed.
type Outcome = Result<(String, DiffStats), String>;

fn check_scene(g: &Gpu, label: &str, scene: &Scene, opts: &RenderOptions) -> Outcome {
    let buffers = pack::pack(scene.clone()).expect("scene packs");
    // The CPU walks the BVH as the GPU renderer does, so costs match node for node.
    let globals = g.renderer.frame(&buffers, &frame::globals(&buffers, opts));
    let (cpu, gpu) = render_both(g, scene, &buffers, &globals);
    if cpu.pixels.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("{label}: CPU image has non-finite values"));
    }
    let cpu = cpu.for_display(opts.aov).to_rgb8();
    let stats = compare(label, &cpu, &gpu.for_display(opts.aov).to_rgb8(), || {
        noise_floor(&buffers, &globals, &cpu)
    })?;
    Ok((label.to_string(), stats))
}

/// Every comparison a scene gets: colour at 1 and 4 samples per pixel, and each AOV.
fn check_variants(g: &Gpu, label: &str, scene: &Scene) -> Vec<Outcome> {
    let base = opts(scene);
    let variants = [
        ("", base.clone()),
        (
            "spp4",
            RenderOptions {
                spp: 4,
                ..base.clone()
            },
        ),
        (
            "normal",
            RenderOptions {
                aov: AOV_NORMAL,
                ..base.clone()
            },
        ),
        (
            "depth",
            RenderOptions {
                aov: AOV_DEPTH,
                ..base.clone()
            },
        ),
        (
            "cost",
            RenderOptions {
                aov: AOV_COST,
                ..base
            },
        ),
    ];
    variants
        .iter()
        .map(|(name, o)| check_scene(g, &format!("{label} {name}"), scene, o))
        .collect()
}

fn opts(scene: &Scene) -> RenderOptions {
    RenderOptions {
        width: SIZE,
        height: SIZE,
        ..RenderOptions::for_camera(&scene.camera)
    }
}

/// Fails with every mismatch at once; otherwise reports the worst agreement seen, which is
/// what `Thresholds::GPU_VS_CPU` has to allow.
fn check_all(cases: impl IntoIterator<Item = Outcome>) {
    let (passed, failures): (Vec<_>, Vec<_>) = cases.into_iter().partition(Result::is_ok);
    let failures: Vec<String> = failures.into_iter().filter_map(Result::err).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let passed: Vec<(String, DiffStats)> = passed.into_iter().filter_map(Result::ok).collect();
    let worst = |key: fn(&DiffStats) -> f64| {
        passed
            .iter()
            .max_by(|a, b| key(&a.1).total_cmp(&key(&b.1)))
            .map(|(label, s)| format!("{:.5} ({label})", key(s)))
            .unwrap_or_default()
    };
    println!(
        "{} comparisons; worst fraction over 2/255 {}, FLIP mean {}, |mean signed| {}",
        passed.len(),
        worst(|s| s.frac_over),
        worst(|s| s.flip_mean),
        worst(|s| s.mean_signed.abs())
    );
}

/// Default size factor of each SPD generator (docs/nff.md).
fn default_size(name: &str) -> Option<u32> {
    Some(match name {
        "balls" => 4,
        "gears" => 4,
        "mount" => 6,
        "rings" => 7,
        "teapot" => 6,
        "tetra" => 6,
        "tree" => 11,
        _ => return None,
    })
}

/// SPD scenes at sizes up to their generator's default, and every P3D file.
fn shared_scene_files(root: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = files_with(&root.join("spd"), &[".nff", ".nff.gz"])
        .into_iter()
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            let stem = name.split('.').next().unwrap_or("");
            let (kind, size) = stem.rsplit_once('-').unwrap_or((stem, ""));
            matches!((default_size(kind), size.parse::<u32>()), (Some(d), Ok(s)) if s <= d)
        })
        .collect();
    files.extend(files_with(&root.join("p3d"), &[".nff"]));
    files
}

#[test]
fn shared_scenes_match_cpu() {
    let (Some(g), Some(root)) = (gpu(), shared_scenes()) else {
        return;
    };
    let files = shared_scene_files(&root);
    assert!(
        files.len() >= 25,
        "expected the SPD and P3D scenes, found {files:?}"
    );
    check_all(files.iter().flat_map(|f| {
        let scene = scene::load(f).expect("shared scene loads");
        let name = f.strip_prefix(&root).unwrap_or(f).display().to_string();
        check_variants(g, &name, &scene)
    }));
}

#[test]
fn own_scenes_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let files = files_with(&own_scenes(), &[".nff"]);
    assert!(!files.is_empty(), "scenes/ has no .nff files");
    check_all(files.iter().flat_map(|f| {
        let scene = scene::load(f).expect("own scene loads");
        let name = f
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        check_variants(g, &name, &scene)
    }));
}

/// A small scene with every light kind, glass, a mirror, a cone and a box, written here so
/// the test does not depend on files that may change.
const FEATURES: &str = "
b 0.2 0.3 0.4
v
from 0 -6 2.5
at 0 0 0.6
up 0 0 1
angle 40
hither 0.01
resolution 128 128
l 4 -4 6
dl -1 1 -2 0.3 0.3 0.3
al -1 -1 5  2 0 0  0 2 0  0.8 0.8 0.7  3 3
f 0.8 0.8 0.8 0.8 0 1 0 1
pl 0 0 0  1 0 0  0 1 0
f 1 0.2 0.2 0.6 0.4 40 0 1
s -1.2 0 0.8 0.8
f 0.9 0.9 1 0.1 0.1 100 0.85 1.5
s 0.6 -1 0.7 0.7
f 0.2 0.8 0.3 0.7 0.2 20 0 1
c 1.6 1 0 0.5  1.6 1 1.5 0.2
f 0.9 0.7 0.2 0.8 0 1 0 1
aabb -0.3 0.5 0.8 1.6 0 0.6
";

fn features_scene(extra_view: &str) -> Scene {
    let text = FEATURES.replace(
        "resolution 128 128",
        &format!("resolution 128 128\n{extra_view}"),
    );
    gpurt::scene::nff::parse(text.as_bytes(), "features.nff", Path::new(".")).expect("parses")
}

/// Area, directional and point lights, glass, a mirror, a cone and a box, with and
/// without the thin lens, under every variant.
#[test]
fn lights_lens_and_every_primitive_kind_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let mut cases = check_variants(g, "features", &features_scene(""));
    cases.extend(check_variants(
        g,
        "features-lens",
        &features_scene("aperture 0.3\nfocal 6"),
    ));
    check_all(cases);
}

/// The same GPU with each traversal its adapter does not use by default (two of single,
/// pairs and wide), so that every walk is checked against the CPU on every adapter the
/// suite runs on.
fn other_traversals() -> &'static [Gpu] {
    static OTHERS: OnceLock<Vec<Gpu>> = OnceLock::new();
    OTHERS.get_or_init(|| {
        let Some(g) = gpu() else {
            return Vec::new();
        };
        [TRAVERSAL_SINGLE, TRAVERSAL_PAIRS, TRAVERSAL_WIDE]
            .into_iter()
            .filter(|&t| t != g.renderer.traversal())
            .map(|t| Gpu {
                ctx: g.ctx.clone(),
                renderer: GpuRenderer::new(&g.ctx.device, None)
                    .expect("shader compiles")
                    .with_traversal(t),
            })
            .collect()
    })
}

/// The other traversals find the same images and, walking the tree as the CPU twin of
/// each does, the same node costs: on the features scene, the bundled scenes and three
/// SPD scenes of thousands of primitives.
#[test]
fn the_other_traversals_match_cpu_too() {
    let mut cases = Vec::new();
    for g in other_traversals() {
        let walk = TRAVERSAL_NAMES[g.renderer.traversal() as usize];
        cases.extend(check_variants(
            g,
            &format!("features ({walk})"),
            &features_scene(""),
        ));
        for f in files_with(&own_scenes(), &[".nff"]) {
            let scene = scene::load(&f).expect("own scene loads");
            let name = format!("{} ({walk})", f.display());
            cases.extend(check_variants(g, &name, &scene));
        }
        if let Some(root) = shared_scenes() {
            for name in ["spd/balls-3.nff", "spd/mount-5.nff", "spd/teapot-6.nff"] {
                let scene = scene::load(&root.join(name)).expect("shared scene loads");
                cases.extend(check_variants(g, &format!("{name} ({walk})"), &scene));
            }
        }
    }
    check_all(cases);
}

/// The comparer must reject a wrong image: a GPU render with a block shifted sideways,
/// and one with a colour bias, both fail; the unmodified render passes. Checked on the
/// features scene and on balls-4, whose noise floor raises the pixel-count limit most.
#[test]
fn comparer_rejects_perturbed_gpu_images() {
    let Some(g) = gpu() else {
        return;
    };
    let mut scenes = vec![("features", features_scene(""))];
    if let Some(root) = shared_scenes() {
        let balls = scene::load(&root.join("spd/balls-4.nff")).expect("balls-4 loads");
        scenes.push(("balls-4", balls));
    }
    for (name, scene) in scenes {
        let o = opts(&scene);
        let buffers = pack::pack(scene.clone()).expect("scene packs");
        let globals = frame::globals(&buffers, &o);
        let (cpu, gpu) = render_both(g, &scene, &buffers, &globals);
        let (cpu, gpu) = (cpu.to_rgb8(), gpu.to_rgb8());
        let floor = || noise_floor(&buffers, &globals, &cpu);
        let label = |what: &str| format!("self-test-{name}-{what}");
        compare(&label("unperturbed"), &cpu, &gpu, floor).expect("unperturbed GPU image passes");

        let mut shifted = gpu.clone();
        for y in 40..72 {
            for x in 40..72 {
                shifted.put_pixel(x, y, *gpu.get_pixel(x - 6, y));
            }
        }
        assert!(
            compare(&label("shifted"), &cpu, &shifted, floor).is_err(),
            "{name}: shifted block passed"
        );

        let mut biased = gpu.clone();
        for p in biased.pixels_mut() {
            p.0 = p.0.map(|c| c.saturating_add(2));
        }
        assert!(
            compare(&label("biased"), &cpu, &biased, floor).is_err(),
            "{name}: colour bias passed"
        );
    }
}

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
        });
    }
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

fn refusal(device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene) -> String {
    let renderer = GpuRenderer::new(device, None).expect("shader module");
    render_with(device, queue, &renderer, scene)
        .expect_err("oversized scene must be refused")
        .to_string()
}

/// A scene larger than a storage binding or a texture the device allows is refused with a
/// message that names the limit and what needed more, never rendered as a black image.
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
    let msg = refusal(&device, &queue, &lit);
    assert!(
        msg.contains("lights")
            && msg.contains("max_storage_buffer_binding_size")
            && msg.contains(&mib.to_string()),
        "{msg}"
    );
    // Triangle normals travel in a texture array, like nodes and primitives: 30000
    // triangles' normals (1.4 MiB) render under that 1 MiB storage limit.
    let renderer = GpuRenderer::new(&device, None).expect("shader module");
    render_with(&device, &queue, &renderer, &with_triangles(30_000))
        .expect("normals beyond a storage binding render");
    // Nodes and primitives travel as texture arrays 4096 texels wide.
    let (device, queue) = device_with(
        g,
        wgpu::Limits {
            max_texture_dimension_2d: 16,
            ..g.ctx.adapter.limits()
        },
    );
    let msg = refusal(&device, &queue, &with_triangles(30_000));
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
    let renderer = GpuRenderer::new(&device, None)
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

/// A scene larger than one texture layer is split over several, as many as it needs:
/// with layers cut to 2 and 1 rows here (balls-4's 7383 primitives take 6 rows, its
/// nodes 3), the images and costs still match the CPU's.
#[test]
fn scenes_over_several_texture_layers_match_cpu() {
    let (Some(g), Some(root)) = (gpu(), shared_scenes()) else {
        return;
    };
    let scene = scene::load(&root.join("spd/balls-4.nff")).expect("balls-4 loads");
    let mut cases = Vec::new();
    for rows in [2, 1] {
        let layered = Gpu {
            ctx: g.ctx.clone(),
            renderer: GpuRenderer::new(&g.ctx.device, None)
                .expect("shader compiles")
                .with_layer_rows(rows),
        };
        let base = opts(&scene);
        for (name, aov) in [("", AOV_COLOR), ("cost", AOV_COST)] {
            let o = RenderOptions {
                aov,
                ..base.clone()
            };
            let label = format!("balls-4 in layers of {rows} rows {name}");
            cases.push(check_scene(&layered, &label, &scene, &o));
        }
    }
    check_all(cases);
}

/// Renders on both backends and checks agreement (with the noise floor) and ray counts:
/// equal within one in 10^4, the drift that lights grazing a surface give (lavapipe's
/// normalize and sqrt are not the CPU's; 47 of 2.65 million shadow rays in the thousand
/// lights case), where dropped samples or bounces lose a tenth or more.
fn check_heavy(g: &Gpu, label: &str, scene: &Scene, opts: &RenderOptions) -> Outcome {
    let buffers = pack::pack(scene.clone()).expect("scene packs");
    let globals = g.renderer.frame(&buffers, &frame::globals(&buffers, opts));
    let never = AtomicBool::new(false);
    let (cpu, counts) =
        gpurt::cpu::render(&buffers, &globals, &|_| {}, &never).expect("CPU renders");
    let (gpu, rays) = g
        .renderer
        .render(
            &g.ctx.device,
            &g.ctx.queue,
            &buffers,
            &globals,
            &|_| {},
            &never,
        )
        .map_err(|e| format!("{label}: GPU render failed: {e}"))?;
    let a = gpurt::agreement::agreement(&buffers, &globals, &cpu, &gpu).expect("compares");
    a.verdict
        .map_err(|why| format!("{label}: {why} ({})", a.stats))?;
    let drift = rays.abs_diff(counts.total()) as f64 / counts.total() as f64;
    if drift > 1e-4 {
        return Err(format!(
            "{label}: the GPU traced {rays} rays, the CPU {}",
            counts.total()
        ));
    }
    Ok((label.to_string(), a.stats))
}

/// An 8x8 area light over a glass sphere and a box: 64 shadow rays per hit.
const AREA_GLASS: &str = "
b 0.05 0.05 0.07
v
from 0 -9 4.5
at 0 0 0.8
up 0 0 1
angle 36
hither 0.01
resolution 64 64
al -1 -1 5 2 0 0 0 2 0 0.85 0.85 0.8 8 8
f 0.85 0.85 0.85 0.85 0 1 0 1
p 4
-10 -10 0
10 -10 0
10 10 0
-10 10 0
f 1 1 1 0.1 0.3 60 0.8 1.5
s -1 0 1.2 1.2
f 0.3 0.45 0.9 0.8 0.1 30 0 1
aabb 0.6 2.4 -0.6 1.2 0 1.4
";

/// Many samples per pixel, which one invocation could not all trace on lavapipe (it ends
/// every loop once an invocation has run 65535 loop iterations): traced a pass of samples
/// at a time, they agree with the CPU, rays counted alike.
#[test]
fn many_samples_per_pixel_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let area = gpurt::scene::nff::parse(AREA_GLASS.as_bytes(), "area-glass.nff", Path::new("."))
        .expect("parses");
    let mut cases = vec![check_heavy(
        g,
        "area light and glass, 64 spp",
        &area,
        &RenderOptions {
            spp: 64,
            ..RenderOptions::for_camera(&area.camera)
        },
    )];
    if let Some(root) = shared_scenes() {
        for (name, side, spp) in [
            ("gears-4", 64, 32),
            ("teapot-6", 48, 64),
            ("mount-5", 48, 64),
        ] {
            let scene = scene::load(&root.join(format!("spd/{name}.nff"))).expect("loads");
            let opts = RenderOptions {
                width: side,
                height: side,
                spp,
                ..RenderOptions::for_camera(&scene.camera)
            };
            cases.push(check_heavy(g, &format!("{name} {spp} spp"), &scene, &opts));
        }
    }
    check_all(cases);
}

/// One sample whose work exceeds what one invocation may do on lavapipe (glass at depth
/// 16; a thousand lights): such pixels continue across dispatches and agree with the CPU.
#[test]
fn heavy_single_samples_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let mut cases = vec![check_heavy(
        g,
        "glass at depth 16",
        &glass,
        &RenderOptions {
            width: 64,
            height: 64,
            max_depth: 16,
            ..RenderOptions::for_camera(&glass.camera)
        },
    )];
    if let Some(root) = shared_scenes() {
        let mut src = std::fs::read_to_string(root.join("spd/balls-3.nff")).expect("reads");
        for i in 0..1000 {
            let (x, y) = ((i % 40) as f32 * 0.15 - 3.0, (i / 40) as f32 * 0.25 - 3.0);
            src.push_str(&format!("l {x} {y} 3 0.01 0.01 0.01\n"));
        }
        let lights = gpurt::scene::nff::parse(src.as_bytes(), "balls-3-lights.nff", Path::new("."))
            .expect("parses");
        let opts = RenderOptions {
            width: 48,
            height: 48,
            ..RenderOptions::for_camera(&lights.camera)
        };
        cases.push(check_heavy(g, "balls-3 with 1000 lights", &lights, &opts));
    }
    check_all(cases);
}

/// A ray whose one traversal is too long for lavapipe's loop limit cannot be split
/// further: a shadow ray up a column of 40000 overlapping glass spheres visits every one.
/// The GPU either agrees with the CPU or fails naming the cause, never returns a darker
/// image.
#[test]
fn unfinished_pixels_are_an_error_never_a_darker_image() {
    let Some(g) = gpu() else {
        return;
    };
    let mut src = String::from(
        "b 0.2 0.2 0.2\nv\nfrom 4 0 0.3\nat 0 0 0.2\nup 0 0 1\nangle 20\nhither 0.01\n\
         resolution 32 32\nl 0 0 30\nf 0.8 0.8 0.8 0.8 0 1 0 1\n\
         p 4\n-3 -3 0\n3 -3 0\n3 3 0\n-3 3 0\nf 0.9 0.9 1 0.1 0 1 0.9 1\n",
    );
    for i in 0..40_000 {
        src.push_str(&format!("s 0 0 {:.4} 0.5\n", 1.0 + i as f32 * 0.0002));
    }
    let scene =
        gpurt::scene::nff::parse(src.as_bytes(), "column.nff", Path::new(".")).expect("parses");
    let opts = RenderOptions::for_camera(&scene.camera);
    if let Err(e) = check_heavy(g, "a column of 40000 glass spheres", &scene, &opts) {
        assert!(
            e.contains("GPU render failed") && e.contains("could not finish"),
            "{e}"
        );
    }
}

/// balls-5 and balls-6 (outside the default sizes) at 128x128 and 4 spp: thousands of
/// sub-pixel mirror spheres. The GPU differs from the CPU on 0.9% and 1.8% of pixels
/// (lavapipe), unbiased, where the CPU differs from itself on 2.5% and 4.6% when its eye
/// moves by one ulp: they agree within the noise floor, which is the limit set for them.
#[test]
fn sub_pixel_sphere_scenes_agree_within_their_noise_floor() {
    let (Some(g), Some(root)) = (gpu(), shared_scenes()) else {
        return;
    };
    check_all(["balls-5", "balls-6"].map(|name| {
        let scene = scene::load(&root.join(format!("spd/{name}.nff.gz"))).expect("loads");
        let opts = RenderOptions {
            spp: 4,
            ..opts(&scene)
        };
        check_scene(g, &format!("spd/{name} spp4"), &scene, &opts)
    }));
}

/// The stratification of samples is the CPU's on the GPU too: the half-covered column of
/// `cpu::HALF_COLUMN` at sample counts that are neither squares nor 2 x N.
#[test]
fn sample_pattern_matches_cpu_on_an_edge() {
    let Some(g) = gpu() else {
        return;
    };
    let scene = gpurt::scene::nff::parse(
        crate::cpu::HALF_COLUMN.as_bytes(),
        "edge.nff",
        Path::new("."),
    )
    .expect("parses");
    for spp in [3, 5, 7, 10] {
        let opts = RenderOptions {
            spp,
            ..RenderOptions::for_camera(&scene.camera)
        };
        let buffers = pack::pack(scene.clone()).expect("packs");
        let globals = frame::globals(&buffers, &opts);
        let (cpu, gpu) = render_both(g, &scene, &buffers, &globals);
        let (c, m) = (
            crate::cpu::column_mean(&cpu, 100),
            crate::cpu::column_mean(&gpu, 100),
        );
        assert!(
            (m - 0.5).abs() <= 0.02 && (m - c).abs() < 1e-3,
            "{spp} spp: GPU {m}, CPU {c}"
        );
    }
}

/// Spheres each 1.5 times as far out as the last chain obvhs' clustering into a tree
/// deeper than the traversal stack (`bvh::tests` shows it); the scene is built by median
/// splits instead (depth log2(n / 4) + 2) and renders the same on both backends, seen
/// along the chain.
#[test]
fn a_scene_deeper_than_the_traversal_stack_renders_and_matches_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let mut src = String::from(
        "v from -4 3 2 at 40 0 0 up 0 0 1 angle 60 hither 0.01 resolution 96 64\n\
         b 0.1 0.1 0.2\nl -10 10 10\nf 1 0.5 0.2 0.7 0.3 20 0 1\n",
    );
    for k in 0..200 {
        let x = 1.5f64.powi(k);
        src.push_str(&format!("s {x} 0 0 {}\n", x * 0.3));
    }
    let scene = scene::nff::parse(src.as_bytes(), "chain", Path::new(".")).expect("parses");
    let buffers = pack::pack(scene.clone()).expect("packs");
    assert!(
        buffers.bvh_depth <= 7,
        "median depth, got {}",
        buffers.bvh_depth
    );
    check_all([check_scene(g, "chain", &scene, &opts(&scene))]);
}

/// A flat mesh (one triangle at z = 0, read as a bare STL) lies just above its automatic
/// ground plane, not in it: no z-fighting, so both renderers agree.
#[test]
fn flat_bare_mesh_does_not_fight_its_ground() {
    let Some(g) = gpu() else {
        return;
    };
    let tri = gpurt::scene::Triangle {
        v: [
            glam::Vec3::new(0.0, 0.0, 0.0),
            glam::Vec3::new(1.0, 0.0, 0.0),
            glam::Vec3::new(0.0, 1.0, 0.0),
        ],
        n: None,
        material: gpurt::scene::MaterialId(0),
    };
    let dir = crate::common::temp_dir("flat-mesh");
    let path = dir.join("flat.stl");
    std::fs::write(&path, gpurt::scene::stl::write_binary(&[tri], &[0; 80])).unwrap();
    let scene = scene::load(&path).expect("loads");
    // With the ground in the mesh's plane, 0.38% of pixels differed (under the general
    // limit, which allows for grazing rays); with the gap, none may.
    let (_, stats) = check_scene(g, "flat.stl", &scene, &opts(&scene)).expect("agrees");
    assert_eq!(stats.pixels_over, 0, "{stats}");
}

/// Extreme but legal scenes: each one reads (degenerate shapes dropped or kept with a
/// warning), renders to finite pixels on the CPU, and the GPU agrees with it.
#[test]
fn extreme_values_render_finite_and_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let view = "v from 0 -8 2 at 0 0 0 up 0 0 1 angle 50 hither 1e-6 resolution 64 64\n";
    let lit = "l 3 -6 6\nf 0.8 0.6 0.4 0.7 0.3 20 0 1\n";
    let cases = [
        (
            "tiny and huge spheres",
            format!("{view}{lit}s 0 0 0 1e-30\ns 1e30 0 0 1e29\ns 0 3 0 1\ns 0 0 1e-30 1e-31\n"),
        ),
        (
            // Shadow rays from the huge sphere start at infinity; three leaves leave a
            // wide node's lanes partly empty, whose infinite boxes give such a ray NaN
            // slab distances (the CPU walk once took one for a leaf and panicked).
            "rays from infinity",
            format!("{view}{lit}s 1e30 0 0 1e29\ns 0 3 0 1\ns 0 0 1e-30 1e-31\n"),
        ),
        (
            "camera inside a sphere",
            "v from 0 0 0 at 1 0 0 up 0 0 1 angle 60 resolution 64 64\nl 0 0 1\n\
             f 0.8 0.8 0.8 0.8 0.2 10 0 1\ns 0 0 0 10\ns 3 0 0 1\n"
                .to_string(),
        ),
        (
            "every light inside closed glass",
            format!(
                "{view}l 0 0 1\nl 0.2 0 1.1\nf 1 1 1 0.1 0.2 30 0.9 1.5\ns 0 0 1 2\n\
                 f 0.8 0.8 0.8 0.8 0 1 0 1\np 4 -10 -10 -1 10 -10 -1 10 10 -1 -10 10 -1\n"
            ),
        ),
        (
            "zero-area triangles",
            format!(
                "{view}{lit}p 3 0 0 0 1 1 1 2 2 2\np 3 1 1 1 1 1 1 1 1 1\n\
                 pp 3 0 0 0 0 0 1 1 0 0 0 0 1 2 0 0 0 0 1\ns 0 2 0 1\n"
            ),
        ),
        (
            "degenerate cones and boxes",
            format!(
                "{view}{lit}c 0 0 0 1 0 0 0 1\nc 0 0 0 0 0 0 1 0\nc 1 0 0 -1 1 0 2 -0.5\n\
                 aabb 1 -1 1 -1 1 -1\naabb 2 2 0 1 0 1\ns -2 0 0 0.5\n"
            ),
        ),
    ];
    let mut outcomes = Vec::new();
    for (name, text) in &cases {
        let scene = gpurt::scene::nff::parse(text.as_bytes(), "extreme.nff", Path::new("."))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            !scene.spheres.is_empty() || !scene.triangles.is_empty() || !scene.cones.is_empty(),
            "{name}: nothing left to render"
        );
        let o = RenderOptions {
            width: 64,
            height: 64,
            ..RenderOptions::for_camera(&scene.camera)
        };
        outcomes.push(check_scene(g, name, &scene, &o));
    }
    check_all(outcomes);
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
/// the render with an error naming the step, never a partial image. On software adapters
/// only: on the H100 this test passed alone, but the whole suite hung in the run that
/// first had it, with this test among those that never finished (a device destroyed
/// while other tests' devices on the same GPU were busy is the suspect; not yet
/// understood, see docs/gpu.md). `GPURT_TEST_LOSS_ON_HARDWARE=1` runs it there too, to
/// look into that.
#[test]
fn a_device_lost_half_way_is_an_error_not_an_image() {
    let Some(g) = gpu() else {
        return;
    };
    let anywhere = std::env::var("GPURT_TEST_LOSS_ON_HARDWARE").is_ok_and(|v| v == "1");
    if g.ctx.info.device_type != wgpu::DeviceType::Cpu && !anywhere {
        crate::common::skip("runs on software adapters only (see its comment)");
        return;
    }
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

/// Dispatches over the renderer's time budget (kept well inside a driver's watchdog) make
/// the rest of the frame, and the frames after it, cut finer: on lavapipe, which has no
/// watchdog, a budget of a nanosecond forces it. The image and the rays stay the same to
/// the bit, although most tiles are then submitted in several buffer-fulls.
#[test]
fn dispatches_over_the_budget_are_cut_finer_and_change_nothing() {
    let Some(g) = gpu() else {
        return;
    };
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    // Two bands on a software adapter: 256 rows of 96 pixels at 8 samples fill one.
    let frame = RenderOptions {
        width: 96,
        height: 300,
        spp: 8,
        ..opts(&scene)
    };
    let globals = frame::globals(&buffers, &frame);
    let never = AtomicBool::new(false);
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let trace_twice = |r: &GpuRenderer| {
        let up = r
            .upload(device, queue, &buffers, &globals)
            .expect("uploads");
        let before = up.dispatch_shape();
        let first = gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
        let after = up.dispatch_shape();
        let second = gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
        (before, after, first, second)
    };
    // The default budget: none on a software adapter; a frame this small is far inside
    // it on a GPU.
    let (shape, kept, reference, again) = trace_twice(&g.renderer);
    assert_eq!(shape, kept, "the default budget refined a small frame");
    assert_eq!(again, reference);

    let tight = GpuRenderer::new(device, None)
        .expect("shader module")
        .with_dispatch_budget(std::time::Duration::from_nanos(1));
    let (before, after, first, second) = trace_twice(&tight);
    assert_eq!(before, shape);
    assert_eq!(
        after,
        (WORKGROUP_SIDE, 1),
        "cut down to one workgroup, one sample"
    );
    println!("dispatch shape {shape:?} -> {after:?}");
    assert!(
        first == reference,
        "a finer cut changed the image or the rays"
    );
    assert!(second == reference, "the refined cut's next frame changed");
}
