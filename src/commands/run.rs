//! One render from a scene file to a film, as the command line drives it: read, then
//! pack for the frame the camera and the options make (each timed), then the frame on any `Renderer`, made ready, traced and timed the same way
//! on both backends.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::cpu::RayCounts;
use crate::film::{Accumulator, Film};
use crate::gpu::GpuContext;
use crate::gpu_types::GpuGlobals;
use crate::pack::frames::{FramePacker, TreeMode};
use crate::pack::{self, SceneBuffers};
use crate::scene::animation::Animation;
use crate::scene::flat::FlatScene;
use crate::scene::{self, Camera, ReadOptions};
use crate::session::{CpuRenderer, GpuSession, Renderer};
use crate::util::error::{Error, Result};

/// A scene read into the renderers' records, not yet packed: its camera says what a
/// frame of it traces, and so the samples that choose its tree's build (`pack`).
#[derive(Clone)]
pub struct Read {
    flat: FlatScene,
    parse_time: Duration,
    /// What moves, in an AFF scene: placed by `at`.
    animation: Option<Box<Animation>>,
    /// Whether the camera was given (`--view`), which the animation then leaves alone.
    view_given: bool,
}

impl Read {
    /// The scene's camera (the view's, when one was given).
    pub fn camera(&self) -> &Camera {
        &self.flat.scene.camera
    }

    /// What the reader warned of.
    pub fn warnings(&self) -> &[String] {
        &self.flat.scene.warnings
    }

    /// What moves in the scene, if anything does.
    pub fn animation(&self) -> Option<&Animation> {
        self.animation.as_deref()
    }

    /// The scene at time `t`, its moving parts placed (an AFF scene's; a still scene
    /// stays as it is), ready to pack; the time placing took is added to the parse time.
    pub fn at(&self, t: f64) -> Read {
        let start = Instant::now();
        let flat = match &self.animation {
            Some(anim) => anim.flat_at(&self.flat, t, !self.view_given),
            None => self.flat.clone(),
        };
        Read {
            flat,
            parse_time: start.elapsed(),
            animation: None,
            view_given: self.view_given,
        }
    }

    /// A packer of the animation's frames (`pack::frames`), each tracing `samples`
    /// camera samples, `frames` of them; `None` for a still scene.
    pub fn frames(&self, samples: u64, frames: u64) -> Result<Option<FramePacker>> {
        let Some(anim) = &self.animation else {
            return Ok(None);
        };
        let mode = TreeMode::from_env().map_err(Error::Render)?;
        let (still, anim) = (self.flat.clone(), anim.as_ref().clone());
        FramePacker::new(still, anim, !self.view_given, samples, frames, mode).map(Some)
    }

    /// The scene for a still image: an AFF scene at time `time`, else at the start of
    /// its time range (or 0); a still scene as it is (`time` must then be `None`).
    pub fn still(self, time: Option<f64>) -> Result<Read> {
        match (&self.animation, time) {
            (None, None) => Ok(self),
            (None, Some(_)) => Err(Error::Scene {
                file: self.flat.scene.name.clone(),
                msg: "--time is for scenes that move (AFF), and nothing moves in this one".into(),
            }),
            (Some(anim), t) => {
                let t = t.unwrap_or_else(|| anim.default_time());
                let mut placed = self.at(t);
                placed.parse_time += self.parse_time;
                Ok(placed)
            }
        }
    }
}

/// A scene read and packed, with the time each step took and the reader's warnings (the
/// `Scene` itself is gone: packing consumes it).
pub struct Prepared {
    pub buffers: SceneBuffers,
    pub warnings: Vec<String>,
    pub parse_time: Duration,
    pub build_time: Duration,
}

/// Reads the scene at `path` straight into the renderers' records (the scene is never
/// held twice), with the camera of the NFF `v` block in `view` when one is given (a view
/// found in `gpurt view`, printed with its C key), read as `read` says (`--lenient`).
pub fn read(path: &Path, view: Option<&Path>, read: &ReadOptions) -> Result<Read> {
    let t0 = Instant::now();
    let mut flat = scene::load_flat_with(path, read)?;
    let animation = flat.scene.animation.take();
    if let Some(view) = view {
        flat.scene.camera = scene::summary(view)?.scene.camera;
    }
    Ok(Read {
        flat,
        parse_time: t0.elapsed(),
        animation,
        view_given: view.is_some(),
    })
}

/// Packs a scene read by `read` for a render of `samples` camera samples, which picks
/// the BVH's build quality (`bvh::Quality::chosen`).
pub fn pack(read: Read, samples: u64) -> Result<Prepared> {
    let Read {
        mut flat,
        parse_time,
        ..
    } = read;
    let t1 = Instant::now();
    let warnings = std::mem::take(&mut flat.scene.warnings);
    let buffers = pack::pack_flat(flat, samples)?;
    Ok(Prepared {
        buffers,
        warnings,
        parse_time,
        build_time: t1.elapsed(),
    })
}

/// A frame rendered, and what it cost.
pub struct Rendered {
    pub film: Film,
    pub rays: u64,
    /// The rays by kind, and how many went in packets, where the renderer counts them
    /// so (the CPU's; `Renderer::ray_kinds`).
    pub kinds: Option<RayCounts>,
    /// Time spent compiling shaders to get ready (zero on the CPU, or when compiled before).
    pub compile: Duration,
    /// Time tracing the frame (on the GPU with the scene's upload and the readback).
    pub trace: Duration,
}

impl Rendered {
    pub fn mrays_per_s(&self) -> f64 {
        self.rays as f64 / self.trace.as_secs_f64().max(1e-9) / 1e6
    }
}

/// Renders every sample of the frame `globals` describes on `renderer`, compiling
/// first so that the tracing is timed alone.
pub fn render_frame(
    renderer: &mut dyn Renderer,
    globals: &GpuGlobals,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<Rendered> {
    let compile = renderer.prepare(globals)?;
    let start = Instant::now();
    let mut accum = Accumulator::new(globals.width, globals.height);
    let rays = renderer.render(globals, 0..globals.spp, &mut accum, progress, cancel)?;
    let trace = start.elapsed();
    Ok(Rendered {
        film: accum.into_film(),
        rays,
        kinds: renderer.ray_kinds(),
        compile,
        trace,
    })
}

/// The renderer for the next of many scenes traced in turn (a batch's scenes, a
/// sequence's frames): on `gpu`'s device, the one `session` kept from scene to scene (its
/// pipelines compiled once), opened the first time; without a device, a CPU renderer of
/// this scene, held in `cpu`.
pub fn next_renderer<'a>(
    gpu: Option<&GpuContext>,
    session: &'a mut Option<GpuSession>,
    cpu: &'a mut Option<CpuRenderer>,
    scene: Arc<SceneBuffers>,
) -> Result<&'a mut dyn Renderer> {
    let Some(ctx) = gpu else {
        return Ok(cpu.insert(CpuRenderer::new(scene)));
    };
    let s = match session.take() {
        Some(mut s) => {
            s.set_scene(scene);
            s
        }
        None => GpuSession::new(ctx.clone(), scene)?,
    };
    Ok(session.insert(s))
}

/// Peak resident memory of this process in bytes (Linux; `None` elsewhere).
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
