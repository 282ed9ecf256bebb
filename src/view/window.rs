//! The viewer's window: winit for the window and its input, a wgpu surface to show the
//! ray-traced image (written straight into the surface texture) and the wireframe (drawn
//! over it by `Wireframe::encode`). Input becomes `camera::Input` and `controls::Action`
//! here and nowhere else; a moved camera starts a new view on the `progressive::Tracer`.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use image::RgbImage;
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::keyboard::{Key as WinitKey, NamedKey};
use winit::window::{Window, WindowId};

use super::camera::{DragMode, Input, OrbitCamera};
use super::controls::{Action, Mode, key_action};
use super::progressive::{Job, Pass, Tracer};
use super::readback::TextureReadback;
use super::script::Event;
use super::wireframe::Wireframe;
use crate::error::{Error, Result};
use crate::frame::{self, RenderOptions};
use crate::gpu::render::scoped;
use crate::gpu::{self, GpuContext};
use crate::gpu_types::{AOV_COLOR, GpuGlobals};
use crate::limits::MAX_SPP;
use crate::pack::SceneBuffers;
use crate::session::{CpuRenderer, GpuSession, Renderer};
use crate::{film, outln};

/// Which renderer traces the viewer's image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The GPU on a hardware adapter, else the CPU (`gpu::choose`).
    Auto,
    Gpu,
    Cpu,
}

/// What `gpurt view` was asked for.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// The scene's name, for the title and the names of saved images.
    pub name: String,
    /// Window size; the scene's resolution when not given.
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Stop accumulating after this many samples per pixel (else at `MAX_SPP`).
    pub spp: Option<u32>,
    pub depth: u32,
    pub ambient: Option<Vec3>,
    pub seed: u32,
    pub backend: Backend,
    pub adapter: Option<String>,
    /// Events to replay, and where to write the window's image once they are done
    /// (the program then exits).
    pub script: Option<Vec<Event>>,
    pub screenshot: Option<PathBuf>,
    /// Print frame times and rates on exit.
    pub stats: bool,
    /// When the program started, for the time to the first picture.
    pub launch: Instant,
}

/// Opens the window and runs until it is closed (or the script's screenshot is written).
pub fn run(buffers: SceneBuffers, opts: ViewOptions) -> Result<()> {
    let event_loop = EventLoop::<Result<Pass>>::with_user_event()
        .build()
        .map_err(no_display)?;
    let mut app = App::new(buffers, opts, event_loop.create_proxy());
    event_loop.run_app(&mut app).map_err(no_display)?;
    if app.opts.stats {
        app.stats.print(&app);
    }
    app.result
}

/// winit's error without the source position it starts with ("os error at FILE:LINE: "),
/// which says nothing to a user.
fn no_display(e: impl std::fmt::Display) -> Error {
    let text = e.to_string();
    let why = match text.strip_prefix("os error at ") {
        Some(rest) => rest.split_once(": ").map_or(rest, |(_, why)| why),
        None => &text,
    };
    Error::NoDisplay(format!(
        "{} (on a machine without a display, run it under xvfb-run)",
        why.trim_end_matches('.')
    ))
}

/// What exists once the window does.
struct Live {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The surface format without sRGB encoding: the image's bytes are shown as they are,
    /// as the PNG of the same view stores them.
    view_format: wgpu::TextureFormat,
    ctx: GpuContext,
    wireframe: Wireframe,
    tracer: Tracer,
    /// The adapter (or CPU) that traces.
    tracing_on: String,
    /// The title shown, set again only when it changes.
    title: String,
}

/// The pointer, for drags.
#[derive(Default)]
struct Pointer {
    at: Option<PhysicalPosition<f64>>,
    orbiting: bool,
    panning: bool,
    shift: bool,
}

struct App {
    buffers: Arc<SceneBuffers>,
    opts: ViewOptions,
    proxy: EventLoopProxy<Result<Pass>>,
    live: Option<Live>,
    camera: OrbitCamera,
    mode: Mode,
    /// The number of the view shown: every camera move or resize makes a new one.
    view: u64,
    view_start: Instant,
    /// The newest pass of the current view.
    latest: Option<Pass>,
    /// Its image in the surface's byte order: converted once per pass, not once per
    /// frame (a script's waits redraw the same pass many times).
    latest_bytes: Vec<u8>,
    pointer: Pointer,
    script: VecDeque<Event>,
    /// Frames still to show before the script goes on.
    waiting: u32,
    /// The next frame is read back and written to `opts.screenshot`, then the program ends.
    shoot: bool,
    /// `P` was pressed: the image is written once the view has its samples.
    save_pending: bool,
    stats: Stats,
    result: Result<()>,
}

