//! What a frame takes on this adapter: which walk of the BVH, which kernels (the one
//! `main` kernel, its `pooled` form or the wavefront ones) and which way of reading the
//! scene (`Strategy`), by what was measured for the kind of adapter (`defaults`) or on
//! the adapter itself (`gpurt tune`, kept by `tuning`), per scene where its tree or size
//! allows, and overridable from the environment for measuring them side by side; and
//! how the frame is cut into work.

use super::cut::{BAND_BYTES, Cut, Shape};
use super::shaders::Fetch;
use crate::gpu_types::{
    AOV_COLOR, GpuGlobals, LIGHT_AREA, LIGHT_EMITTER, POOL_MAX_SIDE, POOL_SIDE, TRAVERSAL_NAMES,
    TRAVERSAL_WIDE, WAVE_RAYS_PER_PATH, WORKGROUP_INVOCATIONS, WORKGROUP_SIDE, wave_buffer_bytes,
};
use crate::pack::SceneBuffers;
use crate::util::error::{Error, Result};

/// The walk of the BVH, the kernels of a colour frame and the way the shaders read the
/// scene that a renderer takes on an adapter: `defaults` (what was measured for the kind
/// of adapter), or what `gpurt tune` measured on the adapter itself (`tuning`), each
/// overridden by its variable of the environment where set (`traversal_for`,
/// `kernels_for`, `fetch_for`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Strategy {
    /// `TRAVERSAL_*`, where a scene's tree allows (`SceneBuffers::traversal_for`).
    pub traversal: u32,
    pub kernels: Kernels,
    pub fetch: Fetch,
}

/// The choice for an adapter that `gpurt tune` has not measured, by what was measured on
/// lavapipe and on the H100 and H200 (docs/gpu.md has the figures):
///
/// - the walk: `TRAVERSAL_WIDE` on every adapter (each scene falls back to pairs where its
///   wide tree does not fit the stack). On the H100 a ray's time goes to waiting on node
///   fetches, and the four-wide tree halves the chain of them: 1.2 to 1.5 times faster
///   than pairs, which was 1.2 to 1.4 times faster than single. On lavapipe it is 2 to
///   19% faster than single. The compressed eight-wide walk (`TRAVERSAL_CWIDE`) fetches
///   40 to 56% fewer node bytes, yet is 1.3 to 1.7 times slower on the H100 and slower on
///   lavapipe's larger scenes. The quantised four-wide walk (`TRAVERSAL_QWIDE`, the wide
///   walk on nodes of 64 bytes) fetches 41 to 43% fewer node bytes and is as fast as wide
///   on lavapipe, but 1.14 to 1.30 times slower on an H200 (`gpurt tune`);
/// - the kernels: the one kernel, `main` (`wavefront_for`, `pooled_for`);
/// - the fetch: storage textures on software adapters, which lavapipe loads a texel at a
///   time where it loads a storage buffer a component at a time (docs/gpu.md, item 2),
///   and storage buffers on hardware ones: on an H100 (docs/gpu.md, "Storage buffers")
///   buffers traced every frame of seven scenes 1.07 to 1.34 times faster than the
///   textures, with the same rays and node fetches. In the browser, unmeasured so far,
///   the textures stay.
pub fn defaults(software: bool) -> Strategy {
    Strategy {
        traversal: TRAVERSAL_WIDE,
        kernels: Kernels::Main,
        fetch: match software || !cfg!(feature = "native") {
            true => Fetch::Textures,
            false => Fetch::Buffers,
        },
    }
}

/// The walk: `GPURT_TRAVERSAL` (`single`, `pairs`, `wide`, `cwide` or `qwide`:
/// `TRAVERSAL_NAMES`) where set, for measuring the walks on one adapter, else `chosen`.
pub(super) fn traversal_for(chosen: u32) -> Result<u32> {
    match std::env::var("GPURT_TRAVERSAL").as_deref() {
        Err(_) | Ok("") => Ok(chosen),
        Ok(v) => match TRAVERSAL_NAMES.iter().position(|&n| n == v) {
            Some(t) => Ok(t as u32),
            None => Err(Error::Render(format!(
                "GPURT_TRAVERSAL={v}: expected one of {}",
                TRAVERSAL_NAMES.join(", ")
            ))),
        },
    }
}

