//! `gpurt.Renderer`: one scene read, packed and (on the GPU) uploaded once, and any number
//! of frames of it, each from the scene's camera or one the call gives. The library's
//! `session::Renderer` does the work; this keeps it between calls.

use std::sync::{Mutex, MutexGuard};

use gpurt::frame::{self, Overrides, RenderOptions};
use gpurt::pack;
use gpurt::scene::Camera;
use pyo3::prelude::*;

use crate::frames::{Frames, lock_detached};
use crate::options::{self, Frame};
use crate::scene::{SceneArg, image};
use crate::to_py;

/// A session for many frames of one scene: `Renderer(scene, width=.., height=..,
/// backend=..)` reads and packs the scene once (and uploads it once, on the first frame on
/// the GPU); `render(spp=.., camera=dict(eye=.., look_at=.., up=.., fov=..))` traces a
/// frame. A camera sweep of 100 frames costs 100 frames, not 100 loads.
#[pyclass(module = "gpurt", frozen)]
pub struct Renderer {
    frames: Mutex<Frames>,
    /// The scene's own camera: what a frame without `camera=` sees, and what a camera
    /// dict's missing keys keep.
    camera: Camera,
    /// What the constructor set over the scene's camera and the defaults.
    base: Overrides,
}

impl Renderer {
    /// The renderer's frames, once no other thread is rendering with them: calls from
    /// several threads wait their turn, without the GIL.
    fn frames(&self, py: Python<'_>) -> MutexGuard<'_, Frames> {
        lock_detached(py, &self.frames)
    }
}

#[pymethods]
impl Renderer {
    /// Reads (when `scene` is a path) and packs the scene for frames of this size (the
    /// scene's resolution by default) on `backend` ("auto", "gpu" or "cpu"). `spp`,
    /// `depth`, `ambient` and `shading` ("phong" or "blinn-phong") are the frames'
    /// defaults; `spp` also picks the BVH's build quality, as on the command line.
    #[new]
    #[pyo3(signature = (scene, *, width=None, height=None, spp=None, depth=None, ambient=None,
                        backend="auto", shading=None))]
    #[allow(clippy::too_many_arguments)]
    fn new<'py>(
        py: Python<'py>,
        scene: SceneArg<'py>,
        width: Option<i64>,
        height: Option<i64>,
        spp: Option<i64>,
        depth: Option<i64>,
        ambient: Option<&Bound<'py, PyAny>>,
        backend: &str,
        shading: Option<&str>,
    ) -> PyResult<Renderer> {
        let frame = Frame {
            width,
            height,
            spp,
            depth,
            ambient,
            aov: None,
            shading,
        };
        let mut base = frame.overrides()?;
        base.aov = None;
        let backend = options::backend(backend)?;
        let scene = scene.load(py)?;
        let camera = scene.camera.clone();
        let samples = RenderOptions::for_camera(&camera)
            .with_overrides(&base)
            .samples();
        let buffers = py
            .detach(|| pack::pack_for(scene, samples))
            .map_err(to_py)?;
        Ok(Renderer {
            frames: Mutex::new(Frames::open(py, buffers, backend)?),
            camera,
            base,
        })
    }

    /// Traces one frame into a `gpurt.Image` (float32, (height, width, 3), linear).
    /// `camera` is a dict with any of `eye`, `look_at`, `up` (three numbers each) and `fov`
    /// (the vertical angle in degrees); what it leaves out is the scene's. Only the frame's
    /// constants change between frames: the scene stays uploaded. `shading` (None keeps
    /// the renderer's) is "phong" or "blinn-phong".
    #[pyo3(signature = (*, spp=None, depth=None, ambient=None, aov=None, shading=None,
                        camera=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        spp: Option<i64>,
        depth: Option<i64>,
        ambient: Option<&Bound<'py, PyAny>>,
        aov: Option<&str>,
        shading: Option<&str>,
        camera: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let frame = Frame {
            spp,
            depth,
            ambient,
            aov,
            shading,
            ..Frame::default()
        };
        let overrides = options::layer(&self.base, &frame.overrides()?);
        let opts = RenderOptions::for_camera(&self.camera).with_overrides(&overrides);
        // The scene's own camera frames a bare mesh again for the frame's size, as
        // `frame::globals` does for the command line; a camera given here is used as is.
        let camera = match camera {
            Some(dict) => options::camera(&self.camera, dict)?,
            None => gpurt::scene::auto::fitted(&self.camera, opts.width, opts.height),
        };
        let mut frames = self.frames(py);
        let globals = frame::globals_from(&frames.buffers, &camera, &opts);
        let film = frames.render(py, &globals)?;
        image(py, film, aov)
    }

    /// "gpu" or "cpu": where this renderer traces.
    #[getter]
    fn backend(&self, py: Python<'_>) -> &'static str {
        self.frames(py).backend()
    }

    /// One line naming what renders: the adapter, or the CPU and its threads.
    #[getter]
    fn device(&self, py: Python<'_>) -> String {
        self.frames(py).describe()
    }

    /// How many times the scene went to the GPU (1 after any number of frames), or None
    /// on the CPU, which traces the packed scene where it is.
    #[getter]
    fn scene_uploads(&self, py: Python<'_>) -> Option<u32> {
        self.frames(py).scene_uploads()
    }

    /// How many frames this renderer has traced.
    #[getter]
    fn frames_rendered(&self, py: Python<'_>) -> u64 {
        self.frames(py).frames
    }

    /// Rays the last frame traced (eye, shadow and secondary), as `gpurt --stats` counts.
    #[getter]
    fn rays(&self, py: Python<'_>) -> u64 {
        self.frames(py).rays
    }

    /// (width, height) of the frames.
    #[getter]
    fn size(&self) -> (u32, u32) {
        let opts = RenderOptions::for_camera(&self.camera).with_overrides(&self.base);
        (opts.width, opts.height)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let (w, h) = self.size();
        format!("<gpurt.Renderer {w}x{h} on {}>", self.frames(py).describe())
    }
}
