//! What the viewer's actions do in the window: a camera move or a new mode starts a new
//! view, a step or play moves an animated scene to another frame, `P` saves the image once
//! the view has its samples, and a `--script` is replayed up to its next wait.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use winit::event_loop::ActiveEventLoop;

use super::App;
use crate::view::controls::Action;
use crate::view::script::Event;
use crate::{film, outln};

impl App {
    pub(super) fn act(&mut self, action: Action, event_loop: &ActiveEventLoop) {
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
            Action::Play => {
                if let Some(p) = &mut self.playback {
                    p.playing = !p.playing;
                    // Playing moves on from a frame once it has a pass.
                    if p.playing && self.latest.is_some() {
                        self.step(1, event_loop);
                    } else if let Some(live) = &self.live {
                        live.window.request_redraw();
                    }
                }
            }
            Action::Step(by) => self.step(by.into(), event_loop),
            Action::Quit => event_loop.exit(),
        }
    }

    /// Shows the frame `by` frames on of an animated scene (nothing for a still one): its
    /// scene packed and handed to the tracer and the wireframe, the view following its
    /// camera unless the view was moved away from it.
    pub(super) fn step(&mut self, by: i64, event_loop: &ActiveEventLoop) {
        let Some(playback) = &mut self.playback else {
            return;
        };
        playback.step(by);
        let buffers = match playback.buffers() {
            Ok(b) => Arc::new(b),
            Err(e) => return self.fail(e, event_loop),
        };
        self.camera.follow(buffers.camera.clone());
        if let Some(live) = &mut self.live {
            if let Err(e) = live.surface.set_scene(&buffers) {
                return self.fail(e, event_loop);
            }
            live.tracer.set_scene(buffers.clone());
        }
        self.buffers = buffers;
        self.restart();
    }

    /// Writes the image `P` asked for: with `--spp N` once the view has its N samples,
    /// else at once, with the samples it has (without a cap a view converges for hours).
    pub(super) fn save_if_ready(&mut self) {
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

    /// Replays the script up to its next wait; when it is over, asks for the screenshot
    /// once the view has its samples.
    pub(super) fn step_script(&mut self, event_loop: &ActiveEventLoop) {
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
}