impl App {
    fn new(buffers: SceneBuffers, opts: ViewOptions, proxy: EventLoopProxy<Result<Pass>>) -> Self {
        let mut camera = OrbitCamera::new(buffers.camera.clone());
        camera.camera.width = opts.width.unwrap_or(camera.camera.width);
        camera.camera.height = opts.height.unwrap_or(camera.camera.height);
        let script = opts.script.clone().unwrap_or_default().into();
        App {
            buffers: Arc::new(buffers),
            proxy,
            live: None,
            camera,
            mode: Mode::RayTraced,
            view: 0,
            view_start: Instant::now(),
            latest: None,
            latest_bytes: Vec::new(),
            pointer: Pointer::default(),
            script,
            waiting: 0,
            shoot: false,
            save_pending: false,
            stats: Stats::new(opts.launch),
            result: Ok(()),
            opts,
        }
    }

    /// Samples per pixel a view gets: the `--spp` cap, else as many as a frame may have.
    fn spp(&self) -> u32 {
        self.opts.spp.unwrap_or(MAX_SPP)
    }

    /// The frame the current view traces.
    fn globals(&self) -> GpuGlobals {
        let c = &self.camera.camera;
        let opts = RenderOptions {
            width: c.width,
            height: c.height,
            spp: self.spp(),
            max_depth: self.opts.depth,
            ambient: self.opts.ambient,
            aov: AOV_COLOR,
            seed: self.opts.seed,
        };
        frame::globals_from(&self.buffers, c, &opts)
    }

