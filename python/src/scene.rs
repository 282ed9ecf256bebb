//! `gpurt.Scene` (a parsed scene: its `info()`, its `render()`), and the shortcuts
//! `gpurt.render(path, ...)` and `gpurt.info(path)`.

use std::path::{Path, PathBuf};

use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::pack;
use gpurt::scene::{self, io::FileKind};
use gpurt::session::Backend;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::pybacked::{PyBackedBytes, PyBackedStr};

use crate::frames::Frames;
use crate::options::{self, Frame};
use crate::shared;
use crate::{film_to_numpy, to_py};

/// A scene read from a file or a string: NFF (with the P3D dialect), STL, OBJ, PLY or glTF.
/// Render it with `render()`, or many frames of it with `gpurt.Renderer(scene, ...)`.
#[pyclass(module = "gpurt", frozen)]
pub struct Scene {
    pub scene: scene::Scene,
}

/// The text or bytes `Scene.from_string` reads.
#[derive(FromPyObject)]
enum Source {
    Text(PyBackedStr),
    Bytes(PyBackedBytes),
}

/// What a path argument names: a path (str or os.PathLike) or a `Scene` already read.
#[derive(FromPyObject)]
pub enum SceneArg<'py> {
    Scene(Bound<'py, Scene>),
    Path(PathBuf),
}

impl SceneArg<'_> {
    /// The scene, read with the GIL released when it is a path.
    pub fn load(self, py: Python<'_>) -> PyResult<scene::Scene> {
        match self {
            SceneArg::Scene(s) => Ok(s.get().scene.clone()),
            SceneArg::Path(path) => load(py, &path),
        }
    }
}

fn load(py: Python<'_>, path: &Path) -> PyResult<scene::Scene> {
    py.detach(|| scene::load(path)).map_err(to_py)
}

/// The scene as `gpurt info --json` prints it, as a Python dict (through `json.loads`, so
/// that the two are the same value). `info` reads records, so the scene is copied into them.
fn info_dict<'py>(py: Python<'py>, scene: &scene::Scene) -> PyResult<Bound<'py, PyAny>> {
    let flat = scene::FlatScene::from_scene(scene.clone());
    let text = gpurt::info::to_json(&flat).to_string();
    py.import("json")?.call_method1("loads", (text,))
}

/// A film as a `gpurt.Image`: the numpy array the film moved into, viewed as the ndarray
/// subclass that shows itself in Jupyter, with its AOV's name.
pub fn image<'py>(py: Python<'py>, film: Film, aov: Option<&str>) -> PyResult<Bound<'py, PyAny>> {
    let array = film_to_numpy(py, film);
    let class = py.import("gpurt")?.getattr("Image")?;
    let image = array.call_method1("view", (class,))?;
    image.setattr("aov", aov)?;
    Ok(image)
}

/// One frame of `scene` as the command line renders it: packed for the frame's samples
/// (which picks the BVH's quality), on the backend chosen, from the scene's camera.
pub fn render_scene<'py>(
    py: Python<'py>,
    scene: scene::Scene,
    frame: &Frame<'_, 'py>,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let backend = options::backend(backend)?;
    let overrides = frame.overrides()?;
    let opts = RenderOptions::for_camera(&scene.camera).with_overrides(&overrides);
    let buffers = py
        .detach(|| pack::pack_for(scene, opts.samples()))
        .map_err(to_py)?;
    let globals = frame::globals(&buffers, &opts);
    let film = match backend {
        Backend::Cpu => Frames::open(py, buffers, backend)?.render(py, &globals)?,
        // The process's device, kept between calls (`shared`).
        _ => shared::render(py, buffers, backend, &globals)?,
    };
    image(py, film, frame.aov)
}

