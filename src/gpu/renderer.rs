//! The GPU renderer: a device's layouts and the pipelines compiled so far, and the making
//! of a scene's GPU state for a frame (`upload`), its moving to other frames
//! (`set_frame`) and the compiling and warming up of the pipelines they need. What a
//! frame's dispatches then do is `trace`'s; this module decides which pipeline, which
//! walk of the BVH and which cut. How a renderer is made for its adapter, and the
//! strategy it takes there, is `setup`'s; the settings tests choose in code,
//! `overrides`'.

mod overrides;
mod setup;

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use web_time::Instant;

use super::cut::{Cut, PIXEL_BYTES, Shape};
use super::device::Gpu;
use super::pipeline::{DiskCache, Modules, ResumePipelines, compile};
use super::policy::{cut_for, pooled_for, wavefront_for};
use super::scene::{GpuScene, bind};
use super::shaders::Fetch;
use super::specialization::Specialization;
use super::trace::encode_band;
use super::tuning::Tuning;
use super::upload::{SceneData, check_sizes, scene_bytes, upload_scene};
use super::wavefront::{Wave, WavePipelines, wave_paths};
use crate::counters::gpu_node_bytes;
use crate::gpu_types::{GpuGlobals, GpuTile, TEXTURE_WIDTH};
use crate::pack::SceneBuffers;
use crate::util::error::Result;

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
    /// The work of a dispatch and of a submission on this device (`policy::shape_for`).
    shape: Shape,
    /// Entries of the traversal stack at least, a multiple of 8, whatever the scene's
    /// tree needs (`policy::stack_floor`, `GPURT_STACK`); 0 by default.
    stack_floor: u32,
    /// How this renderer's frames walk the BVH (`GpuGlobals::traversal`).
    traversal: u32,
    /// How its shaders read the scene's nodes, primitives and normals.
    fetch: Fetch,
    /// What `gpurt tune` measured on the adapter, where this renderer took it.
    tuning: Option<Tuning>,
    /// The wavefront kernels' pipelines, shared with the uploaded scenes, where the
    /// adapter binds them (`wave_binds`), and whether colour frames take them where they
    /// can (`policy::wavefront_for`).
    wave: Option<Arc<WavePipelines>>,
    wavefront: bool,
    /// Whether the one kernel's colour frames take its `pooled` entry point where they
    /// can (`policy::pooled_for`).
    pooled: bool,
    /// Whether colour frames trace shadow rays (`Specialization::shadow_rays`).
    shadow_rays: bool,
    /// Rows of a layer of the node and primitive textures (`upload::layer_rows`).
    layer_rows: u32,
    /// Longest a dispatch should take (`DISPATCH_BUDGET`); `None` on software adapters,
    /// which have no watchdog.
    dispatch_budget: Option<Duration>,
    /// The address space each texture of a scene is allocated with, above the process's
    /// size (`GPURT_FAULT=out-of-memory`, `fault::AddressSpaceCap`); `None`: no cap.
    texture_margin: Option<u64>,
}

impl GpuRenderer {
    /// The pipeline a frame of `scene` needs on this renderer.
    fn spec(&self, scene: &SceneBuffers, globals: &GpuGlobals) -> Specialization {
        let spec = Specialization::of(scene, globals);
        Specialization {
            layer_shift: TEXTURE_WIDTH.ilog2() + self.layer_rows.ilog2(),
            pooled: pooled_for(self.pooled, globals),
            shadow_rays: self.shadow_rays,
            stack: spec.stack.max(self.stack_floor),
            ..spec
        }
    }

    /// How this renderer walks the BVH (`TRAVERSAL_*`), where a scene's tree allows
    /// (see `traversal_for`). A CPU render meant to match this renderer's to the node must
    /// use the walk `frame` gives for its scene.
    pub fn traversal(&self) -> u32 {
        self.traversal
    }

    /// The fewest entries of its traversal stack (`GPURT_STACK`; 0: what each tree needs).
    pub fn stack_floor(&self) -> u32 {
        self.stack_floor
    }

