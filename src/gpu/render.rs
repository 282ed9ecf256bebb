//! Upload, tiled dispatch and readback.
//!
//! A frame is cut (`Cut`) into tiles, one bounded dispatch each, so that no dispatch runs
//! long enough to trip a driver watchdog, and the tiles into bands of rows, one submission
//! and one readback each, so that the host does not wait on the GPU per tile. On a GPU,
//! bands whose dispatches took longer than `DISPATCH_BUDGET` make the rest cut finer.
//! Pixels whose work does not fit one invocation are finished by `resume`.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::cut::{Cut, PIXEL_BYTES};
use super::device::{read_mapped, scoped, wait};
use super::pipeline::{
    DiskCache, Modules, ResumePipelines, bind_group_layout, compile, pipeline_layouts,
    resume_group_layout,
};
use super::resume::resume;
use super::scene::{Bound, GpuScene, bind};
use super::specialization::Specialization;
use super::upload::{self, SceneData, check_sizes, scene_bytes, upload_scene};
use crate::error::{Error, Result};
use crate::film::{Accumulator, Film};
use crate::gpu_types::{
    GpuGlobals, GpuTile, PIXEL_CUT_SHORT, TEXTURE_WIDTH, TRAVERSAL_NAMES, TRAVERSAL_WIDE,
};
use crate::pack::SceneBuffers;

/// The shader with its bind group layout, and the pipelines compiled from it so far, one
/// per `Specialization`. Reusable across renders (and threads) on one device.
pub struct GpuRenderer {
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// The `resume` entry point's layouts and pipelines, shared with the uploaded scenes.
    resume: Arc<ResumePipelines>,
    modules: Arc<Modules>,
    cache: Option<DiskCache>,
    pipelines: Mutex<HashMap<Specialization, wgpu::ComputePipeline>>,
    compile_time: Mutex<Duration>,
    /// The device is a CPU (lavapipe): bands are kept small.
    software: bool,
    /// How this renderer's frames walk the BVH (`GpuGlobals::traversal`).
    traversal: u32,
    /// Rows of a layer of the node and primitive textures (`upload::layer_rows`).
    layer_rows: u32,
    /// Longest a dispatch should take (`DISPATCH_BUDGET`); `None` on software adapters,
    /// which have no watchdog.
    dispatch_budget: Option<Duration>,
    /// The address space each texture of a scene is allocated with, above the process's
    /// size (`GPURT_FAULT=out-of-memory`, `fault::AddressSpaceCap`); `None`: no cap.
    texture_margin: Option<u64>,
}

/// Time one dispatch may take on a GPU, an eighth of the shortest common driver watchdog
/// (Windows' two seconds): the mean dispatch of a band is what is measured, and one tile
/// may take several times the mean. A band whose dispatches took longer on average makes
/// the rest of the frame, and the frames after it, cut finer (`Cut::finer`), to half the
/// budget.
pub const DISPATCH_BUDGET: Duration = Duration::from_millis(250);

/// The traversal for an adapter: `TRAVERSAL_WIDE` on every adapter (each scene falls back
/// to pairs where its wide tree does not fit the stack). On the H100 a ray's time goes to
/// waiting on node fetches, and the four-wide tree halves the chain of them: 1.2 to 1.5
/// times faster than pairs, which was 1.2 to 1.4 times faster than single. On lavapipe it
/// is 2 to 19% faster than single (docs/gpu.md has the figures). `GPURT_TRAVERSAL`
/// (`single`, `pairs` or `wide`: `TRAVERSAL_NAMES`) overrides it, for measuring them on
/// one adapter.
fn traversal_for() -> Result<u32> {
    match std::env::var("GPURT_TRAVERSAL").as_deref() {
        Err(_) | Ok("") => Ok(TRAVERSAL_WIDE),
        Ok(v) => match TRAVERSAL_NAMES.iter().position(|&n| n == v) {
            Some(t) => Ok(t as u32),
            None => Err(Error::Render(format!(
                "GPURT_TRAVERSAL={v}: expected one of {}",
                TRAVERSAL_NAMES.join(", ")
            ))),
        },
    }
}

