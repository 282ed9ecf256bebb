//! Progressive rendering for the viewer, apart from any window: a worker thread owns a
//! `Renderer` and traces the current view in passes of a few samples each, adding them to
//! one `Accumulator`; a new view (the camera moved) cancels the pass in flight and starts
//! again from no samples. Each finished pass is handed to a callback as an image, so the
//! window shows the view converging while its own thread stays free for input.

use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use image::RgbImage;

use crate::film::Accumulator;
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use crate::session::Renderer;
use crate::util::error::{Error, Result};

/// How long one pass should take: long passes trace more samples per second, short ones
/// answer a moving camera sooner.
const TARGET_PASS: Duration = Duration::from_millis(150);

/// Most samples one pass traces.
const MAX_BATCH: u32 = 64;

/// Which samples the passes of one view trace: a first pass of one sample (the first
/// picture as soon as possible), then batches that double while a pass takes less than
/// half of `TARGET_PASS` and halve while it takes more than twice as long, up to the
/// frame's samples per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    spp: u32,
    done: u32,
    batch: u32,
}

impl Schedule {
    /// The passes of a frame of `spp` samples per pixel.
    pub fn new(spp: u32) -> Self {
        Schedule {
            spp,
            done: 0,
            batch: 1,
        }
    }

    /// The samples the next pass traces; `None` once all `spp` are done.
    pub fn next(&self) -> Option<Range<u32>> {
        (self.done < self.spp).then(|| self.done..(self.done + self.batch).min(self.spp))
    }

    /// Records a pass of `samples` that took `took`, and sizes the next.
    pub fn record(&mut self, samples: Range<u32>, took: Duration) {
        self.done = samples.end;
        if took < TARGET_PASS / 2 {
            self.batch = (self.batch * 2).min(MAX_BATCH);
        } else if took > TARGET_PASS * 2 {
            self.batch = (self.batch / 2).max(1);
        }
    }

    /// Samples per pixel done so far.
    pub fn done(&self) -> u32 {
        self.done
    }
}

/// A view to trace: the frame's constants, numbered so that the results of an older
/// view that arrive late are recognised.
#[derive(Clone, Copy, Debug)]
pub struct Job {
    pub view: u64,
    pub globals: GpuGlobals,
}

/// A finished pass: the view's image so far.
#[derive(Clone, Debug)]
pub struct Pass {
    pub view: u64,
    pub image: RgbImage,
    /// Samples per pixel in `image`.
    pub samples: u32,
    /// Rays traced for the view so far, and the time spent tracing them (shader
    /// compilation excluded).
    pub rays: u64,
    pub trace_time: Duration,
    /// Time spent compiling shaders for this view's first pass (zero once compiled).
    pub compile: Duration,
}

enum Message {
    Trace(Job),
    /// Another scene for the views that follow (an animation's next frame).
    Scene(Arc<SceneBuffers>),
    Pause,
    Stop,
}

/// The worker thread and the way to reach it.
pub struct Tracer {
    jobs: Option<Sender<Message>>,
    cancel: Arc<AtomicBool>,
    worker: Option<JoinHandle<()>>,
}

impl Tracer {
    /// Starts a worker that traces with `renderer` and calls `on_pass` after every pass
    /// (or with the error that stopped a view; the worker then waits for the next).
    pub fn spawn(
        renderer: Box<dyn Renderer + Send>,
        on_pass: impl Fn(Result<Pass>) + Send + 'static,
    ) -> Tracer {
        let (tx, rx) = mpsc::channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let flag = cancel.clone();
        let worker = std::thread::Builder::new()
            .name("gpurt tracer".into())
            .spawn(move || work(renderer, &rx, &flag, &on_pass))
            .expect("a thread can be spawned");
        Tracer {
            jobs: Some(tx),
            cancel,
            worker: Some(worker),
        }
    }

    /// Traces `job` from no samples, abandoning the view in progress.
    pub fn trace(&self, job: Job) {
        self.send(Message::Trace(job));
    }

    /// Traces another scene from the next `trace` on.
    pub fn set_scene(&self, scene: Arc<SceneBuffers>) {
        self.send(Message::Scene(scene));
    }

    /// Stops tracing until the next `trace`.
    pub fn pause(&self) {
        self.send(Message::Pause);
    }

    fn send(&self, message: Message) {
        self.cancel.store(true, Ordering::Relaxed);
        if let Some(jobs) = &self.jobs {
            // A worker that has gone has reported why through `on_pass`.
            let _ = jobs.send(message);
        }
    }
}