    /// `globals` with this renderer's traversal for `scene` (`SceneBuffers::traversal_for`)
    /// and its kernels (`policy::wavefront_for`, where the adapter binds the wavefront
    /// kernels): what its frames of `globals` trace.
    pub fn frame(&self, scene: &SceneBuffers, globals: &GpuGlobals) -> GpuGlobals {
        // The wavefront kernels trace every shadow ray.
        let wave = self.wave.is_some()
            && self.shadow_rays
            && wavefront_for(self.wavefront, scene, globals);
        GpuGlobals {
            traversal: scene.traversal_for(self.traversal),
            wavefront: u32::from(wave),
            ..*globals
        }
    }

    /// The kernels a frame of `scene` as `globals` says traces through on this renderer:
    /// `main`, `pooled` or `wavefront`.
    pub fn kernels(&self, scene: &SceneBuffers, globals: &GpuGlobals) -> &'static str {
        let globals = &self.frame(scene, globals);
        if globals.wavefront != 0 {
            "wavefront"
        } else if self.spec(scene, globals).pooled {
            "pooled"
        } else {
            "main"
        }
    }

    /// Total time spent creating modules and compiling pipelines, first dispatches
    /// included (lavapipe compiles there).
    pub fn compile_time(&self) -> Duration {
        *self.compile_time.lock().expect("not poisoned")
    }

    /// The scene's arrays on the device, laid out for the walk `traversal` as this
    /// renderer's shaders read them (`fetch`, `layer_rows`, `texture_margin`).
    fn upload_scene(&self, gpu: &Gpu, scene: &SceneBuffers, traversal: u32) -> Result<SceneData> {
        let (fetch, rows, margin) = (self.fetch, self.layer_rows, self.texture_margin);
        upload_scene(gpu, scene, traversal, fetch, rows, margin)
    }

    /// How this renderer's shaders read the scene's nodes, primitives and normals.
    pub fn fetch(&self) -> Fetch {
        self.fetch
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
        let gpu = &Gpu::new(device, queue);
        let globals = &self.frame(scene, globals);
        let spec = self.spec(scene, globals);
        if let Some(p) = self.pipelines.lock().expect("not poisoned").get(&spec) {
            return Ok(p.clone());
        }
        let data = self.upload_scene(gpu, scene, globals.traversal)?;
        self.pipeline(gpu, scene, &data, globals)
    }

    /// The pipeline for a scene and render settings, compiled the first time and warmed
    /// up on `data`, the scene's arrays on the device.
    fn pipeline(
        &self,
        gpu: &Gpu,
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
            gpu,
            &self.pipeline_layout,
            &self.modules,
            if spec.pooled { "pooled" } else { "main" },
            spec,
            self.cache.as_ref().map(DiskCache::cache),
        )?;
        self.warm_up(gpu, data, globals, &pipeline)?;
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
        gpu: &Gpu,
        data: &SceneData,
        globals: &GpuGlobals,
        pipeline: &wgpu::ComputePipeline,
    ) -> Result<()> {
        let bound = bind(gpu, &self.layout, data, globals, PIXEL_BYTES, 1)?;
        let tile = GpuTile {
            x: globals.width / 2,
            y: globals.height / 2,
            width: 1,
            height: 1,
            out_stride: 1,
            sample_count: 1,
            ..Default::default()
        };
        gpu.write(&bound.tile_buf, 0, bytemuck::bytes_of(&tile));
        gpu.scoped("compiling the shader", || {
            let mut enc = gpu.encoder();
            encode_band(&mut enc, pipeline, &bound, &[tile]);
            gpu.run(enc);
        })?;
        gpu.wait()
    }

    /// How a frame of `globals` is cut on this device (`policy::cut_for`).
    fn cut(&self, limits: &wgpu::Limits, globals: &GpuGlobals) -> Cut {
        cut_for(
            limits,
            globals,
            &self.shape,
            pooled_for(self.pooled, globals),
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
        let gpu = &Gpu::new(device, queue);
        let limits = gpu.limits();
        let globals = &self.frame(scene, globals);
        let cut = self.cut(&limits, globals);
        check_sizes(
            &limits,
            scene,
            globals.traversal,
            cut.band_bytes(),
            self.fetch,
            self.layer_rows,
        )?;
        scene.check_for_gpu(globals)?;
        let spec = self.spec(scene, globals);
        let data = self.upload_scene(gpu, scene, globals.traversal)?;
        let pipeline = self.pipeline(gpu, scene, &data, globals)?;
        let bound = bind(
            gpu,
            &self.layout,
            &data,
            globals,
            cut.band_bytes(),
            cut.dispatches_per_submission(),
        )?;
        let wave = self.wave_for(gpu, spec, &cut, globals)?;
        // The texture uploads are queued: finish them, so a failure surfaces here.
        gpu.finish()?;
        Ok(GpuScene {
            data,
            bound,
            pipeline,
            cut,
            scene_bytes: scene_bytes(scene, globals.traversal, self.fetch, self.layer_rows),
            resume: self.resume.clone(),
            spec,
            dispatch_budget: self.dispatch_budget,
            finer: Mutex::new(None),
            node_bytes: gpu_node_bytes(globals.traversal),
            wave,
            counted: Mutex::new(None),
            resumed: Default::default(),
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
        let gpu = &Gpu::new(device, queue);
        let limits = gpu.limits();
        let globals = &self.frame(scene, globals);
        scene.check_for_gpu(globals)?;
        let spec = self.spec(scene, globals);
        let spec_changed = spec != uploaded.spec;
        if spec_changed {
            uploaded.pipeline = self.pipeline(gpu, scene, &uploaded.data, globals)?;
            uploaded.spec = spec;
        }
        uploaded.node_bytes = gpu_node_bytes(globals.traversal);
        *uploaded.counted.lock().expect("counts lock") = None;
        let cut = self.cut(&limits, globals);
        let counts_alike = (globals.counters != 0) == uploaded.bound.counting;
        if cut == uploaded.cut && counts_alike {
            gpu.write(&uploaded.bound.globals, 0, bytemuck::bytes_of(globals));
        } else {
            check_sizes(
                &limits,
                scene,
                globals.traversal,
                cut.band_bytes(),
                self.fetch,
                self.layer_rows,
            )?;
            uploaded.bound = bind(
                gpu,
                &self.layout,
                &uploaded.data,
                globals,
                cut.band_bytes(),
                cut.dispatches_per_submission(),
            )?;
            uploaded.cut = cut;
            *uploaded.finer.lock().expect("cut lock") = None;
        }
        let wave_fits = |w: &Wave| w.capacity >= wave_paths(&cut) && w.lights == globals.n_lights;
        if (globals.wavefront != 0) != uploaded.wave.is_some()
            || uploaded
                .wave
                .as_ref()
                .is_some_and(|w| !wave_fits(w) || spec_changed)
        {
            uploaded.wave = self.wave_for(gpu, spec, &cut, globals)?;
        }
        if let Some(w) = uploaded.wave.as_mut() {
            w.depth = globals.max_depth;
        }
        Ok(())
    }

    /// The wave a frame of `globals` (cut as `cut`) runs the wavefront kernels in, when
    /// it takes them: a path for each pixel sample of a tile's pass.
    fn wave_for(
        &self,
        gpu: &Gpu<'_>,
        spec: Specialization,
        cut: &Cut,
        globals: &GpuGlobals,
    ) -> Result<Option<Wave>> {
        (globals.wavefront != 0)
            .then(|| {
                let pipelines = self.wave.as_ref().expect("frames take the kernels it has");
                Wave::new(gpu, pipelines, spec, wave_paths(cut), globals)
            })
            .transpose()
    }

    /// Gets `uploaded` ready for the frame `globals` of `scene`: uploads the scene the
    /// first time (returning true), else moves it to this frame when the frame changed
    /// (`set_frame`). The one way a session of many frames keeps its scene on the device
    /// (`session::GpuSession`, the browser page).
    pub fn ready(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        uploaded: &mut Option<(GpuGlobals, GpuScene)>,
        scene: &SceneBuffers,
        globals: &GpuGlobals,
    ) -> Result<bool> {
        match uploaded {
            Some((current, _)) if current == globals => Ok(false),
            Some((current, up)) => {
                self.set_frame(device, queue, up, scene, globals)?;
                *current = *globals;
                Ok(false)
            }
            None => {
                *uploaded = Some((*globals, self.upload(device, queue, scene, globals)?));
                Ok(true)
            }
        }
    }
}