impl GpuRenderer {
    /// Sets up the layouts. Shader modules and pipelines are made on first use by `render` (or
    /// `prepare`). `adapter_info` keys the on-disk pipeline cache, used when the device has
    /// `PIPELINE_CACHE` (pass `None` to skip the cache).
    pub fn new(device: &wgpu::Device, adapter_info: Option<&wgpu::AdapterInfo>) -> Result<Self> {
        let start = Instant::now();
        let software = device.adapter_info().device_type == wgpu::DeviceType::Cpu;
        let cache_file = DiskCache::file(device, adapter_info);
        let layout = bind_group_layout(device);
        let resume_layout = resume_group_layout(device);
        let (pipeline_layout, resume_pipeline_layout, cache) =
            scoped(device, "compiling the shader", || {
                let (main, resume) = pipeline_layouts(device, &layout, &resume_layout);
                (
                    main,
                    resume,
                    cache_file.map(|file| DiskCache::open(device, file)),
                )
            })?;
        let modules = Arc::new(Modules::default());
        Ok(GpuRenderer {
            resume: Arc::new(ResumePipelines {
                layout: resume_layout,
                pipeline_layout: resume_pipeline_layout,
                modules: modules.clone(),
                compiled: Mutex::new(HashMap::new()),
            }),
            layout,
            pipeline_layout,
            modules,
            cache,
            pipelines: Mutex::new(HashMap::new()),
            compile_time: Mutex::new(start.elapsed()),
            software,
            traversal: traversal_for()?,
            layer_rows: upload::layer_rows(device),
            dispatch_budget: (!software).then_some(DISPATCH_BUDGET),
            texture_margin: None,
        })
    }

    /// This renderer splitting the node and primitive textures into layers of `rows`
    /// rows (a power of two, at most the device's), as a scene too large for one layer
    /// is split: lets the tests check many layers on small scenes.
    pub fn with_layer_rows(self, rows: u32) -> Self {
        assert!(rows.is_power_of_two() && rows <= self.layer_rows);
        GpuRenderer {
            layer_rows: rows,
            ..self
        }
    }

    /// This renderer allocating each texture of a scene with the process's address space
    /// capped `margin` bytes above its size (the out-of-memory fault, `fault.rs`): on a
    /// software adapter, whose device memory is the process's own, a texture larger than
    /// that cannot be allocated. Only the allocations run capped, not the copies into
    /// them, which lavapipe compiles code for.
    pub fn with_texture_margin(self, margin: u64) -> Self {
        GpuRenderer {
            texture_margin: Some(margin),
            ..self
        }
    }

    /// This renderer holding each dispatch to `budget` (instead of `DISPATCH_BUDGET` on
    /// GPUs and none on software adapters): lets the tests make lavapipe refine its cut.
    pub fn with_dispatch_budget(self, budget: Duration) -> Self {
        GpuRenderer {
            dispatch_budget: Some(budget),
            ..self
        }
    }

    /// The pipeline a frame of `scene` needs on this renderer.
    fn spec(&self, scene: &SceneBuffers, globals: &GpuGlobals) -> Specialization {
        Specialization {
            layer_shift: TEXTURE_WIDTH.ilog2() + self.layer_rows.ilog2(),
            ..Specialization::of(scene, globals)
        }
    }

    /// How this renderer walks the BVH (`TRAVERSAL_*`), where a scene's tree allows
    /// (see `traversal_for`). A CPU render meant to match this renderer's to the node must
    /// use the walk `frame` gives for its scene.
    pub fn traversal(&self) -> u32 {
        self.traversal
    }

    /// This renderer walking the BVH as `traversal` says, whatever its adapter.
    pub fn with_traversal(self, traversal: u32) -> Self {
        GpuRenderer { traversal, ..self }
    }

    /// `globals` with this renderer's traversal for `scene` (`SceneBuffers::traversal_for`):
    /// what its frames of `globals` trace.
    pub fn frame(&self, scene: &SceneBuffers, globals: &GpuGlobals) -> GpuGlobals {
        GpuGlobals {
            traversal: scene.traversal_for(self.traversal),
            ..*globals
        }
    }

    /// Total time spent creating modules and compiling pipelines, first dispatches
    /// included (lavapipe compiles there).
    pub fn compile_time(&self) -> Duration {
        *self.compile_time.lock().expect("not poisoned")
    }

