//! gpurt in the browser: the page's glue over the library's core, built for
//! `wasm32-unknown-unknown`. It reads a dropped or fetched scene with the library's
//! readers (`scene::io::decompress`, `scene::parse`), packs it, and traces it with the
//! WGSL renderer on the page's WebGPU device, one sample per step into an `Accumulator`
//! (progressive, as `gpurt view`), moving the camera with the viewer's `OrbitCamera`. An
//! animated scene (AFF) shows any of its frames, packed as the command line's sequences
//! pack them (`pack::frames`). It adds no rendering of its own; `index.html` and `app.js`
//! are the page.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

use gpurt::film::{self, Accumulator};
use gpurt::frame::{self, Overrides, RenderOptions, Shading};
use gpurt::gpu::{self, GpuContext, GpuRenderer, GpuScene};
use gpurt::gpu_types::GpuGlobals;
use gpurt::limits::{MAX_DEPTH, MAX_FILE_BYTES, MAX_IMAGE_SIDE, MAX_SPP};
use gpurt::pack::frames::{FramePacker, TreeMode};
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::animation::{Animation, TimeRange};
use gpurt::scene::{self, FlatScene, io::FileKind};
use gpurt::view::camera::{DragMode, Input, Key, OrbitCamera};
use wasm_bindgen::prelude::*;

fn js(e: impl std::fmt::Display) -> JsValue {
    JsValue::from_str(&e.to_string())
}

/// The device's error in `slot`, taken, as an error.
fn reported(slot: &Mutex<Option<String>>) -> Result<(), JsValue> {
    match slot.lock().expect("not poisoned").take() {
        Some(e) => Err(js(e)),
        None => Ok(()),
    }
}

/// A scene read and packed, with the camera that moves over it.
struct Loaded {
    buffers: SceneBuffers,
    orbit: OrbitCamera,
    /// Whether the camera was moved from the scene's own: until it is, a bare mesh is
    /// framed again for each new image size, as the command line frames it.
    moved: bool,
    /// The scene on the device and the frame it was last made ready for.
    uploaded: Option<(GpuGlobals, GpuScene)>,
    /// An animated scene's frames and the one shown; `None` for a still scene.
    frames: Option<Frames>,
}

struct Frames {
    packer: FramePacker,
    range: TimeRange,
    shown: u32,
}

/// The page's renderer: one WebGPU device, and the scene it shows.
#[wasm_bindgen]
pub struct Session {
    ctx: GpuContext,
    renderer: GpuRenderer,
    /// The first error the device reported outside a call's own checks (WebGPU reports
    /// validation and out-of-memory errors asynchronously: see the library's
    /// `gpu::device::Device::scoped`).
    gpu_error: Arc<Mutex<Option<String>>>,
    loaded: Option<Loaded>,
    overrides: Overrides,
    accum: Option<Accumulator>,
    rays: u64,
}