    /// Whether the current view has all the samples it will get.
    fn converged(&self) -> bool {
        self.latest
            .as_ref()
            .is_some_and(|p| p.samples >= self.spp())
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let c = &self.camera.camera;
        let attributes = Window::default_attributes()
            .with_title(format!("gpurt view - {}", self.opts.name))
            .with_inner_size(PhysicalSize::new(c.width, c.height));
        let window = Arc::new(event_loop.create_window(attributes).map_err(no_display)?);
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| Error::Gpu(format!("cannot draw into the window: {e}")))?;
        let ctx = gpu::open_on(&instance, self.opts.adapter.as_deref(), Some(&surface))?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // 8-bit formats only: the image's bytes go into the surface texture unchanged.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f.remove_srgb_suffix(),
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .ok_or_else(|| {
                Error::Gpu(format!(
                    "the window offers no 8-bit RGBA or BGRA format (only {:?})",
                    caps.formats
                ))
            })?;
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST;
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        if !caps.usages.contains(usage) {
            return Err(Error::Gpu(format!(
                "the window's surface cannot be copied into (it allows {:?})",
                caps.usages
            )));
        }
        if self.opts.screenshot.is_some() && !usage.contains(wgpu::TextureUsages::COPY_SRC) {
            return Err(Error::Gpu(
                "the window's surface cannot be read back for --screenshot".into(),
            ));
        }
        let view_format = format.remove_srgb_suffix();
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            color_space: wgpu::SurfaceColorSpace::Auto,
            view_formats: if view_format == format {
                vec![]
            } else {
                vec![view_format]
            },
        };
        surface.configure(&ctx.device, &config);
        let wireframe = Wireframe::new(&ctx.device, &self.buffers, view_format)?;
        // The tracer gets a device of its own: one device runs its submissions in order,
        // so a window sharing the tracer's would wait for each band of rays before drawing
        // a frame (a second or more at 800x600 on lavapipe), and a moving camera's
        // wireframe would stall with it.
        let filter = self.opts.adapter.as_deref();
        let tracer_device = match self.opts.backend {
            Backend::Gpu => Some(gpu::open(filter)?),
            Backend::Cpu => None,
            Backend::Auto => match gpu::choose(filter)? {
                gpu::Choice::Gpu(ctx) => Some(*ctx),
                gpu::Choice::Cpu(_) => None,
            },
        };
        let renderer: Box<dyn Renderer + Send> = match tracer_device {
            Some(ctx) => Box::new(GpuSession::new(ctx, self.buffers.clone())?),
            None => Box::new(CpuRenderer::new(self.buffers.clone())),
        };
        let tracing_on = renderer.describe();
        let proxy = self.proxy.clone();
        let tracer = Tracer::spawn(renderer, move |pass| {
            // The loop is gone only when the window has closed.
            let _ = proxy.send_event(pass);
        });
        self.stats.adapter = ctx.describe();
        self.stats.tracing_on = tracing_on.clone();
        self.live = Some(Live {
            window,
            surface,
            config,
            view_format,
            ctx,
            wireframe,
            tracer,
            tracing_on,
            title: String::new(),
        });
        self.resize(size);
        Ok(())
    }

    /// The window's size is the image's: a new size is a new view.
    fn resize(&mut self, size: PhysicalSize<u32>) {
        let Some(live) = &mut self.live else { return };
        let (w, h) = (size.width.max(1), size.height.max(1));
        if (live.config.width, live.config.height) != (w, h) {
            live.config.width = w;
            live.config.height = h;
            live.surface.configure(&live.ctx.device, &live.config);
        }
        self.camera.camera.width = w;
        self.camera.camera.height = h;
        self.restart();
    }

    /// Starts the current view from no samples (or stops tracing in wireframe mode).
    fn restart(&mut self) {
        self.view += 1;
        self.view_start = Instant::now();
        self.latest = None;
        let globals = self.globals();
        let Some(live) = &self.live else { return };
        if self.mode.traces() {
            live.tracer.trace(Job {
                view: self.view,
                globals,
            });
        } else {
            live.tracer.pause();
        }
        live.window.request_redraw();
    }

    fn act(&mut self, action: Action, event_loop: &ActiveEventLoop) {
        match action {
            Action::Camera(input) => {
                let (w, h) = (self.camera.camera.width, self.camera.camera.height);
                let moved = self.camera.apply(input);
                // A reset brings back the scene's resolution; the window's stays.
                self.camera.camera.width = w;
                self.camera.camera.height = h;
                if moved {
                    self.restart();
                }
            }
            Action::NextMode => {
                let was = self.mode;
                self.mode = self.mode.next();
                if was.traces() != self.mode.traces() {
                    self.restart();
                } else if let Some(live) = &self.live {
                    live.window.request_redraw();
                }
            }
            Action::PrintView => outln!("{}", self.camera.nff_view()),
            Action::SavePng => {
                self.save_pending = true;
                self.save_if_ready();
            }
            Action::Quit => event_loop.exit(),
        }
    }

    /// Writes the image `P` asked for: with `--spp N` once the view has its N samples,
    /// else at once, with the samples it has (without a cap a view converges for hours).
    fn save_if_ready(&mut self) {
        let ready = if self.opts.spp.is_some() {
            self.converged()
        } else {
            self.latest.is_some()
        };
        if !self.save_pending || !ready {
            return;
        }
        self.save_pending = false;
        let Some(pass) = &self.latest else { return };
        let stem = Path::new(&self.opts.name)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let stem = stem.split('.').next().unwrap_or("view");
        let path = (1..)
            .map(|n| PathBuf::from(format!("{stem}-view-{n}.png")))
            .find(|p| !p.exists())
            .expect("a free name");
        match film::save_rgb8(&pass.image, &path) {
            Ok(()) => eprintln!("gpurt: wrote {} ({} spp)", path.display(), pass.samples),
            Err(e) => eprintln!("gpurt: {e}"),
        }
    }

    fn pointer_moved(&mut self, at: PhysicalPosition<f64>, event_loop: &ActiveEventLoop) {
        let last = self.pointer.at.replace(at);
        let Some(last) = last else { return };
        let (dx, dy) = ((at.x - last.x) as f32, (at.y - last.y) as f32);
        let mode = if self.pointer.panning || (self.pointer.orbiting && self.pointer.shift) {
            DragMode::Pan
        } else if self.pointer.orbiting {
            DragMode::Orbit
        } else {
            return;
        };
        if dx != 0.0 || dy != 0.0 {
            self.act(Action::Camera(Input::Drag { mode, dx, dy }), event_loop);
        }
    }

    /// Replays the script up to its next wait; when it is over, asks for the screenshot
    /// once the view has its samples.
    fn step_script(&mut self, event_loop: &ActiveEventLoop) {
        if self.opts.script.is_none() {
            return;
        }
        while self.waiting == 0 {
            match self.script.pop_front() {
                Some(Event::Action(a)) => self.act(a, event_loop),
                Some(Event::Wait(n)) => self.waiting = n,
                None => break,
            }
        }
        let Some(live) = &self.live else { return };
        if self.waiting > 0 {
            // Frames are shown back to back while a script waits.
            live.window.request_redraw();
        } else if self.opts.screenshot.is_some()
            && !self.shoot
            && (!self.mode.traces() || self.opts.spp.is_none() || self.converged())
        {
            self.shoot = true;
            live.window.request_redraw();
        }
    }

    /// Shows the current view: the image of its newest pass, or the wireframe until
    /// there is one, with the wireframe over it in overlay mode.
    fn draw(&mut self) -> Result<()> {
        let globals = self.globals();
        let title = self.title();
        let Some(live) = &mut self.live else {
            return Ok(());
        };
        let start = Instant::now();
        let frame = match live.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                live.window.request_redraw();
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                live.surface.configure(&live.ctx.device, &live.config);
                live.window.request_redraw();
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(Error::Gpu("the window's surface texture is invalid".into()));
            }
        };
        let (w, h) = (live.config.width, live.config.height);
        let traced = self
            .latest
            .as_ref()
            .is_some_and(|p| self.mode.traces() && p.image.dimensions() == (w, h));
        let lines = self.mode != Mode::RayTraced || !traced;
        let (device, queue) = (&live.ctx.device, &live.ctx.queue);
        let target = frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(live.view_format),
            ..Default::default()
        });
        let shot = scoped(device, "drawing the window", || {
            let mut enc = device.create_command_encoder(&Default::default());
            if traced {
                queue.write_texture(
                    frame.texture.as_image_copy(),
                    &self.latest_bytes,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * w),
                        rows_per_image: Some(h),
                    },
                    frame.texture.size(),
                );
            } else {
                clear(&mut enc, &target);
            }
            if lines {
                live.wireframe.encode(queue, &mut enc, &target, &globals);
            }
            let shot = self
                .shoot
                .then(|| TextureReadback::encode(device, &mut enc, &frame.texture));
            queue.submit([enc.finish()]);
            shot
        })?;
        if let Some(shot) = shot {
            let img = shot.read(device, live.view_format)?;
            let path = self.opts.screenshot.as_ref().expect("shoot needs a path");
            film::save_rgb8(&img, path)?;
        }
        queue.present(frame);
        self.stats
            .frame(start.elapsed(), traced, self.latest.as_ref());
        if live.title != title {
            live.window.set_title(&title);
            live.title = title;
        }
        self.waiting = self.waiting.saturating_sub(1);
        Ok(())
    }

    fn title(&self) -> String {
        let mut t = format!("gpurt view - {} - {}", self.opts.name, self.mode.name());
        if let Some(p) = self.latest.as_ref().filter(|_| self.mode.traces()) {
            let mrays = p.rays as f64 / p.trace_time.as_secs_f64().max(1e-9) / 1e6;
            t.push_str(&format!(" - {} spp - {mrays:.1} Mrays/s", p.samples));
        }
        if let Some(live) = &self.live {
            t.push_str(&format!(" - {}", live.tracing_on));
        }
        t
    }

    fn fail(&mut self, e: Error, event_loop: &ActiveEventLoop) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        event_loop.exit();
    }
}

