//! One scene, many frames: the `Renderer` trait both backends implement. A renderer holds
//! a packed scene (uploaded once on the GPU) and traces frames against it, in steps if
//! wanted: samples `0..k` and then `k..n` into one `Accumulator` give the image of `0..n`,
//! to the bit on the CPU and within the GPU-vs-CPU limits on the GPU. `docs/api.md` has
//! an example.
//!
//! Which of the two traces is chosen here too, once for every command (`Backend`,
//! `choose`, and `Probe`, which runs the choice while the scene is read).

use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::thread::JoinHandle;
use std::time::Duration;

use crate::bvh::wide::WideNode;
use crate::counters::{self, Counters};
use crate::cpu::RayCounts;
use crate::film::Accumulator;
use crate::gpu::{self, GpuContext, GpuScene};
use crate::gpu_types::{AOV_COST, GpuGlobals};
use crate::pack::SceneBuffers;
use crate::util::error::{Error, Result};
use crate::util::fault::{Fault, OUT_OF_MEMORY_MARGIN};

/// A backend that traces frames of one packed scene.
pub trait Renderer {
    /// One line naming what renders: the adapter, or the CPU and its threads.
    fn describe(&self) -> String;

    /// One line on how it traces, where that was chosen for the adapter: the GPU's walk,
    /// kernels and fetch, and whether `gpurt tune` chose them (`--stats`).
    fn strategy(&self) -> Option<String> {
        None
    }

    /// The frame this renderer traces when asked for `globals`: the same, but for the
    /// BVH walk, which the GPU picks for its adapter (`GpuRenderer::traversal`). A CPU
    /// render of this frame matches this renderer's node for node.
    fn frame(&self, globals: &GpuGlobals) -> GpuGlobals {
        *globals
    }

    /// Moves the renderer to another scene (a batch's next, an animation's next frame):
    /// the GPU uploads it with the next frame and keeps its compiled pipelines, so scenes
    /// of one kind compile once (unless the scene is too large for the renderer's way of
    /// reading it: `GpuRenderer::suits`).
    fn set_scene(&mut self, scene: Arc<SceneBuffers>);

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

    /// What the last `render` or `render_rows` counted, when its frame asked for counts
    /// (`GpuGlobals::counters`): rays and BVH node fetches by kind of ray, on this
    /// renderer's own walk.
    fn counters(&self) -> Option<Counters> {
        None
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

    /// The rays of the last `render` or `render_rows` by kind, and how many of each went in
    /// packets, where this renderer counts them so (the CPU; the GPU counts one total).
    fn ray_kinds(&self) -> Option<RayCounts> {
        None
    }
}

/// The CPU reference renderer, on all cores (rayon).
pub struct CpuRenderer {
    scene: Arc<SceneBuffers>,
    /// The last frame's rays (`ray_kinds`).
    counts: Option<RayCounts>,
    /// The last frame's counters, when it asked for them (`counters`).
    counted: Option<Counters>,
}

impl CpuRenderer {
    pub fn new(scene: Arc<SceneBuffers>) -> Self {
        CpuRenderer {
            scene,
            counts: None,
            counted: None,
        }
    }
}

impl Renderer for CpuRenderer {
    fn describe(&self) -> String {
        let packets = match crate::cpu::fast::packet::Kernels::from_env() {
            Ok(Some(k)) => format!("packets of {} rays ({})", k.lanes(), k.isa().name()),
            Ok(None) => "no packets".to_string(),
            Err(e) => e.to_string(),
        };
        format!("CPU, {} threads, {packets}", rayon::current_num_threads())
    }

    fn set_scene(&mut self, scene: Arc<SceneBuffers>) {
        self.scene = scene;
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
        let counts =
            crate::cpu::render_rows(&self.scene, globals, rows, samples, accum, progress, cancel)?;
        // The CPU walks its own eight-wide tree, but for the cost AOV (`Bindings::new`).
        let node_bytes = match globals.aov {
            AOV_COST => counters::gpu_node_bytes(globals.traversal),
            _ => size_of::<WideNode>() as u64,
        };
        self.counted = (globals.counters != 0).then(|| counts.counters(node_bytes));
        self.counts = Some(counts);
        Ok(counts.total())
    }