/// How a renderer's shaders read the scene's nodes, primitives and normals: `GPURT_FETCH`
/// (`textures` or `buffers`) where set; else `chosen`, unless the scenes in hand
/// (`buffers_fit` false) have an array larger than one storage buffer may be (textures
/// grow by layers).
pub(super) fn fetch_for(chosen: Fetch, buffers_fit: bool) -> Result<Fetch> {
    let var = std::env::var("GPURT_FETCH");
    fetch_by(var.as_deref().ok(), chosen, buffers_fit)
}

/// `fetch_for` with `GPURT_FETCH`'s value given (`None`: unset).
fn fetch_by(var: Option<&str>, chosen: Fetch, buffers_fit: bool) -> Result<Fetch> {
    match var {
        None | Some("") if !buffers_fit => Ok(Fetch::Textures),
        None | Some("") => Ok(chosen),
        Some("textures") => Ok(Fetch::Textures),
        Some("buffers") => Ok(Fetch::Buffers),
        Some(v) => Err(Error::Render(format!(
            "GPURT_FETCH={v}: expected textures or buffers"
        ))),
    }
}

/// The kernels that trace a colour frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernels {
    /// The one kernel, `main`.
    Main,
    /// The wavefront kernels (`shaders/wavefront.wgsl`).
    Wavefront,
    /// The one kernel with a workgroup's samples shared out among its lanes (`pooled`).
    Pooled,
}

impl Kernels {
    /// Every kind, by the name `GPURT_KERNELS` takes.
    pub const ALL: [Kernels; 3] = [Kernels::Main, Kernels::Wavefront, Kernels::Pooled];

