//! The viewer's window: its life and its events (winit), and what it shows. Input becomes
//! `controls::Action`s (`input`) and acts here on the camera and the mode; a moved camera
//! or a new size starts a new view on the `progressive::Tracer`, whose passes come back as
//! events and are drawn, with or without the wireframe, into the window's `surface`. What
//! each action does, and the replay of a script, are `actions`'.

mod actions;

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::{Window, WindowId};

use super::camera::OrbitCamera;
use super::controls::Mode;
use super::input::Pointer;
use super::playback::Playback;
use super::progressive::{Job, Pass, Tracer};
use super::script::Event;
use super::stats::Stats;
use super::surface::{Drawn, Surface};
use crate::frame::{self, Overrides, RenderOptions, Shading};
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use crate::scene::auto;
use crate::session::{self, Backend, CpuRenderer, GpuSession, Missing, Renderer};
use crate::util::error::{Error, Result};
use crate::util::limits::MAX_SPP;

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
    /// The highlight's model.
    pub shading: Shading,
    /// Which renderer traces the image (`Both`: the GPU).
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
/// `buffers` is the scene shown first; an animated scene's `playback` steps and plays
/// through its frames from there (`buffers` being its first).
pub fn run(buffers: SceneBuffers, opts: ViewOptions, playback: Option<Playback>) -> Result<()> {
    let event_loop = EventLoop::<Result<Pass>>::with_user_event()
        .build()
        .map_err(no_display)?;
    let mut app = App::new(buffers, opts, event_loop.create_proxy());
    app.playback = playback;
    event_loop.run_app(&mut app).map_err(no_display)?;
    if app.opts.stats {
        let c = &app.camera.camera;
        app.stats.print((c.width, c.height), app.mode);
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
    surface: Surface,
    tracer: Tracer,
    /// The adapter (or CPU) that traces.
    tracing_on: String,
    /// The title shown, set again only when it changes.
    title: String,
}

struct App {
    buffers: Arc<SceneBuffers>,
    /// An animated scene's frames, the one shown being `buffers`.
    playback: Option<Playback>,
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
        let c = &buffers.camera;
        let (width, height) = (
            opts.width.unwrap_or(c.width),
            opts.height.unwrap_or(c.height),
        );
        // A bare mesh is framed again for the window's shape.
        let mut camera = OrbitCamera::new(auto::fitted(c, width, height));
        (camera.camera.width, camera.camera.height) = (width, height);
        let script = opts.script.clone().unwrap_or_default().into();
        App {
            buffers: Arc::new(buffers),
            playback: None,
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
        let opts = RenderOptions::for_camera(c).with_overrides(&Overrides {
            spp: Some(self.spp()),
            max_depth: Some(self.opts.depth),
            ambient: self.opts.ambient,
            seed: Some(self.opts.seed),
            shading: Some(self.opts.shading),
            ..Overrides::default()
        });
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
        let surface = Surface::new(
            &window,
            self.opts.adapter.as_deref(),
            self.opts.screenshot.is_some(),
            &self.buffers,
        )?;
        // The tracer gets a device of its own: one device runs its submissions in order,
        // so a window sharing the tracer's would wait for each band of rays before drawing
        // a frame (a second or more at 800x600 on lavapipe), and a moving camera's
        // wireframe would stall with it.
        let found = session::choose(
            self.opts.backend,
            self.opts.adapter.as_deref(),
            Missing::Error,
        )?;
        let renderer: Box<dyn Renderer + Send> = match found.gpu {
            Some(ctx) => Box::new(GpuSession::new(ctx, self.buffers.clone())?),
            None => Box::new(CpuRenderer::new(self.buffers.clone())),
        };
        let tracing_on = renderer.describe();
        let proxy = self.proxy.clone();
        let tracer = Tracer::spawn(renderer, move |pass| {
            // The loop is gone only when the window has closed.
            let _ = proxy.send_event(pass);
        });
        self.stats.devices(surface.describe(), tracing_on.clone());
        let (w, h) = surface.size();
        self.live = Some(Live {
            window,
            surface,
            tracer,
            tracing_on,
            title: String::new(),
        });
        self.resize(PhysicalSize::new(w, h));
        Ok(())
    }

    /// The window's size is the image's: a new size is a new view.
    fn resize(&mut self, size: PhysicalSize<u32>) {
        let Some(live) = &mut self.live else { return };
        let (w, h) = (size.width.max(1), size.height.max(1));
        live.surface.resize((w, h));
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

    /// Shows the current view: the image of its newest pass, or the wireframe until
    /// there is one, with the wireframe over it in overlay mode.
    fn draw(&mut self) -> Result<()> {
        let globals = self.globals();
        let title = self.title();
        let Some(live) = &mut self.live else {
            return Ok(());
        };
        let traced = self
            .latest
            .as_ref()
            .is_some_and(|p| self.mode.traces() && p.image.dimensions() == live.surface.size());
        let lines = self.mode != Mode::RayTraced || !traced;
        let screenshot = self.shoot.then(|| {
            let path = self.opts.screenshot.as_ref().expect("shoot needs a path");
            path.as_path()
        });
        let start = Instant::now();
        let drawn = live.surface.draw(
            traced.then_some(self.latest_bytes.as_slice()),
            lines.then_some(&globals),
            screenshot,
        )?;
        if let Drawn::Later = drawn {
            live.window.request_redraw();
            return Ok(());
        }
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
        if let Some(p) = &self.playback {
            t.push_str(&format!(" - {}", p.describe()));
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
                    self.latest_bytes = live.surface.bytes(&pass.image);
                }
                self.latest = Some(pass);
                self.save_if_ready();
                if let Some(live) = &self.live {
                    live.window.request_redraw();
                }
                // Playing: this frame has been shown; on to the next.
                if self.playback.as_ref().is_some_and(|p| p.playing) {
                    self.step(1, event_loop);
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
            event => {
                if let Some(action) = self.pointer.action(&event) {
                    self.act(action, event_loop);
                }
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        self.step_script(event_loop);
        event_loop.set_control_flow(ControlFlow::Wait);
    }
}