    fn counters(&self) -> Option<Counters> {
        self.counted
    }

    fn ray_kinds(&self) -> Option<RayCounts> {
        self.counts
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
        let fault = Fault::from_env()?;
        let renderer = renderer_for(&ctx, &scene, fault)?;
        Ok(GpuSession {
            ctx,
            renderer,
            scene,
            uploaded: None,
            uploads: 0,
            fault,
        })
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

    fn strategy(&self) -> Option<String> {
        Some(self.renderer.describe_strategy())
    }

    fn frame(&self, globals: &GpuGlobals) -> GpuGlobals {
        self.renderer.frame(&self.scene, globals)
    }

    fn set_scene(&mut self, scene: Arc<SceneBuffers>) {
        self.uploaded = None;
        self.scene = scene;
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
                gpu::device::Device::new(device).lose();
            }
        };
        gpu::trace_rows(
            device, queue, uploaded, rows, samples, accum, &progress, cancel,
        )
    }

    fn counters(&self) -> Option<Counters> {
        self.uploaded.as_ref().and_then(|(_, u)| u.counters())
    }
}

impl GpuSession {
    /// Gets the uploaded scene ready for the frame `globals`, uploading it the first time.
    fn set_frame(&mut self, globals: &GpuGlobals) -> Result<()> {
        if self.uploaded.is_none() && !self.renderer.suits(&self.ctx.device, &self.scene) {
            self.renderer = renderer_for(&self.ctx, &self.scene, self.fault)?;
        }
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let slot = &mut self.uploaded;
        if self
            .renderer
            .ready(device, queue, slot, &self.scene, globals)?
        {
            self.uploads += 1;
        }
        Ok(())
    }
}

/// The renderer for frames of `scene` on `ctx`'s device (`GpuRenderer::for_scene`), its
/// uploads under the out-of-memory fault's cap where `fault` asks for it.
fn renderer_for(
    ctx: &GpuContext,
    scene: &SceneBuffers,
    fault: Option<Fault>,
) -> Result<gpu::GpuRenderer> {
    let renderer = gpu::GpuRenderer::for_scene(&ctx.device, Some(&ctx.info), scene)?;
    Ok(match fault {
        Some(Fault::OutOfMemory) => renderer.with_texture_margin(OUT_OF_MEMORY_MARGIN),
        _ => renderer,
    })
}

/// Which renderer traces a command's rays (`--backend`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The GPU when there is a hardware adapter (or the one named), else the CPU, which is
    /// faster than a software rasteriser such as lavapipe on the same cores (`gpu::choose`).
    Auto,
    /// WGSL compute through wgpu, on any adapter, software ones included.
    Gpu,
    /// The CPU reference renderer.
    Cpu,
    /// Both, the GPU's image compared with the CPU's (a command that traces once traces
    /// on the GPU).
    Both,
}

impl Backend {
    /// Every backend, in the order `--help` lists them.
    pub const ALL: [Backend; 4] = [Backend::Auto, Backend::Gpu, Backend::Cpu, Backend::Both];

    /// The name `--backend` takes.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
            Backend::Both => "both",
        }
    }

    /// The backend called `name`.
    pub fn from_name(name: &str) -> Option<Backend> {
        Backend::ALL.into_iter().find(|b| b.name() == name)
    }
}

/// What `Backend::Gpu` does when no adapter exists and none was asked for by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Missing {
    /// Renders on the CPU, with a warning: a render, a batch or a shard gets its image.
    Cpu,
    /// Fails: `bench` times the backends it is told to, and the viewer's window needs an
    /// adapter anyway.
    Error,
}

/// What the adapter search found for a backend: the device to render on, if any, and a
/// line about the choice.
pub struct Found {
    pub gpu: Option<GpuContext>,
    pub note: Option<Note>,
}

/// A line about the choice of backend: the command line prints it always when it is a
/// warning, else with `-v` or `--stats`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Note {
    pub text: String,
    pub warning: bool,
}