    /// The scene's arrays on the device, laid out for the walk `traversal` as this
    /// renderer's textures are (`layer_rows`, `texture_margin`).
    fn upload_scene(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        traversal: u32,
    ) -> Result<SceneData> {
        upload_scene(
            device,
            queue,
            scene,
            traversal,
            self.layer_rows,
            self.texture_margin,
        )
    }

    /// Compiles (once) the pipeline for a scene and render settings. The first time, the
    /// scene is uploaded for the warm-up and let go; `upload` and `set_frame` compile on
    /// the scene they already hold instead.
    pub fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        globals: &GpuGlobals,
    ) -> Result<wgpu::ComputePipeline> {
        let globals = &self.frame(scene, globals);
        let spec = self.spec(scene, globals);
        if let Some(p) = self.pipelines.lock().expect("not poisoned").get(&spec) {
            return Ok(p.clone());
        }
        let data = self.upload_scene(device, queue, scene, globals.traversal)?;
        self.pipeline(device, queue, scene, &data, globals)
    }

    /// The pipeline for a scene and render settings, compiled the first time and warmed
    /// up on `data`, the scene's arrays on the device.
    fn pipeline(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        data: &SceneData,
        globals: &GpuGlobals,
    ) -> Result<wgpu::ComputePipeline> {
        let spec = self.spec(scene, globals);
        let mut pipelines = self.pipelines.lock().expect("not poisoned");
        if let Some(p) = pipelines.get(&spec) {
            return Ok(p.clone());
        }
        let start = Instant::now();
        let pipeline = compile(
            device,
            &self.pipeline_layout,
            &self.modules,
            "main",
            spec,
            self.cache.as_ref().map(DiskCache::cache),
        )?;
        self.warm_up(device, queue, data, globals, &pipeline)?;
        if let Some(cache) = &self.cache {
            cache.save();
        }
        *self.compile_time.lock().expect("not poisoned") += start.elapsed();
        pipelines.insert(spec, pipeline.clone());
        Ok(pipeline)
    }

    /// Traces the centre pixel of the frame `globals` once, one sample, on the scene's
    /// arrays `data`, so that drivers that compile at the first dispatch (lavapipe)
    /// compile now and the compile time is the whole cost of getting a pipeline ready.
    /// A real pixel with the frame's own constants compiles exactly what the frame's
    /// dispatches will run, whatever the driver specialises on.
    fn warm_up(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        data: &SceneData,
        globals: &GpuGlobals,
        pipeline: &wgpu::ComputePipeline,
    ) -> Result<()> {
        let bound = bind(device, &self.layout, data, globals, PIXEL_BYTES, 1)?;
        let tile = GpuTile {
            x: globals.width / 2,
            y: globals.height / 2,
            width: 1,
            height: 1,
            out_stride: 1,
            sample_count: 1,
            ..Default::default()
        };
        queue.write_buffer(&bound.tile_buf, 0, bytemuck::bytes_of(&tile));
        scoped(device, "compiling the shader", || {
            let mut enc = device.create_command_encoder(&Default::default());
            encode_band(&mut enc, pipeline, &bound, &[tile]);
            queue.submit([enc.finish()]);
        })?;
        wait(device)?;
        Ok(())
    }

    /// How a frame of `globals`' size and samples is cut on this device. Software
    /// adapters get small bands so that Ctrl-C and the progress bar respond within a
    /// second, and one sample per pass: lavapipe ends every loop once an invocation has run
    /// 65535 loop iterations in all, and one sample of an ordinary scene needs far fewer.
    /// GPUs take up to 16 samples per pass, and a band is the most one submission should
    /// hold.
    fn cut(&self, device: &wgpu::Device, globals: &GpuGlobals) -> Cut {
        let limits = device.limits();
        let (pass_samples, band_samples) = if self.software {
            (1, 1 << 18)
        } else {
            (16, 1 << 26)
        };
        Cut::new(
            globals.width,
            globals.height,
            globals.spp,
            pass_samples,
            band_samples,
            limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size),
            // Software adapters split a dispatch among their threads in fixed runs; a
            // GPU's own scheduler balances, and neighbouring blocks share its caches.
            self.software,
        )
    }

    /// Uploads a scene for the frame described by `globals` and gets its pipeline ready.
    /// The result can be traced any number of times (`trace`), each time giving the same
    /// image, and moved to other frames of the same scene with `set_frame`.
    pub fn upload(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        globals: &GpuGlobals,
    ) -> Result<GpuScene> {
        let globals = &self.frame(scene, globals);
        let cut = self.cut(device, globals);
        check_sizes(
            device,
            scene,
            globals.traversal,
            cut.band_bytes(),
            self.layer_rows,
        )?;
        scene.check(globals)?;
        let spec = self.spec(scene, globals);
        let data = self.upload_scene(device, queue, scene, globals.traversal)?;
        let pipeline = self.pipeline(device, queue, scene, &data, globals)?;
        let bound = bind(
            device,
            &self.layout,
            &data,
            globals,
            cut.band_bytes(),
            cut.dispatches_per_submission(),
        )?;
        // The texture uploads are queued: finish them, so a failure surfaces here.
        queue.submit([]);
        wait(device)?;
        Ok(GpuScene {
            data,
            bound,
            pipeline,
            cut,
            scene_bytes: scene_bytes(scene, globals.traversal, self.layer_rows),
            resume: self.resume.clone(),
            spec,
            dispatch_budget: self.dispatch_budget,
            finer: Mutex::new(None),
        })
    }

    /// Moves an uploaded scene to another frame of it (camera, size, samples, depth,
    /// AOV): the scene's arrays stay where they are. A frame of the same size and
    /// samples per pixel rewrites only the constants' buffer; another size remakes the
    /// band's output buffers and the bind group; other settings may pick another
    /// pipeline (compiled once).
    pub fn set_frame(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        uploaded: &mut GpuScene,
        scene: &SceneBuffers,
        globals: &GpuGlobals,
    ) -> Result<()> {
        let globals = &self.frame(scene, globals);
        scene.check(globals)?;
        let spec = self.spec(scene, globals);
        if spec != uploaded.spec {
            uploaded.pipeline = self.pipeline(device, queue, scene, &uploaded.data, globals)?;
            uploaded.spec = spec;
        }
        let cut = self.cut(device, globals);
        if cut == uploaded.cut {
            queue.write_buffer(&uploaded.bound.globals, 0, bytemuck::bytes_of(globals));
        } else {
            check_sizes(
                device,
                scene,
                globals.traversal,
                cut.band_bytes(),
                self.layer_rows,
            )?;
            uploaded.bound = bind(
                device,
                &self.layout,
                &uploaded.data,
                globals,
                cut.band_bytes(),
                cut.dispatches_per_submission(),
            )?;
            uploaded.cut = cut;
            *uploaded.finer.lock().expect("cut lock") = None;
        }
        Ok(())
    }

    /// Renders the image described by `globals` on `device`. Returns the film and the
    /// number of rays traced.
    pub fn render(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        globals: &GpuGlobals,
        progress: &dyn Fn(u64),
        cancel: &AtomicBool,
    ) -> Result<(Film, u64)> {
        let uploaded = self.upload(device, queue, scene, globals)?;
        trace(device, queue, &uploaded, progress, cancel)
    }
}

