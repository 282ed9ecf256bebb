//! The process's renderer for `gpurt.render`: for each backend asked for ("auto", "gpu"),
//! what `session::choose` found, kept from the first call to the next, so that a notebook
//! calling `gpurt.render` in a loop opens one device and compiles its pipelines once (a
//! `Renderer` keeps a device of its own). A GPU whose render fails (a lost device, memory
//! that ran out) is dropped, and the next call opens a new one rather than use it again;
//! `gpurt.release()` drops them at once, and exit does.
//!
//! Calls wait their turn for the kept GPU, without the GIL; CPU renders do not wait.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

use gpurt::film::Film;
use gpurt::gpu_types::GpuGlobals;
use gpurt::pack::SceneBuffers;
use gpurt::session::{self, Backend, CpuRenderer, GpuSession, Missing, Renderer};
use pyo3::prelude::*;

use crate::frames::{lock_detached, trace, warn_note};
use crate::to_py;

/// What was found for a backend: a GPU session (its device and compiled pipelines), or
/// the CPU, with the warning a missing GPU gives (`--backend gpu` falls back so).
enum Kept {
    Gpu(Box<GpuSession>),
    Cpu(Option<String>),
}

/// What each of "auto" and "gpu" found.
struct Shared {
    auto: Option<Kept>,
    gpu: Option<Kept>,
}

static SHARED: Mutex<Shared> = Mutex::new(Shared {
    auto: None,
    gpu: None,
});

/// GPU sessions opened for `gpurt.render` in this process (what `_devices_opened` tells the
/// tests: one for any number of calls, one more after a failure or `release`).
static OPENED: AtomicU32 = AtomicU32::new(0);

/// Renders `globals` of `buffers` on what `backend` finds, kept for the next call.
pub fn render(
    py: Python<'_>,
    buffers: SceneBuffers,
    backend: Backend,
    globals: &GpuGlobals,
) -> PyResult<Film> {
    let buffers = Arc::new(buffers);
    let mut guard = lock_detached(py, &SHARED);
    let slot = match backend {
        Backend::Gpu => &mut guard.gpu,
        _ => &mut guard.auto,
    };
    if slot.is_none() {
        let found = py
            .detach(|| session::choose(backend, None, Missing::Cpu))
            .map_err(to_py)?;
        let note = found.note.filter(|n| n.warning).map(|n| n.text);
        *slot = Some(match found.gpu {
            Some(ctx) => {
                let session = GpuSession::new(ctx, buffers.clone()).map_err(to_py)?;
                OPENED.fetch_add(1, Ordering::Relaxed);
                Kept::Gpu(Box::new(session))
            }
            None => Kept::Cpu(note),
        });
    }
    let traced = match slot.as_mut().expect("filled above") {
        Kept::Gpu(session) => {
            session.set_scene(buffers);
            trace(py, session.as_mut(), globals)
        }
        Kept::Cpu(note) => {
            if let Some(text) = note {
                warn_note(py, text)?;
            }
            let cpu = &mut CpuRenderer::new(buffers);
            drop(guard);
            return Ok(trace(py, cpu, globals)?.map_err(to_py)?.film);
        }
    };
    match traced {
        Ok(Ok(rendered)) => Ok(rendered.film),
        // The device may be lost or its memory spent: the next call opens a new one.
        Ok(Err(e)) => {
            *slot = None;
            Err(to_py(e))
        }
        Err(interrupt) => Err(interrupt),
    }
}

/// `gpurt.release()`: drops the kept devices (and the scene each holds); the next render
/// opens what it needs again.
#[pyfunction]
pub fn release(py: Python<'_>) {
    let mut guard = lock_detached(py, &SHARED);
    (guard.auto, guard.gpu) = (None, None);
}

/// GPU sessions `gpurt.render` has opened in this process (for the tests).
#[pyfunction]
pub fn _devices_opened() -> u32 {
    OPENED.load(Ordering::Relaxed)
}