    /// The name `GPURT_KERNELS` (and `--stats`, and a tuning file) gives it.
    pub fn name(self) -> &'static str {
        match self {
            Kernels::Main => "main",
            Kernels::Wavefront => "wavefront",
            Kernels::Pooled => "pooled",
        }
    }

    /// The kernels named `name`.
    pub fn from_name(name: &str) -> Option<Kernels> {
        Kernels::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// The kernels of every colour frame: `GPURT_KERNELS` (`main`, `wavefront` or `pooled`)
/// where set, else `chosen`; `wavefront_for` and `pooled_for` then say which frames
/// can take them.
pub(super) fn kernels_for(chosen: Kernels) -> Result<Kernels> {
    match std::env::var("GPURT_KERNELS").as_deref() {
        Err(_) | Ok("") => Ok(chosen),
        Ok(v) => Kernels::from_name(v).ok_or_else(|| {
            Error::Render(format!(
                "GPURT_KERNELS={v}: expected main, wavefront or pooled"
            ))
        }),
    }
}

/// Whether a frame traced by the one kernel takes its `pooled` entry point: where forced
/// (`GPURT_KERNELS=pooled`, `GpuRenderer::with_pooled`), for colour frames (an AOV
/// traces one ray a sample, which leaves no lane idle for long), else `main`. Nowhere by
/// default: on an H200 it was 1.04 to 1.59 times `main`'s frame time on the SPD scenes
/// (`gpurt tune`, 1080p), and on lavapipe, which runs every lane through every branch,
/// it has nothing to gain.
pub(super) fn pooled_for(forced: bool, globals: &GpuGlobals) -> bool {
    forced && globals.aov == AOV_COLOR
}

/// Whether a frame of `scene` traces through the wavefront kernels, where the
/// renderer's kernels are the wavefront ones (`wavefront`: `GPURT_KERNELS`, a tuning,
/// `GpuRenderer::with_wavefront`). Colour frames without area lights or emitters only: an
/// AOV traces eye rays alone, which one kernel does without idle lanes, and the samples of
/// an area light or an emitter draw from a path's random stream in the depth-first order of its ray tree, which the
/// wavefront's rounds (a generation of rays each) cannot follow.
///
/// Measured (docs/gpu.md, "The wavefront kernels"): the one kernel is 1.3 to 1.7 times
/// faster than the kernels over queues of rays on lavapipe, and 2.8 to 41 times on an
/// H200 (seven scenes, 1080p and 4K, 1 and 16 spp), so no adapter's defaults take them.
pub(super) fn wavefront_for(wavefront: bool, scene: &SceneBuffers, globals: &GpuGlobals) -> bool {
    let sampled = (scene.lights.iter()).any(|l| matches!(l.kind, LIGHT_AREA | LIGHT_EMITTER));
    globals.aov == AOV_COLOR && !sampled && wavefront
}

/// Pixels a side of a wave's tile at most, before `cut_for` fits its records to
/// `WAVE_BYTES` and the device's limits.
const WAVE_TILE_SIDE: u32 = 1024;

/// Device memory a wave's records may take (`gpu_types::wave_buffer_bytes`): about 510 +
/// 210 x lights bytes a path, so 262 144 paths (a power of two) for one to three lights.
const WAVE_BYTES: u64 = 512 << 20;

/// How much work a dispatch and a submission take on this adapter. Software adapters
/// get small bands so that Ctrl-C and the progress bar respond within a second, one
/// sample per pass (lavapipe ends every loop once an invocation has run 65535 loop
/// iterations in all, and one sample of an ordinary scene needs far fewer) and tiles of
/// 256x256 pixels, scattered over their threads. GPUs take up to `GPU_PASS_SAMPLES`
/// samples a pass on strips as wide as the frame of up to `GPU_DISPATCH_SAMPLES` pixel
/// samples, in bands of up to `GPU_BAND_BYTES`; a band is the most one submission should
/// hold. `GPURT_PASS_SAMPLES`, `GPURT_DISPATCH_SAMPLES`, `GPURT_BAND_BYTES` and
/// `GPURT_WAVE_SIDE` and `GPURT_WAVE_BYTES` (a wavefront frame's wave: `WAVE_TILE_SIDE`
/// and `WAVE_BYTES` by default) override the shape, for measuring it on one adapter.
pub(super) fn shape_for(software: bool) -> Result<Shape> {
    let mut shape = if software {
        Shape {
            pass_samples: 1,
            dispatch_samples: 1 << 16,
            band_samples: 1 << 18,
            wave_side: WAVE_TILE_SIDE,
            wave_bytes: WAVE_BYTES,
            spread: true,
            strips: false,
            band_bytes: BAND_BYTES,
            pool_side: POOL_SIDE,
        }
    } else {
        gpu_shape()
    };
    if let Some(n) = count_from_env("GPURT_PASS_SAMPLES")? {
        shape.pass_samples = u32::try_from(n).unwrap_or(u32::MAX);
    }
    if let Some(n) = count_from_env("GPURT_DISPATCH_SAMPLES")? {
        shape.dispatch_samples = n;
    }
    if let Some(n) = count_from_env("GPURT_BAND_BYTES")? {
        shape.band_bytes = n;
    }
    if let Some(n) = count_from_env("GPURT_WAVE_SIDE")? {
        // A power of two, as tile sides are.
        shape.wave_side = (n.min(1 << 15) as u32).next_power_of_two();
    }
    if let Some(n) = count_from_env("GPURT_WAVE_BYTES")? {
        shape.wave_bytes = n;
    }
    if let Some(n) = count_from_env("GPURT_POOL_SIDE")? {
        // Whole 8x8 blocks, at most 64 pixels a lane.
        let side = u32::try_from(n).unwrap_or(u32::MAX).clamp(1, POOL_MAX_SIDE);
        shape.pool_side = side.next_multiple_of(WORKGROUP_SIDE);
    }
    Ok(shape)
}

/// The shape of a GPU's work (`shape_for`), before the environment's overrides.
pub(super) fn gpu_shape() -> Shape {
    Shape {
        pass_samples: GPU_PASS_SAMPLES,
        dispatch_samples: GPU_DISPATCH_SAMPLES,
        band_samples: 1 << 26,
        wave_side: WAVE_TILE_SIDE,
        wave_bytes: WAVE_BYTES,
        spread: false,
        strips: true,
        band_bytes: GPU_BAND_BYTES,
        pool_side: POOL_SIDE,
    }
}

/// Samples of a pixel one dispatch traces at most on a GPU: at 16 spp, four passes of 4
/// were up to 10% faster on an H200 than sixteen of 1 (docs/gpu.md).
const GPU_PASS_SAMPLES: u32 = 4;

/// Output bytes a band holds at most on a GPU: a 4K frame's 133 MB in one band.
const GPU_BAND_BYTES: u64 = 256 << 20;

/// Pixel samples one dispatch traces at most on a GPU: a 4K frame at one sample is one
/// dispatch, at 4 samples a pass two strips of 1088 rows, over four million invocations
/// each, many times what a large GPU holds at once, so that few dispatches end with the
/// GPU half idle. On an H200 (docs/gpu.md, docs/speed.md), strips of 2^24 made 4K frames of
/// seven scenes 2 to 22% faster than the 1024x1024 squares of 2^22 before them (12
/// dispatches a frame at 1 spp, four of them 112 rows high); strips of 2^22 were slower
/// at 16 spp. A slow GPU's
/// dispatches over `DISPATCH_BUDGET` are cut finer (`Cut::finer`).
const GPU_DISPATCH_SAMPLES: u64 = 1 << 24;

/// A positive whole number from the environment variable `name`; `None` where it is
/// unset or empty.
/// `GPURT_STACK`: the fewest entries of each invocation's traversal stack, rounded up to a
/// multiple of 8 as the stack a tree needs is (`Specialization::stack`); never fewer than
/// the tree needs, which the walk could overflow. For measuring what the stack's size
/// costs a GPU apart from the tree (the SAH-optimal collapse's trees need deeper stacks
/// on some scenes, docs/speed.md); 0, no floor, by default.
pub(super) fn stack_floor() -> Result<u32> {
    let n = count_from_env("GPURT_STACK")?.unwrap_or(0);
    // At most the fixed stack the walks once had, which every tree fits.
    Ok((n.min(crate::gpu_types::TRAVERSAL_STACK as u64) as u32).next_multiple_of(8))
}

fn count_from_env(name: &str) -> Result<Option<u64>> {
    match std::env::var(name).as_deref() {
        Err(_) | Ok("") => Ok(None),
        Ok(v) => match v.parse::<u64>() {
            Ok(n) if n > 0 => Ok(Some(n)),
            _ => Err(Error::Render(format!(
                "{name}={v}: expected a whole number above 0"
            ))),
        },
    }
}

/// How a frame of `globals`' size and samples is cut on this device, with `shape`'s
/// work a dispatch and a submission. The wavefront path's tiles are its waves: squares,
/// at most `shape.wave_side` a side. Where the one kernel takes its `pooled` entry
/// point, a workgroup traces a square of `shape.pool_side` pixels a side.
pub(super) fn cut_for(
    limits: &wgpu::Limits,
    globals: &GpuGlobals,
    shape: &Shape,
    pooled: bool,
) -> Cut {
    let shape = &Shape {
        strips: shape.strips && globals.wavefront == 0,
        ..*shape
    };
    let mut cut = Cut::new(
        globals.width,
        globals.height,
        globals.spp,
        shape,
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size),
    );
    if globals.wavefront != 0 {
        // Halve the side (bands stay whole rows of tiles, sides being powers of two),
        // down to one workgroup's square, until the wave fits.
        let paths = |side: u32| u64::from(side * side) * u64::from(cut.pass_samples);
        let mut side = cut.tile_rows.min(shape.wave_side);
        while side > WORKGROUP_SIDE && !wave_fits(limits, shape, paths(side), globals.n_lights) {
            side /= 2;
        }
        (cut.tile_width, cut.tile_rows) = (side, side);
    } else if pooled {
        cut.group_side = shape.pool_side;
    }
    cut
}