#[wasm_bindgen]
impl Session {
    /// Opens the page's WebGPU adapter and device.
    pub async fn start() -> Result<Session, JsValue> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::BROWSER_WEBGPU,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let ctx = gpu::request(&instance).await.map_err(js)?;
        let gpu_error = Arc::new(Mutex::new(None));
        let slot = gpu_error.clone();
        ctx.device.on_uncaptured_error(Arc::new(move |e| {
            let mut slot = slot.lock().expect("not poisoned");
            slot.get_or_insert_with(|| format!("GPU error: {e}"));
        }));
        let renderer = GpuRenderer::new(&ctx.device, None).map_err(js)?;
        Ok(Session {
            ctx,
            renderer,
            gpu_error,
            loaded: None,
            overrides: Overrides::default(),
            accum: None,
            rays: 0,
        })
    }

    /// The adapter, as `gpurt -v` names it.
    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }

    /// Reads a scene file's bytes (NFF, P3D, STL or OBJ by `name`'s extension, gzip
    /// too). A bad file is an error `FILE:LINE:COL: message`, `FILE` being `name`.
    pub fn load(&mut self, name: &str, bytes: Vec<u8>) -> Result<(), JsValue> {
        let path = Path::new(name);
        let bytes = scene::io::decompress(bytes, path, MAX_FILE_BYTES).map_err(js)?;
        // A page has no files around the scene: an NFF `mesh` include is an error.
        let mut scene =
            scene::parse(&bytes, FileKind::of(path), name, Path::new("/")).map_err(js)?;
        let samples = RenderOptions::for_camera(&scene.camera)
            .with_overrides(&self.overrides)
            .samples();
        // An animation with frames to show plays from its first; any other scene (one
        // that moves without a time range too) packs as the command line packs it.
        let plays = |a: &Animation| !a.is_still() && a.range.is_some();
        let (buffers, frames) = match scene.animation.take_if(|a| plays(a)) {
            Some(animation) => {
                let range = animation.range.expect("plays");
                let still = FlatScene::from_scene(scene);
                let mut packer = FramePacker::new(
                    still,
                    *animation,
                    true,
                    samples,
                    range.frames.into(),
                    TreeMode::Auto,
                )
                .map_err(js)?;
                let (buffers, _) = packer.pack(range.time(0)).map_err(js)?;
                let frames = Frames {
                    packer,
                    range,
                    shown: 0,
                };
                (buffers, Some(frames))
            }
            None => (pack::pack_for(scene, samples).map_err(js)?, None),
        };
        let orbit = OrbitCamera::new(buffers.camera.clone());
        self.loaded = Some(Loaded {
            buffers,
            orbit,
            moved: false,
            uploaded: None,
            frames,
        });
        self.restart();
        Ok(())
    }

    /// Sets the image size, samples per pixel and depth (0 keeps the scene's or the
    /// default) and the highlight's model ("phong" or "blinn-phong", as `--shading`
    /// takes it), and starts the image again.
    pub fn set_options(
        &mut self,
        width: u32,
        height: u32,
        spp: u32,
        depth: u32,
        shading: &str,
    ) -> Result<(), JsValue> {
        let pick = |v: u32, what: &str, max: u32| match v {
            0 => Ok(None),
            v if v <= max => Ok(Some(v)),
            v => Err(js(format!("{what} must be 1 to {max}, got {v}"))),
        };
        let shading = Shading::from_name(shading).ok_or_else(|| {
            let names: Vec<&str> = Shading::ALL.iter().map(|s| s.name()).collect();
            js(format!(
                "shading must be one of {}, got {shading:?}",
                names.join(", ")
            ))
        })?;
        self.overrides = Overrides {
            width: pick(width, "width", MAX_IMAGE_SIDE)?,
            height: pick(height, "height", MAX_IMAGE_SIDE)?,
            spp: pick(spp, "spp", MAX_SPP)?,
            max_depth: pick(depth, "depth", MAX_DEPTH)?,
            shading: Some(shading),
            ..Overrides::default()
        };
        self.restart();
        Ok(())
    }

    /// The frames of an animated scene (AFF), 0 for a still one.
    pub fn frames(&self) -> u32 {
        self.animation().map_or(0, |f| f.range.frames)
    }

    /// The frame of an animated scene shown (0 for a still one).
    pub fn frame(&self) -> u32 {
        self.animation().map_or(0, |f| f.shown)
    }

    /// Shows frame `frame` (from 0, as BART counts them) of an animated scene: its moving
    /// parts placed at the frame's time, and the view following the animation's camera
    /// unless it was moved away; the image starts again.
    pub fn set_frame(&mut self, frame: u32) -> Result<(), JsValue> {
        let loaded = self.loaded.as_mut().ok_or_else(|| js("no scene loaded"))?;
        let frames = loaded
            .frames
            .as_mut()
            .ok_or_else(|| js("nothing moves in this scene: it has no frames"))?;
        let n = frames.range.frames;
        if frame >= n {
            return Err(js(format!(
                "frame {frame} is outside the animation, whose {n} frames are 0..{}",
                n - 1
            )));
        }
        let (buffers, _) = frames.packer.pack(frames.range.time(frame)).map_err(js)?;
        frames.shown = frame;
        loaded.orbit.follow(buffers.camera.clone());
        loaded.buffers = buffers;
        loaded.uploaded = None;
        self.restart();
        Ok(())
    }

    /// Orbits (or pans, with `pan`) by a drag of `dx`, `dy` pixels, as in `gpurt view`.
    pub fn drag(&mut self, dx: f32, dy: f32, pan: bool) {
        let mode = if pan { DragMode::Pan } else { DragMode::Orbit };
        self.input(Input::Drag { mode, dx, dy });
    }

    /// Dollies by `notches` wheel notches (positive: towards the focus).
    pub fn dolly(&mut self, notches: f32) {
        self.input(Input::Wheel(notches));
    }

    /// Back to the scene's own camera.
    pub fn reset(&mut self) {
        self.input(Input::Key(Key::Reset));
    }

    /// The current camera as an NFF `v` block, which `gpurt SCENE --view FILE` renders.
    pub fn view_block(&self) -> String {
        self.loaded
            .as_ref()
            .map(|l| l.orbit.nff_view())
            .unwrap_or_default()
    }

    /// (width, height) of the image.
    pub fn size(&self) -> Vec<u32> {
        let opts = self.options();
        opts.map_or(vec![0, 0], |o| vec![o.width, o.height])
    }

    /// Samples per pixel traced so far, and the frame's total.
    pub fn samples(&self) -> Vec<u32> {
        let done = self.accum.as_ref().map_or(0, |a| a.samples);
        vec![done, self.options().map_or(0, |o| o.spp)]
    }

    /// Rays traced for the image so far, counted as `gpurt --stats` counts them.
    pub fn rays(&self) -> f64 {
        self.rays as f64
    }

    /// Traces the next sample of every pixel; false when the image has all its samples.
    pub async fn step(&mut self) -> Result<bool, JsValue> {
        let (Some(opts), Some(loaded)) = (self.options(), self.loaded.as_mut()) else {
            return Ok(false);
        };
        let accum = self
            .accum
            .get_or_insert_with(|| Accumulator::new(opts.width, opts.height));
        if accum.samples >= opts.spp {
            return Ok(false);
        }
        let globals = frame::globals_from(&loaded.buffers, &loaded.orbit.camera, &opts);
        let globals = self.renderer.frame(&loaded.buffers, &globals);
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let slot = &mut loaded.uploaded;
        self.renderer
            .ready(device, queue, slot, &loaded.buffers, &globals)
            .map_err(js)?;
        let (_, uploaded) = slot.as_ref().expect("made ready");
        let next = accum.samples..accum.samples + 1;
        let rows = 0..opts.height;
        let never = AtomicBool::new(false);
        let trace =
            gpu::trace_rows_async(device, queue, uploaded, rows, next, accum, &|_| {}, &never);
        let rays = trace.await.map_err(js)?;
        reported(&self.gpu_error)?;
        self.rays += rays;
        Ok(accum.samples < opts.spp)
    }

    /// The first error the device reported since the last check, as an error: WebGPU
    /// reports some (a shader its compiler rejects) only after the work that met it has
    /// been read back, so a finished image is checked once more before it is shown.
    pub fn check(&self) -> Result<(), JsValue> {
        reported(&self.gpu_error)
    }

    /// The image so far as RGBA bytes for a canvas: the 8-bit values the command line's
    /// PNG holds (`Film::to_rgb8`), opaque.
    pub fn rgba(&self) -> Vec<u8> {
        let Some(accum) = &self.accum else {
            return Vec::new();
        };
        let rgb = accum.film().to_rgb8();
        rgb.pixels().flat_map(|p| [p[0], p[1], p[2], 255]).collect()
    }

    /// The image so far as a PNG file, the bytes `gpurt` writes for the same film.
    pub fn png(&self) -> Result<Vec<u8>, JsValue> {
        let accum = self
            .accum
            .as_ref()
            .ok_or_else(|| js("nothing rendered yet"))?;
        film::encode_png(&accum.film().to_rgb8()).map_err(js)
    }
}