#[pymethods]
impl Scene {
    /// Reads a scene file (str or os.PathLike): NFF, STL, OBJ, PLY or glTF by its first bytes or
    /// extension, gzip too. A malformed file raises `SceneError` with `FILE:LINE:COL: message`.
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
        Ok(Scene {
            scene: load(py, &path)?,
        })
    }

    /// Reads a scene from a string (or bytes, for binary STL) in `format`: "nff" (and its
    /// P3D dialect), "stl", "obj", "ply" or "gltf" (JSON or .glb bytes). `name` names it in error messages; an NFF `mesh`
    /// include is looked for in the current directory.
    #[staticmethod]
    #[pyo3(signature = (text, format = "nff", name = "<string>"))]
    fn from_string(py: Python<'_>, text: Source, format: &str, name: &str) -> PyResult<Scene> {
        let kind = match format {
            "nff" | "p3d" => FileKind::Nff,
            "stl" => FileKind::Stl,
            "obj" => FileKind::Obj,
            "ply" => FileKind::Ply,
            "gltf" => FileKind::Gltf,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "format must be 'nff', 'p3d', 'stl', 'obj', 'ply' or 'gltf', got {format:?}"
                )));
            }
        };
        let bytes: &[u8] = match &text {
            Source::Text(t) => t.as_bytes(),
            Source::Bytes(b) => b,
        };
        let scene = py
            .detach(|| scene::parse(bytes, kind, name, Path::new(".")))
            .map_err(to_py)?;
        Ok(Scene { scene })
    }

    /// What the scene holds, as the dict `gpurt info --json` prints: camera, resolution,
    /// background, ambient, bounds, counts, lights, materials, warnings.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        info_dict(py, &self.scene)
    }

    /// The name the scene's messages use (its path, or `name` of `from_string`).
    #[getter]
    fn name(&self) -> &str {
        &self.scene.name
    }

    /// The reader's warnings (what it dropped or clamped), each naming its line.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    /// Renders the scene from its own camera: see `gpurt.render`.
    #[pyo3(signature = (*, width=None, height=None, spp=None, depth=None, ambient=None,
                        backend="auto", shading=None, aov=None, time=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: Option<i64>,
        height: Option<i64>,
        spp: Option<i64>,
        depth: Option<i64>,
        ambient: Option<&Bound<'py, PyAny>>,
        backend: &str,
        shading: Option<&str>,
        aov: Option<&str>,
        time: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let frame = Frame {
            width,
            height,
            spp,
            depth,
            ambient,
            aov,
            shading,
        };
        let scene = at_time(self.scene.clone(), time)?;
        render_scene(py, scene, &frame, backend)
    }

    /// The animation's time range and frame count, `(start, end, frames)`, for a scene
    /// that moves (AFF with an `a` statement); None otherwise.
    #[getter]
    fn time_range(&self) -> Option<(f64, f64, u32)> {
        let range = self.scene.animation.as_ref()?.range?;
        Some((range.start, range.end, range.frames))
    }

    /// The time of frame `frame` (counted from 0) of the animation.
    fn frame_time(&self, frame: u32) -> PyResult<f64> {
        match self.scene.animation.as_ref().and_then(|a| a.range) {
            Some(r) if frame < r.frames => Ok(r.time(frame)),
            Some(r) => Err(PyValueError::new_err(format!(
                "frame {frame} is outside the animation, whose {} frames are 0..{}",
                r.frames,
                r.frames - 1
            ))),
            None => Err(not_animated(&self.scene)),
        }
    }

    /// The scene as it is at `time`: a still scene (what moves placed, the camera
    /// moved), for `gpurt.Renderer` to render many views of one moment.
    fn at(&self, time: f64) -> PyResult<Scene> {
        Ok(Scene {
            scene: at_time(self.scene.clone(), Some(time))?,
        })
    }

    fn __repr__(&self) -> String {
        let s = &self.scene;
        format!(
            "<gpurt.Scene {:?}: {} spheres, {} triangles, {} planes, {} cones, {} boxes, {} lights>",
            s.name,
            s.spheres.len(),
            s.triangles.len(),
            s.planes.len(),
            s.cones.len(),
            s.boxes.len(),
            s.lights.len()
        )
    }
}

/// Renders a scene (a path, str or os.PathLike, or a `Scene`) into a `gpurt.Image`: a
/// float32 numpy array of shape (height, width, 3) holding the linear values the command
/// line's EXR of the same render holds. `None` keeps the scene's resolution and the
/// defaults (1 sample per pixel, depth 5, the scene's ambient). `backend` is "auto" (the
/// GPU when there is a hardware one, else the CPU), "gpu" or "cpu"; `aov` is None,
/// "normal", "depth", "cost" or "uv"; `shading` is None (Phong), "phong" or "blinn-phong", the
/// highlight's model as `--shading` takes it; `time` renders a scene that moves (AFF) as
/// it is at that time (default: the start of its range). The GIL is released while
/// rendering, and Ctrl-C stops the render with KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (scene, *, width=None, height=None, spp=None, depth=None, ambient=None,
                    backend="auto", shading=None, aov=None, time=None))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: SceneArg<'py>,
    width: Option<i64>,
    height: Option<i64>,
    spp: Option<i64>,
    depth: Option<i64>,
    ambient: Option<&Bound<'py, PyAny>>,
    backend: &str,
    shading: Option<&str>,
    aov: Option<&str>,
    time: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let frame = Frame {
        width,
        height,
        spp,
        depth,
        ambient,
        aov,
        shading,
    };
    // Checked before the scene is read, so that a bad argument costs nothing.
    frame.overrides()?;
    options::backend(backend)?;
    let scene = at_time(scene.load(py)?, time)?;
    render_scene(py, scene, &frame, backend)
}

/// The ValueError for a time given for a scene where nothing moves.
fn not_animated(scene: &scene::Scene) -> PyErr {
    PyValueError::new_err(format!(
        "{}: time is for scenes that move (AFF), and nothing moves in this one",
        scene.name
    ))
}

/// `scene` at `time` where one is given (an error for a scene that does not move, or a
/// time that is not finite); as it is otherwise (packing places a moving scene at its
/// start).
fn at_time(scene: scene::Scene, time: Option<f64>) -> PyResult<scene::Scene> {
    match time {
        None => Ok(scene),
        Some(t) if !t.is_finite() => Err(PyValueError::new_err(format!(
            "time must be a finite number, got {t}"
        ))),
        Some(_) if scene.animation.is_none() => Err(not_animated(&scene)),
        Some(t) => Ok(scene.at(t)),
    }
}

/// `Scene.open(path).info()`: the dict `gpurt info --json` prints for the file.
#[pyfunction]
pub fn info<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    info_dict(py, &load(py, &path)?)
}
