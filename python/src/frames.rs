//! A packed scene on the renderer chosen for it, and its frames traced with the GIL
//! released: the render runs on a thread of its own while the calling thread waits without
//! the GIL, waking every few milliseconds to let Python's signal handlers run; a
//! KeyboardInterrupt there cancels the render (the library's `cancel` flag) and is raised
//! once the render has stopped.

use std::ffi::CString;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError, TryLockError};
use std::time::Duration;

use gpurt::film::Film;
use gpurt::gpu_types::GpuGlobals;
use gpurt::pack::SceneBuffers;
use gpurt::run;
use gpurt::session::{self, Backend, CpuRenderer, GpuSession, Missing, Renderer};
use pyo3::exceptions::{PyRuntimeError, PyRuntimeWarning};
use pyo3::prelude::*;

use crate::to_py;

/// How often the waiting thread takes the GIL back to run Python's signal handlers.
const SIGNAL_POLL: Duration = Duration::from_millis(20);

/// One packed scene on one renderer: the GPU's device keeps the uploaded scene between
/// frames, so that a sweep of frames pays for one upload.
pub struct Frames {
    renderer: Traced,
    pub buffers: Arc<SceneBuffers>,
    /// Frames rendered, for the counters Python reads.
    pub frames: u64,
    /// Rays the last frame traced, counted as the command line's `--stats` counts them.
    pub rays: u64,
}

/// The renderer, kept by kind so that the GPU's upload counter can be read.
enum Traced {
    Gpu(Box<GpuSession>),
    Cpu(Box<CpuRenderer>),
}

impl Frames {
    /// Chooses the renderer for `backend` as the command line does (`session::choose`; a
    /// missing GPU falls back to the CPU with a RuntimeWarning, as `--backend gpu` warns).
    pub fn open(py: Python<'_>, buffers: SceneBuffers, backend: Backend) -> PyResult<Frames> {
        let buffers = Arc::new(buffers);
        let found = py
            .detach(|| session::choose(backend, None, Missing::Cpu))
            .map_err(to_py)?;
        if let Some(note) = found.note.filter(|n| n.warning) {
            warn_note(py, &note.text)?;
        }
        let renderer = match found.gpu {
            Some(ctx) => Traced::Gpu(Box::new(
                GpuSession::new(ctx, buffers.clone()).map_err(to_py)?,
            )),
            None => Traced::Cpu(Box::new(CpuRenderer::new(buffers.clone()))),
        };
        Ok(Frames {
            renderer,
            buffers,
            frames: 0,
            rays: 0,
        })
    }

    fn renderer(&mut self) -> &mut (dyn Renderer + Send) {
        match &mut self.renderer {
            Traced::Gpu(gpu) => gpu.as_mut(),
            Traced::Cpu(cpu) => cpu.as_mut(),
        }
    }

    /// "gpu" or "cpu": where the frames are traced.
    pub fn backend(&self) -> &'static str {
        match self.renderer {
            Traced::Gpu(_) => "gpu",
            Traced::Cpu(_) => "cpu",
        }
    }

    /// One line naming what renders: the adapter, or the CPU and its threads.
    pub fn describe(&self) -> String {
        match &self.renderer {
            Traced::Gpu(gpu) => gpu.describe(),
            Traced::Cpu(cpu) => cpu.describe(),
        }
    }

    /// How many times the scene's arrays went to the GPU: once for any number of frames
    /// (`None` on the CPU, which traces the packed arrays where they are).
    pub fn scene_uploads(&self) -> Option<u32> {
        match &self.renderer {
            Traced::Gpu(gpu) => Some(gpu.scene_uploads()),
            Traced::Cpu(_) => None,
        }
    }

    /// Renders every sample of `globals` (`trace`).
    pub fn render(&mut self, py: Python<'_>, globals: &GpuGlobals) -> PyResult<Film> {
        let rendered = trace(py, self.renderer(), globals)?.map_err(to_py)?;
        self.frames += 1;
        self.rays = rendered.rays;
        Ok(rendered.film)
    }
}

/// `mutex` locked once no other thread holds it, waited for without the GIL (a render
/// holding it releases the GIL itself). A guard cannot leave `detach`, which needs what
/// it returns to be `Send`: the lock is waited for there, then taken with the GIL held,
/// again if another thread took it meanwhile. A poisoned lock is taken as it is.
pub fn lock_detached<'m, T: Send>(py: Python<'_>, mutex: &'m Mutex<T>) -> MutexGuard<'m, T> {
    loop {
        match mutex.try_lock() {
            Ok(guard) => return guard,
            Err(TryLockError::Poisoned(p)) => return p.into_inner(),
            Err(TryLockError::WouldBlock) => {
                py.detach(|| drop(mutex.lock().unwrap_or_else(PoisonError::into_inner)))
            }
        }
    }
}

/// A note of the renderer's choice that is a warning (no GPU where one was asked for), as
/// a Python RuntimeWarning.
pub fn warn_note(py: Python<'_>, text: &str) -> PyResult<()> {
    let text = CString::new(text).unwrap_or_default();
    PyErr::warn(py, &py.get_type::<PyRuntimeWarning>(), &text, 2)
}

/// Renders every sample of `globals` on `renderer` (the renderer's own frame of it, as the
/// command line renders), with the GIL released: Ctrl-C raises KeyboardInterrupt (the
/// outer error), the library's failure is the inner one.
pub fn trace(
    py: Python<'_>,
    renderer: &mut (dyn Renderer + Send),
    globals: &GpuGlobals,
) -> PyResult<gpurt::Result<run::Rendered>> {
    let globals = renderer.frame(globals);
    let cancel = AtomicBool::new(false);
    let done = AtomicBool::new(false);
    let mut interrupt = None;
    let result = std::thread::scope(|s| {
        let waiter = std::thread::current();
        let (cancel, done, globals) = (&cancel, &done, &globals);
        let tracer = s.spawn(move || {
            let _finish = Finish { done, waiter };
            run::render_frame(renderer, globals, &|_| {}, cancel)
        });
        while !done.load(Ordering::Acquire) {
            py.detach(|| std::thread::park_timeout(SIGNAL_POLL));
            if interrupt.is_none()
                && let Err(e) = py.check_signals()
            {
                // Stop the render, and wait for it to stop before raising.
                cancel.store(true, Ordering::Relaxed);
                interrupt = Some(e);
            }
        }
        tracer.join()
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    result.map_err(|_| PyRuntimeError::new_err("gpurt: the render thread panicked"))
}

/// Wakes the thread waiting on a render when the render's thread ends its work, by
/// returning or by panicking: `done` is set first, then the waiter unparked. (Waiting on
/// the thread's own `is_finished`, which turns true only once the thread has returned
/// after the unpark, could miss it and sleep out a whole `SIGNAL_POLL`: an 8x8 frame
/// took 21 ms instead of 0.5 one time in three.)
struct Finish<'a> {
    done: &'a AtomicBool,
    waiter: std::thread::Thread,
}

impl Drop for Finish<'_> {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Release);
        self.waiter.unpark();
    }
}