impl Drop for Tracer {
    fn drop(&mut self) {
        // A message, not just a closed channel: the worker drains every message before
        // it would see the channel close, and would trace a last pass on the way.
        self.send(Message::Stop);
        drop(self.jobs.take());
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

/// The view being traced.
struct Current {
    job: Job,
    accum: Accumulator,
    schedule: Schedule,
    rays: u64,
    trace_time: Duration,
    compile: Duration,
}

fn work(
    mut renderer: Box<dyn Renderer + Send>,
    rx: &Receiver<Message>,
    cancel: &AtomicBool,
    on_pass: &dyn Fn(Result<Pass>),
) {
    let mut current: Option<Current> = None;
    loop {
        let busy = current
            .as_ref()
            .is_some_and(|c| c.schedule.next().is_some());
        // With nothing to trace, sleep until told; otherwise look for news between passes.
        let mut message = if busy {
            match rx.try_recv() {
                Ok(m) => Some(m),
                Err(TryRecvError::Empty) => None,
                Err(TryRecvError::Disconnected) => return,
            }
        } else {
            match rx.recv() {
                Ok(m) => Some(m),
                Err(_) => return,
            }
        };
        if message.is_some() {
            // Only the newest message matters, but for scenes, each taken in turn; the
            // flag is cleared before looking, so a message sent from here on cancels the
            // next pass.
            cancel.store(false, Ordering::Relaxed);
            let mut newest = message.take();
            loop {
                match newest {
                    Some(Message::Scene(scene)) => {
                        renderer.set_scene(scene);
                        newest = None;
                    }
                    other => message = other.or(message),
                }
                match rx.try_recv() {
                    Ok(m) => newest = Some(m),
                    Err(_) => break,
                }
            }
        }
        match message {
            Some(Message::Trace(job)) => {
                let (w, h) = (job.globals.width, job.globals.height);
                current = Some(Current {
                    job,
                    accum: Accumulator::new(w, h),
                    schedule: Schedule::new(job.globals.spp),
                    rays: 0,
                    trace_time: Duration::ZERO,
                    compile: Duration::ZERO,
                });
            }
            Some(Message::Pause) => current = None,
            Some(Message::Stop) => return,
            // Scenes were taken in turn above.
            Some(Message::Scene(_)) | None => {}
        }
        let Some(cur) = current.as_mut() else {
            continue;
        };
        let Some(samples) = cur.schedule.next() else {
            continue;
        };
        match pass(renderer.as_mut(), cur, samples, cancel) {
            Ok(()) => on_pass(Ok(Pass {
                view: cur.job.view,
                image: cur.accum.film().to_rgb8(),
                samples: cur.accum.samples,
                rays: cur.rays,
                trace_time: cur.trace_time,
                compile: std::mem::take(&mut cur.compile),
            })),
            // Cancelled for a newer message, which the loop picks up next.
            Err(Error::Interrupted) => {}
            Err(e) => {
                current = None;
                on_pass(Err(e));
            }
        }
    }
}

/// Traces one pass of the current view.
fn pass(
    renderer: &mut dyn Renderer,
    cur: &mut Current,
    samples: Range<u32>,
    cancel: &AtomicBool,
) -> Result<()> {
    let g = cur.job.globals;
    cur.compile += renderer.prepare(&g)?;
    let start = Instant::now();
    let rays = renderer.render(&g, samples.clone(), &mut cur.accum, &|_| {}, cancel)?;
    let took = start.elapsed();
    cur.schedule.record(samples, took);
    cur.rays += rays;
    cur.trace_time += took;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{self, RenderOptions};
    use crate::session::CpuRenderer;
    use std::sync::Mutex;

    #[test]
    fn batches_grow_while_fast_shrink_while_slow_and_stop_at_the_frame_spp() {
        let mut s = Schedule::new(10);
        assert_eq!(s.next(), Some(0..1));
        s.record(0..1, Duration::ZERO);
        assert_eq!(s.next(), Some(1..3));
        s.record(1..3, Duration::ZERO);
        assert_eq!(s.next(), Some(3..7));
        s.record(3..7, TARGET_PASS * 3);
        assert_eq!(s.next(), Some(7..9));
        s.record(7..9, TARGET_PASS);
        assert_eq!(s.next(), Some(9..10), "clipped to the frame");
        s.record(9..10, Duration::ZERO);
        assert_eq!((s.next(), s.done()), (None, 10));
        let mut s = Schedule::new(crate::util::limits::MAX_SPP);
        for _ in 0..20 {
            let r = s.next().unwrap();
            s.record(r, Duration::ZERO);
        }
        assert_eq!(s.next().unwrap().len() as u32, MAX_BATCH);
    }

    fn scene() -> Arc<crate::pack::SceneBuffers> {
        let src = b"v from 0 -6 2 at 0 0 0 up 0 0 1 angle 40 resolution 24 16
            b 0.1 0.2 0.3  l 2 -4 5  f 1 0.5 0.2 0.7 0.3 20 0.2 1.3  s 0 0 0 1
            f 0.3 0.8 0.3 1 0 1 0 0  p 3 -4 -4 -1  4 -4 -1  0 4 -1";
        let s = crate::scene::nff::parse(src, "t", std::path::Path::new(".")).unwrap();
        Arc::new(crate::pack::pack(s).unwrap())
    }

    /// Runs a tracer on the CPU and collects what it reports.
    fn tracer(buffers: &Arc<crate::pack::SceneBuffers>) -> (Tracer, Arc<Mutex<Vec<Pass>>>) {
        let passes = Arc::new(Mutex::new(Vec::new()));
        let sink = passes.clone();
        let t = Tracer::spawn(Box::new(CpuRenderer::new(buffers.clone())), move |p| {
            sink.lock().unwrap().push(p.expect("the pass traces"))
        });
        (t, passes)
    }

    fn wait_for(passes: &Mutex<Vec<Pass>>, done: impl Fn(&[Pass]) -> bool) {
        let start = Instant::now();
        while !done(&passes.lock().unwrap()) {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "the tracer stalled"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn passes_add_up_to_the_one_step_image_and_a_new_view_starts_again() {
        let buffers = scene();
        let opts = RenderOptions {
            spp: 7,
            ..RenderOptions::for_camera(&buffers.camera)
        };
        let g = frame::globals(&buffers, &opts);
        let (t, passes) = tracer(&buffers);
        t.trace(Job {
            view: 1,
            globals: g,
        });
        wait_for(&passes, |p| p.last().is_some_and(|p| p.samples == 7));
        // One step, as the offline render does it.
        let whole = crate::commands::run::render_frame(
            &mut CpuRenderer::new(buffers.clone()),
            &g,
            &|_| {},
            &AtomicBool::new(false),
        )
        .unwrap();
        {
            let p = passes.lock().unwrap();
            assert_eq!(p[0].samples, 1, "the first picture comes after one sample");
            assert!(p.windows(2).all(|w| w[0].samples < w[1].samples));
            let last = p.last().unwrap();
            assert_eq!(last.image, whole.film.to_rgb8(), "to the bit on the CPU");
            assert_eq!(last.rays, whole.rays);
        }
        // A moved camera restarts from no samples, under its own number.
        let mut moved = g;
        moved.cam_pos.x += 0.5;
        passes.lock().unwrap().clear();
        t.trace(Job {
            view: 2,
            globals: moved,
        });
        wait_for(&passes, |p| p.last().is_some_and(|p| p.samples == 7));
        let p = passes.lock().unwrap();
        assert_eq!(p[0].samples, 1);
        assert!(p.iter().all(|p| p.view == 2));
        assert_ne!(p.last().unwrap().image, whole.film.to_rgb8());
    }

    /// A paused tracer reports no pass although its frame is far from done (a frame that
    /// had finished would report none either); told to trace again, the same worker goes
    /// on (the control: the quiet was the pause); dropped while busy, it stops within
    /// seconds (a worker that never stopped would otherwise hang the test) and has let go
    /// of its callback.
    #[test]
    fn a_paused_tracer_traces_nothing_and_dropping_it_stops_the_worker() {
        let buffers = scene();
        let spp = crate::util::limits::MAX_SPP;
        let g = frame::globals(
            &buffers,
            &RenderOptions {
                spp,
                ..RenderOptions::for_camera(&buffers.camera)
            },
        );
        let (t, passes) = tracer(&buffers);
        t.trace(Job {
            view: 1,
            globals: g,
        });
        wait_for(&passes, |p| !p.is_empty());
        t.pause();
        std::thread::sleep(Duration::from_millis(50));
        let n = passes.lock().unwrap().len();
        std::thread::sleep(Duration::from_millis(200));
        {
            let p = passes.lock().unwrap();
            assert_eq!(p.len(), n, "paused");
            let done = p[n - 1].samples;
            assert!(done < spp / 2, "{done} of {spp} samples before the pause");
        }
        t.trace(Job {
            view: 2,
            globals: g,
        });
        wait_for(&passes, |p| {
            p.len() > n && p[n..].iter().all(|p| p.view == 2)
        });
        let (stopped, done) = mpsc::channel();
        std::thread::spawn(move || {
            drop(t);
            let _ = stopped.send(());
        });
        done.recv_timeout(Duration::from_secs(30))
            .expect("dropping a busy tracer stops its worker");
        assert_eq!(
            Arc::strong_count(&passes),
            1,
            "the worker kept its callback"
        );
    }
}
