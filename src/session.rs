//! One scene, many frames: the `Renderer` trait both backends implement. A renderer holds
//! a packed scene (uploaded once on the GPU) and traces frames against it, in steps if
//! wanted: samples `0..k` and then `k..n` into one `Accumulator` give the image of `0..n`,
//! to the bit on the CPU and within the GPU-vs-CPU limits on the GPU. `docs/api.md` has
//! an example.

use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::error::Result;
use crate::fault::{Fault, OUT_OF_MEMORY_MARGIN};
use crate::film::Accumulator;
use crate::gpu::{self, GpuContext, GpuScene};
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;

/// A backend that traces frames of one packed scene.
pub trait Renderer {
    /// One line naming what renders: the adapter, or the CPU and its threads.
    fn describe(&self) -> String;

    /// The frame this renderer traces when asked for `globals`: the same, but for the
    /// BVH walk, which the GPU picks for its adapter (`GpuRenderer::traversal`). A CPU
    /// render of this frame matches this renderer's node for node.
    fn frame(&self, globals: &GpuGlobals) -> GpuGlobals {
        *globals
    }

    /// Gets ready to render frames like `globals`: the GPU compiles the pipeline such
    /// frames need (once per kind of frame); the CPU has nothing to do. Returns the time
    /// spent compiling, so that callers can report it apart from the frame.
    fn prepare(&mut self, globals: &GpuGlobals) -> Result<Duration>;

    /// Traces samples `samples` of every pixel of the frame `globals` describes (camera,
    /// size, samples per pixel, depth, AOV) and adds them to `accum`, which must hold
    /// samples `0..samples.start` of the same frame. Returns the rays traced, counted
    /// alike by both backends. `progress` gets the pixels finished as they finish;
    /// `cancel` stops the render with `Error::Interrupted`, leaving `accum` as it was.
    fn render(
        &mut self,
        globals: &GpuGlobals,
        samples: Range<u32>,
        accum: &mut Accumulator,
        progress: &(dyn Fn(u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<u64> {
        let rows = 0..globals.height;
        self.render_rows(globals, rows, samples, accum, progress, cancel)
    }

    /// `render` for the image rows `rows` only (one shard of a sharded image): the other
    /// rows of `accum` stay as they are. Each pixel gets the value the whole frame gives it.
    fn render_rows(
        &mut self,
        globals: &GpuGlobals,
        rows: Range<u32>,
        samples: Range<u32>,
        accum: &mut Accumulator,
        progress: &(dyn Fn(u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<u64>;
}

/// The CPU reference renderer, on all cores (rayon).
pub struct CpuRenderer {
    scene: Arc<SceneBuffers>,
}

impl CpuRenderer {
    pub fn new(scene: Arc<SceneBuffers>) -> Self {
        CpuRenderer { scene }
    }
}

impl Renderer for CpuRenderer {
    fn describe(&self) -> String {
        format!("CPU, {} threads", rayon::current_num_threads())
    }

    fn prepare(&mut self, _: &GpuGlobals) -> Result<Duration> {
        Ok(Duration::ZERO)
    }

    fn render_rows(
        &mut self,
        globals: &GpuGlobals,
        rows: Range<u32>,
        samples: Range<u32>,
        accum: &mut Accumulator,
        progress: &(dyn Fn(u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<u64> {
        // The same guard as the GPU's: a frame the fixed-size stacks cannot trace is an
        // error, not a panic.
        self.scene.check(globals)?;
        crate::cpu::render_rows(&self.scene, globals, rows, samples, accum, progress, cancel)
            .map(|c| c.total())
    }
}

/// The GPU renderer on its own device. The scene is uploaded once, on the first frame;
/// a later frame with another camera rewrites only a uniform, one of another size
/// remakes only the output buffers (`GpuRenderer::set_frame`).
pub struct GpuSession {
    ctx: GpuContext,
    renderer: gpu::GpuRenderer,
    scene: Arc<SceneBuffers>,
    uploaded: Option<(GpuGlobals, GpuScene)>,
    uploads: u32,
    /// The fault `GPURT_FAULT` asks for (`fault::Fault`), so that the command line's
    /// handling of a GPU lost mid-render or out of memory on upload can be tested end to
    /// end.
    fault: Option<Fault>,
}

impl GpuSession {
    /// Opens `ctx`'s device for `scene`; shader pipelines are compiled on first use (and
    /// cached on disk where the device allows, keyed by the adapter).
    pub fn new(ctx: GpuContext, scene: Arc<SceneBuffers>) -> Result<Self> {
        let mut renderer = gpu::GpuRenderer::new(&ctx.device, Some(&ctx.info))?;
        let fault = Fault::from_env()?;
        if fault == Some(Fault::OutOfMemory) {
            renderer = renderer.with_texture_margin(OUT_OF_MEMORY_MARGIN);
        }
        Ok(GpuSession {
            ctx,
            renderer,
            scene,
            uploaded: None,
            uploads: 0,
            fault,
        })
    }

    /// Moves the session to another scene (a batch): the next frame uploads it; the
    /// compiled pipelines stay, so scenes of one kind compile once.
    pub fn set_scene(&mut self, scene: Arc<SceneBuffers>) {
        self.uploaded = None;
        self.scene = scene;
    }

    /// How many times a scene's arrays have been uploaded: once per scene, for any number
    /// of frames.
    pub fn scene_uploads(&self) -> u32 {
        self.uploads
    }

    /// Time spent compiling shaders so far.
    pub fn compile_time(&self) -> Duration {
        self.renderer.compile_time()
    }
}

impl Renderer for GpuSession {
    fn describe(&self) -> String {
        self.ctx.describe()
    }

    fn frame(&self, globals: &GpuGlobals) -> GpuGlobals {
        self.renderer.frame(&self.scene, globals)
    }

    /// Uploads the scene (the first time) or moves it to this frame, compiling the frame's
    /// pipeline on it: the warm-up traces a pixel of the real scene.
    fn prepare(&mut self, globals: &GpuGlobals) -> Result<Duration> {
        let before = self.renderer.compile_time();
        self.set_frame(globals)?;
        Ok(self.renderer.compile_time() - before)
    }

    fn render_rows(
        &mut self,
        globals: &GpuGlobals,
        rows: Range<u32>,
        samples: Range<u32>,
        accum: &mut Accumulator,
        progress: &(dyn Fn(u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<u64> {
        self.set_frame(globals)?;
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let (_, uploaded) = self.uploaded.as_ref().expect("uploaded by set_frame");
        let lose_device = self.fault == Some(Fault::LoseDevice);
        let progress = |pixels| {
            progress(pixels);
            if lose_device {
                device.destroy();
            }
        };
        gpu::trace_rows(
            device, queue, uploaded, rows, samples, accum, &progress, cancel,
        )
    }
}

impl GpuSession {
    /// Gets the uploaded scene ready for the frame `globals`, uploading it the first time.
    fn set_frame(&mut self, globals: &GpuGlobals) -> Result<()> {
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        match &mut self.uploaded {
            Some((current, _)) if current == globals => {}
            Some((current, uploaded)) => {
                self.renderer
                    .set_frame(device, queue, uploaded, &self.scene, globals)?;
                *current = *globals;
            }
            None => {
                let uploaded = self.renderer.upload(device, queue, &self.scene, globals)?;
                self.uploads += 1;
                self.uploaded = Some((*globals, uploaded));
            }
        }
        Ok(())
    }
}