impl ApplicationHandler<Result<Pass>> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.live.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.fail(e, event_loop);
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, pass: Result<Pass>) {
        match pass {
            Ok(pass) if pass.view == self.view => {
                self.stats.pass(&pass, self.view_start);
                if let Some(live) = &self.live {
                    self.latest_bytes = surface_bytes(&pass.image, live.view_format);
                }
                self.latest = Some(pass);
                self.save_if_ready();
                if let Some(live) = &self.live {
                    live.window.request_redraw();
                }
            }
            // A pass of a view that has since moved on.
            Ok(_) => {}
            Err(e) => self.fail(e, event_loop),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => self.resize(size),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.draw() {
                    self.fail(e, event_loop);
                } else if self.shoot {
                    event_loop.exit();
                }
            }
            WindowEvent::ModifiersChanged(m) => self.pointer.shift = m.state().shift_key(),
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.pointer.orbiting = down,
                    MouseButton::Middle | MouseButton::Right => self.pointer.panning = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.pointer_moved(position, event_loop),
            WindowEvent::CursorLeft { .. } => self.pointer.at = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    // Touchpads report pixels; about 40 make a notch.
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if notches != 0.0 {
                    self.act(Action::Camera(Input::Wheel(notches)), event_loop);
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let name = match &event.logical_key {
                    WinitKey::Character(c) => Some(c.as_str()),
                    WinitKey::Named(NamedKey::Escape) => Some("escape"),
                    _ => None,
                };
                if let Some(action) = name.and_then(key_action) {
                    self.act(action, event_loop);
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        self.step_script(event_loop);
        event_loop.set_control_flow(ControlFlow::Wait);
    }
}

/// Clears the target to black (the background of the wireframe alone).
fn clear(enc: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
}

/// An image's pixels in the byte order of a surface format (RGBA or BGRA), opaque.
fn surface_bytes(img: &RgbImage, format: wgpu::TextureFormat) -> Vec<u8> {
    let bgra = format == wgpu::TextureFormat::Bgra8Unorm;
    img.pixels()
        .flat_map(|p| {
            let [r, g, b] = p.0;
            if bgra { [b, g, r, 255] } else { [r, g, b, 255] }
        })
        .collect()
}

/// What `--stats` prints on exit: how soon the first pictures came, how long frames take
/// to draw, and how fast the last view converged.
struct Stats {
    launch: Instant,
    adapter: String,
    tracing_on: String,
    first_frame: Option<Duration>,
    first_image: Option<(Duration, u32)>,
    draw_times: Vec<Duration>,
    first_present: Option<Instant>,
    last_present: Option<Instant>,
    /// The newest pass shown and how long its view had been traced by then.
    last_pass: Option<(u32, u64, Duration, Duration)>,
}

impl Stats {
    fn new(launch: Instant) -> Self {
        Stats {
            launch,
            adapter: String::new(),
            tracing_on: String::new(),
            first_frame: None,
            first_image: None,
            draw_times: Vec::new(),
            first_present: None,
            last_present: None,
            last_pass: None,
        }
    }

    fn frame(&mut self, took: Duration, traced: bool, latest: Option<&Pass>) {
        let now = Instant::now();
        self.first_frame.get_or_insert(now - self.launch);
        if traced && let Some(p) = latest {
            self.first_image
                .get_or_insert((now - self.launch, p.samples));
        }
        self.first_present.get_or_insert(now);
        self.last_present = Some(now);
        self.draw_times.push(took);
    }

    fn pass(&mut self, pass: &Pass, view_start: Instant) {
        self.last_pass = Some((
            pass.samples,
            pass.rays,
            pass.trace_time,
            view_start.elapsed(),
        ));
    }

    fn print(&self, app: &App) {
        let c = &app.camera.camera;
        eprintln!(
            "viewer      {}x{}, {} mode",
            c.width,
            c.height,
            app.mode.name()
        );
        eprintln!("display     {}", self.adapter);
        eprintln!("tracing     {}", self.tracing_on);
        if let Some(t) = self.first_frame {
            eprintln!("first frame {:.3} s after launch", t.as_secs_f64());
        }
        if let Some((t, spp)) = self.first_image {
            eprintln!(
                "first image {:.3} s after launch ({spp} spp)",
                t.as_secs_f64()
            );
        }
        let mut times = self.draw_times.clone();
        times.sort();
        if let (Some(first), Some(last)) = (self.first_present, self.last_present)
            && times.len() > 1
        {
            let span = (last - first).as_secs_f64().max(1e-9);
            eprintln!(
                "frames      {} shown, {:.1} per second; drawing one takes {:.2} ms (median)",
                times.len(),
                (times.len() - 1) as f64 / span,
                times[times.len() / 2].as_secs_f64() * 1e3
            );
        }
        if let Some((spp, rays, trace, wall)) = self.last_pass {
            eprintln!(
                "last view   {spp} spp in {:.3} s: {:.2} spp/s, {:.2} Mrays/s ({:.2} tracing alone)",
                wall.as_secs_f64(),
                f64::from(spp) / wall.as_secs_f64().max(1e-9),
                rays as f64 / wall.as_secs_f64().max(1e-9) / 1e6,
                rays as f64 / trace.as_secs_f64().max(1e-9) / 1e6
            );
        }
    }
}