impl Session {
    /// The loaded scene's frames, if it is animated.
    fn animation(&self) -> Option<&Frames> {
        self.loaded.as_ref()?.frames.as_ref()
    }

    /// The frame's options: the scene's resolution and the defaults, with the page's
    /// settings over them.
    fn options(&self) -> Option<RenderOptions> {
        let loaded = self.loaded.as_ref()?;
        Some(RenderOptions::for_camera(&loaded.buffers.camera).with_overrides(&self.overrides))
    }

    /// Starts the image again (new settings or a new view), keeping the orbit camera's
    /// idea of the image size current for its drag scale and its `v` block.
    fn restart(&mut self) {
        self.accum = None;
        self.rays = 0;
        if let Some(opts) = self.options()
            && let Some(loaded) = self.loaded.as_mut()
        {
            let (w, h) = (opts.width, opts.height);
            if !loaded.moved && (loaded.orbit.camera.width, loaded.orbit.camera.height) != (w, h) {
                loaded.orbit = OrbitCamera::new(scene::auto::fitted(&loaded.buffers.camera, w, h));
            }
            loaded.orbit.camera.width = w;
            loaded.orbit.camera.height = h;
        }
    }

    fn input(&mut self, input: Input) {
        if let Some(loaded) = self.loaded.as_mut()
            && loaded.orbit.apply(input)
        {
            loaded.moved = !matches!(input, Input::Key(Key::Reset));
            self.restart();
        }
    }
}
