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
                        backend="auto", shading=None, aov=None))]
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
        render_scene(py, self.scene.clone(), &frame, backend)
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
/// highlight's model as `--shading` takes it. The GIL is released while
/// rendering, and Ctrl-C stops the render with KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (scene, *, width=None, height=None, spp=None, depth=None, ambient=None,
                    backend="auto", shading=None, aov=None))]
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
    let scene = scene.load(py)?;
    render_scene(py, scene, &frame, backend)
}

/// `Scene.open(path).info()`: the dict `gpurt info --json` prints for the file.
#[pyfunction]
pub fn info<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    info_dict(py, &load(py, &path)?)
}