/// Whether a wave of `paths` paths on a scene of `lights` lights fits: each of its
/// records a storage binding, all of them `shape.wave_bytes`, and the dispatches over a
/// round's rays and over its shadow rays (a slot per ray and light, all of them queued at
/// most) the device's workgroups: past that, a dispatch sized on the device does nothing.
fn wave_fits(limits: &wgpu::Limits, shape: &Shape, paths: u64, lights: u32) -> bool {
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let bytes = wave_buffer_bytes(paths, u64::from(lights));
    let slots = paths * WAVE_RAYS_PER_PATH * u64::from(lights.max(1));
    let groups = slots.div_ceil(WORKGROUP_INVOCATIONS.into());
    bytes.iter().all(|&b| b <= limit)
        && bytes.iter().sum::<u64>() <= shape.wave_bytes
        && groups <= u64::from(limits.max_compute_workgroups_per_dimension)
}

#[cfg(test)]
mod tests {
    use super::{
        Fetch, Kernels, Shape, cut_for, defaults, fetch_by, gpu_shape, shape_for, wave_fits,
    };
    use crate::gpu::wavefront::wave_paths;
    use crate::gpu_types::{GpuGlobals, WAVE_RAYS_PER_PATH, WORKGROUP_INVOCATIONS};

    /// A wavefront frame's waves fit (`wave_fits`: each record a storage binding, all of
    /// them the shape's `wave_bytes`, the dispatches over a round's rays and its shadow
    /// slots the device's workgroups), and they are as large as that allows (twice the side would not fit,
    /// or the side is the cap). More lights make smaller waves.
    #[test]
    fn a_waves_records_fit_the_budget_and_the_device() {
        let big = wgpu::Limits {
            max_storage_buffer_binding_size: u32::MAX as u64,
            max_buffer_size: u64::MAX,
            ..wgpu::Limits::default()
        };
        let small = wgpu::Limits::default();
        for (limits, shape) in [(&big, gpu_shape()), (&small, shape_for(true).unwrap())] {
            let mut last = u32::MAX;
            for lights in [1, 3, 5, 12, 400] {
                let globals = GpuGlobals {
                    width: 3840,
                    height: 2160,
                    spp: 16,
                    n_lights: lights,
                    wavefront: 1,
                    ..Default::default()
                };
                let cut = cut_for(limits, &globals, &shape, false);
                assert_eq!(cut.tile_width, cut.tile_rows, "square waves");
                let fits = |side: u32| {
                    let paths = u64::from(side * side * cut.pass_samples);
                    wave_fits(limits, &shape, paths, lights)
                };
                // The square tile the cut would make anyway caps a wave's side too.
                let squares = Shape {
                    strips: false,
                    ..shape
                };
                let plain = GpuGlobals {
                    wavefront: 0,
                    ..globals
                };
                let cap = cut_for(limits, &plain, &squares, false)
                    .tile_rows
                    .min(shape.wave_side);
                let side = cut.tile_rows;
                assert!(fits(side), "{lights} lights: side {side}");
                assert!(
                    side == cap || !fits(2 * side),
                    "{lights} lights: side {side} of {cap}"
                );
                let paths = wave_paths(&cut);
                // The dispatches over a round's rays and over its shadow slots.
                let slots = u64::from(paths) * WAVE_RAYS_PER_PATH * u64::from(lights);
                let groups = slots.div_ceil(WORKGROUP_INVOCATIONS.into());
                assert!(
                    groups <= u64::from(limits.max_compute_workgroups_per_dimension),
                    "{lights} lights: {groups} workgroups over the shadow slots"
                );
                assert!(paths <= last, "{lights} lights: {paths} paths");
                last = paths;
            }
        }
    }