/// Traces an uploaded scene's image. Returns the film and the number of rays traced.
pub fn trace(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<(Film, u64)> {
    let mut accum = Accumulator::new(scene.cut.width, scene.cut.height);
    let rays = trace_samples(
        device,
        queue,
        scene,
        0..scene.cut.spp,
        &mut accum,
        progress,
        cancel,
    )?;
    Ok((accum.into_film(), rays))
}

/// Traces samples `samples` of every pixel of an uploaded scene and adds them to
/// `accum`, which must hold samples `0..samples.start` of the same frame (progressive
/// rendering). Returns the rays traced.
pub fn trace_samples(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<u64> {
    let rows = 0..scene.cut.height;
    trace_rows(device, queue, scene, rows, samples, accum, progress, cancel)
}

/// `trace_samples` for the image rows `rows` only (a shard of the image): the other
/// rows of `accum` stay as they are.
#[allow(clippy::too_many_arguments)]
pub fn trace_rows(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    rows: Range<u32>,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<u64> {
    let cut = scene.cut;
    accum.check(cut.width, cut.height, cut.spp, &samples)?;
    let (mut rays, mut cut_short) = (0u64, 0u64);
    // Pixels whose work did not fit one invocation, finished by `resume`.
    let mut unfinished = Vec::new();
    // The bands, clipped to `rows`.
    let bands = cut.bands().filter_map(|(y0, n)| {
        let (lo, hi) = (y0.max(rows.start), (y0 + n).min(rows.end));
        (lo < hi).then(|| (lo, hi - lo))
    });
    let mut tracing = scene.tracing_cut();
    let all = u64::from(samples.end - samples.start).max(1);
    for (y0, rows) in bands {
        let pixels = u64::from(cut.width) * u64::from(rows);
        let bytes = pixels * PIXEL_BYTES;
        // Progress is in pixels: a submission of part of the samples reports its share.
        let mut reported = 0;
        for run in cut.submissions(&samples) {
            if cancel.load(Ordering::Relaxed) {
                return Err(Error::Interrupted);
            }
            let last = run.end == samples.end;
            let start = Instant::now();
            let dispatches = scoped(device, "tracing a band", || {
                let first = run.start == samples.start;
                let (mut enc, dispatches) =
                    submit_band(device, queue, scene, &tracing, y0, rows, &run, first);
                if last {
                    let (output, readback) = (&scene.bound.output, &scene.bound.readback);
                    enc.copy_buffer_to_buffer(output, 0, readback, 0, bytes);
                }
                queue.submit([enc.finish()]);
                dispatches
            })?;
            if last {
                let (band_rays, band_cut) =
                    read_band(device, &scene.bound.readback, bytes, y0, &mut accum.sums)?;
                rays += band_rays;
                unfinished.extend(band_cut);
            } else {
                // One submission at a time, so that Ctrl-C is seen within one.
                wait(device)?;
            }
            if let Some(budget) = scene.dispatch_budget {
                // The time includes the band's readback after its last submission: the
                // mean dispatch is overestimated, on the safe side.
                let mean = start.elapsed().as_secs_f64() / f64::from(dispatches.max(1));
                if mean > budget.as_secs_f64() {
                    tracing = tracing.finer(2.0 * mean / budget.as_secs_f64());
                    *scene.finer.lock().expect("cut lock") = Some(tracing);
                }
            }
            let done = pixels * u64::from(run.end - samples.start) / all;
            progress(done - reported);
            reported = done;
        }
    }
    if !unfinished.is_empty() {
        let (more_rays, cut) = resume(
            device,
            queue,
            scene,
            &unfinished,
            &samples,
            &mut accum.sums,
            cancel,
        )?;
        rays += more_rays;
        cut_short += cut;
    }
    if cut_short > 0 {
        return Err(Error::Gpu(format!(
            "{cut_short} of {} pixels could not finish on {}: the driver ended a shader loop \
             before its end (lavapipe stops every loop once one invocation has run 65535 \
             loop iterations, and a single ray of these pixels needs more, crossing too \
             many surfaces); render with --backend cpu",
            u64::from(cut.width) * u64::from(cut.height),
            device.adapter_info().name
        )));
    }
    accum.samples = samples.end;
    Ok(rays)
}

/// Traces an uploaded scene's image and waits for the GPU, reading nothing back: the
/// GPU's own time for a frame, as a viewer that displays on the device would see it.
pub fn trace_on_device(device: &wgpu::Device, queue: &wgpu::Queue, scene: &GpuScene) -> Result<()> {
    let cut = scene.tracing_cut();
    for (y0, rows) in cut.bands() {
        for run in cut.submissions(&(0..cut.spp)) {
            scoped(device, "tracing a band", || {
                let first = run.start == 0;
                let (enc, _) = submit_band(device, queue, scene, &cut, y0, rows, &run, first);
                queue.submit([enc.finish()]);
            })?;
        }
    }
    wait(device)
}

/// Writes the tiles of the band at row `y0` for `samples` as `cut` cuts it and encodes
/// their dispatches, after the clearing of the band's output when `clear` (the first
/// samples of the band: each pass adds to what the passes before left). A finer cut than
/// the one the tile buffer was made for has more tiles than slots: all but the last
/// buffer-full are submitted here. Returns the encoder of the last, and the dispatches.
#[allow(clippy::too_many_arguments)]
fn submit_band(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    cut: &Cut,
    y0: u32,
    rows: u32,
    samples: &Range<u32>,
    clear: bool,
) -> (wgpu::CommandEncoder, u32) {
    let tiles = cut.tiles(y0, rows, samples);
    let stride = scene.bound.tile_stride as usize;
    let band_bytes = u64::from(cut.width) * u64::from(rows) * PIXEL_BYTES;
    let mut enc = device.create_command_encoder(&Default::default());
    if clear {
        enc.clear_buffer(&scene.bound.output, 0, Some(band_bytes));
    }
    // `tile_buf` holds the dispatches of a submission of the frame's own cut (`bind`).
    let slots = scene.cut.dispatches_per_submission().max(1) as usize;
    let mut groups = tiles.chunks(slots).peekable();
    while let Some(group) = groups.next() {
        let mut bytes = vec![0u8; group.len() * stride];
        for (chunk, tile) in bytes.chunks_mut(stride).zip(group) {
            chunk[..size_of::<GpuTile>()].copy_from_slice(bytemuck::bytes_of(tile));
        }
        // Queue order: this write lands after the submissions before it have run.
        queue.write_buffer(&scene.bound.tile_buf, 0, &bytes);
        encode_band(&mut enc, &scene.pipeline, &scene.bound, group);
        if groups.peek().is_some() {
            queue.submit([enc.finish()]);
            enc = device.create_command_encoder(&Default::default());
        }
    }
    (enc, tiles.len() as u32)
}

/// Encodes one compute pass with a dispatch per tile, each tile read from its slot of the
/// tile buffer (written beforehand, in the same order).
fn encode_band(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    bound: &Bound,
    tiles: &[GpuTile],
) {
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        for (i, tile) in tiles.iter().enumerate() {
            pass.set_bind_group(0, &bound.bind_group, &[i as u32 * bound.tile_stride]);
            let groups = tile.workgroups();
            pass.dispatch_workgroups(groups[0], groups[1], 1);
        }
    }
}

/// Maps the readback buffer and adds the band's sums (full rows from `y0`) to `sums`;
/// returns its ray count and the pixels (x | y << 16) whose work was cut short, which are
/// left to `resume` (neither their sums nor their rays are counted).
fn read_band(
    device: &wgpu::Device,
    readback: &wgpu::Buffer,
    bytes: u64,
    y0: u32,
    sums: &mut Film,
) -> Result<(u64, Vec<u32>)> {
    let width = sums.width as usize;
    // In parallel: a 4K band is 133 MB, and one core takes longer to add it up than the
    // GPU took to trace it.
    const CHUNK: usize = 1 << 14;
    read_mapped(device, readback, bytes, |view| {
        let px: &[[u32; 4]] = bytemuck::cast_slice(view);
        let start = y0 as usize * width;
        sums.pixels[start..start + px.len()]
            .par_chunks_mut(CHUNK)
            .zip(px.par_chunks(CHUNK))
            .enumerate()
            .map(|(k, (out, px))| {
                let (mut rays, mut cut) = (0u64, Vec::new());
                for (i, (out, p)) in out.iter_mut().zip(px).enumerate() {
                    if p[3] & PIXEL_CUT_SHORT != 0 {
                        let j = start + k * CHUNK + i;
                        cut.push((j % width) as u32 | ((j / width) as u32) << 16);
                    } else {
                        for c in 0..3 {
                            out[c] += f32::from_bits(p[c]);
                        }
                        rays += u64::from(p[3]);
                    }
                }
                (rays, cut)
            })
            .reduce(
                || (0, Vec::new()),
                |(rays, mut cut), (more, more_cut)| {
                    cut.extend(more_cut);
                    (rays + more, cut)
                },
            )
    })
}

/// Convenience for one render: compiles the pipeline (no disk cache) and renders.
pub fn render_gpu(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
    globals: &GpuGlobals,
) -> Result<(Film, u64)> {
    let r = GpuRenderer::new(device, None)?;
    r.render(
        device,
        queue,
        scene,
        globals,
        &|_| {},
        &AtomicBool::new(false),
    )
}