/// Whether an adapter was asked for by name (`--adapter` or `GPURT_ADAPTER`).
fn adapter_named(adapter: Option<&str>) -> bool {
    adapter.is_some() || std::env::var("GPURT_ADAPTER").is_ok_and(|v| !v.is_empty())
}

/// The one choice between the GPU and the CPU: opens the device `backend` renders on,
/// on the adapter whose name contains `adapter` (else `GPURT_ADAPTER`'s) when one is
/// named. `Cpu` opens none; `Both` needs an adapter; `Gpu` too, but for `missing`;
/// `Auto` takes a hardware adapter or the one named, else the CPU (`gpu::choose`), and
/// says which and why in the note.
pub fn choose(backend: Backend, adapter: Option<&str>, missing: Missing) -> Result<Found> {
    let named = adapter_named(adapter);
    let (gpu, note) = match backend {
        Backend::Cpu => (None, None),
        Backend::Both => (Some(gpu::open(adapter)?), None),
        Backend::Gpu => match gpu::open(adapter) {
            Ok(ctx) => (Some(ctx), None),
            // An adapter asked for by name that is missing is an error, not a fallback.
            Err(Error::NoAdapter(why)) if !named && missing == Missing::Cpu => (
                None,
                Some(Note {
                    text: format!("gpurt: no GPU adapter{why}; rendering on the CPU"),
                    warning: true,
                }),
            ),
            Err(e) => return Err(e),
        },
        Backend::Auto => match gpu::choose(adapter)? {
            gpu::Choice::Gpu(ctx) => {
                let ctx = *ctx;
                let why = if named {
                    "the adapter named"
                } else {
                    "a hardware adapter"
                };
                let text = format!("backend     gpu: {why}");
                (
                    Some(ctx),
                    Some(Note {
                        text,
                        warning: false,
                    }),
                )
            }
            gpu::Choice::Cpu(why) => (
                None,
                Some(Note {
                    text: format!("backend     cpu: {why} (--backend gpu forces the GPU path)"),
                    warning: false,
                }),
            ),
        },
    };
    Ok(Found { gpu, note })
}

/// `choose` on a thread of its own: looking for an adapter (and opening its device) takes
/// 50 ms or more, so it runs while the scene is read and its BVH built. Dropped without
/// `join` (the scene failed to read), it still waits for the search to end: a process
/// that exits while another thread is inside the Vulkan driver's start-up can die in the
/// driver (NVIDIA's did: a bad `--view` file exited on a signal instead of with status 2).
pub struct Probe(Option<JoinHandle<Result<Found>>>);

impl Probe {
    /// Starts `choose(backend, adapter, missing)`.
    pub fn start(backend: Backend, adapter: Option<String>, missing: Missing) -> Probe {
        Probe(Some(std::thread::spawn(move || {
            choose(backend, adapter.as_deref(), missing)
        })))
    }

    /// What the search found.
    pub fn join(mut self) -> Result<Found> {
        let search = self.0.take().expect("joined once");
        search.join().expect("the adapter search does not panic")
    }
}

impl Drop for Probe {
    fn drop(&mut self) {
        if let Some(search) = self.0.take() {
            let _ = search.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backends_are_named_as_the_command_line_names_them() {
        for b in Backend::ALL {
            assert_eq!(Backend::from_name(b.name()), Some(b));
        }
        let names: Vec<&str> = Backend::ALL.iter().map(|b| b.name()).collect();
        assert_eq!(names, ["auto", "gpu", "cpu", "both"]);
        assert_eq!(Backend::from_name("GPU"), None);
    }

    #[test]
    fn the_cpu_backend_opens_no_device_and_says_nothing() {
        let found = choose(Backend::Cpu, None, Missing::Error).unwrap();
        assert!(found.gpu.is_none());
        assert_eq!(found.note, None);
        let found = Probe::start(Backend::Cpu, Some("any".into()), Missing::Cpu)
            .join()
            .unwrap();
        assert!(found.gpu.is_none() && found.note.is_none());
    }
}