    /// Unset, the adapter's choice stands (buffers on hardware by default, textures on
    /// software adapters), but a scene too large for one buffer reads textures; set,
    /// `GPURT_FETCH` decides, even for such a scene (whose upload is then refused with
    /// the limit named); anything else is an error naming the variable.
    #[test]
    fn the_fetch_follows_the_adapter_the_scene_and_the_variable() {
        let hardware = match cfg!(feature = "native") {
            true => Fetch::Buffers,
            false => Fetch::Textures,
        };
        assert_eq!(defaults(false).fetch, hardware);
        assert_eq!(defaults(true).fetch, Fetch::Textures);
        for unset in [None, Some("")] {
            for chosen in [Fetch::Textures, Fetch::Buffers] {
                assert_eq!(fetch_by(unset, chosen, true).unwrap(), chosen);
                assert_eq!(fetch_by(unset, chosen, false).unwrap(), Fetch::Textures);
            }
        }
        for (chosen, fit) in [
            (Fetch::Buffers, true),
            (Fetch::Textures, true),
            (Fetch::Buffers, false),
        ] {
            let by = |v| fetch_by(Some(v), chosen, fit).unwrap();
            assert_eq!(by("textures"), Fetch::Textures);
            assert_eq!(by("buffers"), Fetch::Buffers);
        }
        let e = fetch_by(Some("texture"), Fetch::Buffers, true)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("GPURT_FETCH=texture") && e.contains("textures or buffers"),
            "{e}"
        );
    }

    /// Every kind of kernels goes by its name and back.
    #[test]
    fn kernels_go_by_their_names() {
        for k in Kernels::ALL {
            assert_eq!(Kernels::from_name(k.name()), Some(k));
        }
        assert_eq!(Kernels::from_name("megakernel"), None);
    }
}
