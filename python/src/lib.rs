//! `gpurt._native`: the compiled half of the Python module `gpurt`. A way in over the
//! library (`scene`, `run::read` and `run::pack`, `frame`, `session::Renderer`, `film`); it adds
//! no rendering of its own. The pure-Python half (`gpurt/__init__.py`) holds `Image`, the
//! ndarray that shows itself in Jupyter.
//!
//! - `scene`: `Scene` (a parsed scene), `render` and `info`, the one-call shortcuts;
//! - `renderer`: `Renderer`, one uploaded scene and many frames;
//! - `options`: Python arguments into the library's `Overrides`, `Backend` and `Camera`;
//! - `frames`: a frame traced with the GIL released and Ctrl-C watched, into numpy;
//! - `shared`: the device `render` keeps between calls.

mod frames;
mod options;
mod renderer;
mod scene;
mod shared;

use gpurt::Error;
use gpurt::film::{self, Film};
use numpy::ndarray::Array3;
use numpy::{PyArray3, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{
    PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyPermissionError, PyRuntimeError,
    PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

create_exception!(
    gpurt,
    SceneError,
    PyValueError,
    "A scene that cannot be read: its message is the command line's `FILE:LINE:COL: message`; \
     `path`, `line`, `column` and `reason` hold its parts (`line` and `column` None where the \
     fault has no place in the text, `offset` the byte of a binary STL's)."
);

/// The Python exception for a library error: a scene's fault is a `SceneError` with the
/// command line's message, a file that cannot be read an `OSError` of its kind, a frame the
/// scene cannot trace a `ValueError`, a missing or failing GPU a `RuntimeError`.
pub(crate) fn to_py(e: Error) -> PyErr {
    let msg = e.to_string();
    match &e {
        Error::Parse {
            file,
            line,
            col,
            msg: reason,
            ..
        } => scene_error(msg, file, (Some(*line), Some(*col), None), reason),
        Error::Binary {
            file,
            offset,
            msg: reason,
        } => scene_error(msg, file, (None, None, Some(*offset)), reason),
        Error::Scene { file, msg: reason } => scene_error(msg, file, (None, None, None), reason),
        Error::Io { source, .. } => match source.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
            _ => PyOSError::new_err(msg),
        },
        Error::Render(_) | Error::Image(_) => PyValueError::new_err(msg),
        Error::Interrupted => PyKeyboardInterrupt::new_err(msg),
        Error::NoAdapter(_) | Error::Gpu(_) | Error::NoDisplay(_) => PyRuntimeError::new_err(msg),
    }
}

/// A `SceneError` with `message` and its parts as attributes, so that callers need not
/// take the message apart: `path`, `line`, `column`, `offset` and `reason`.
fn scene_error(
    message: String,
    path: &str,
    (line, column, offset): (Option<u32>, Option<u32>, Option<u64>),
    reason: &str,
) -> PyErr {
    let err = SceneError::new_err(message);
    Python::attach(|py| {
        let value = err.value(py);
        let set = || -> PyResult<()> {
            value.setattr("path", path)?;
            value.setattr("line", line)?;
            value.setattr("column", column)?;
            value.setattr("offset", offset)?;
            value.setattr("reason", reason)
        };
        // Setting an attribute on a fresh exception cannot fail; if it did, the message
        // still says everything.
        let _ = set();
    });
    err
}

/// `array` as a C-contiguous float32 array of shape (H, W, 3), converting what numpy can.
fn float_image<'py>(array: &Bound<'py, PyAny>) -> PyResult<PyReadonlyArray3<'py, f32>> {
    let numpy = array.py().import("numpy")?;
    let converted = numpy.call_method1("ascontiguousarray", (array, "float32"))?;
    let image = converted.cast_into::<PyArray3<f32>>().map_err(|_| {
        PyValueError::new_err("expected an image array of shape (height, width, 3)")
    })?;
    if image.shape()[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "expected an image array of shape (height, width, 3), got {:?}",
            image.shape()
        )));
    }
    Ok(image.readonly())
}

/// The 8-bit image the command line writes as PNG for these linear values: each channel
/// clamped to [0, 1], scaled by 255 and rounded (gpurt's images carry no transfer
/// curve: see the shading model). Returns a new uint8 array of the same shape.
#[pyfunction]
fn to_srgb8<'py>(array: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let image = float_image(array)?;
    let view = image.as_array();
    let bytes = view.mapv(film::quantize);
    Ok(PyArray3::from_owned_array(array.py(), bytes))
}

/// The PNG file (bytes) the command line writes for these linear values and AOV: depth
/// as grey and cost as a heat ramp, scaled by their largest value; colour and normals as
/// they are. Used by `Image._repr_png_`.
#[pyfunction]
#[pyo3(signature = (array, aov=None))]
fn png<'py>(
    py: Python<'py>,
    array: &Bound<'py, PyAny>,
    aov: Option<&str>,
) -> PyResult<Bound<'py, PyBytes>> {
    let aov = options::aov_code(aov)?;
    let image = float_image(array)?;
    let view = image.as_array();
    let (height, width) = (view.shape()[0], view.shape()[1]);
    let pixels = view
        .as_standard_layout()
        .as_slice()
        .expect("standard layout")
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let film = Film {
        width: width as u32,
        height: height as u32,
        pixels,
    };
    let bytes = film::encode_png(&film.for_display(aov).to_rgb8()).map_err(to_py)?;
    Ok(PyBytes::new(py, &bytes))
}

/// A film moved into a numpy array of shape (H, W, 3), float32, without copying its
/// pixels: the Vec of `[f32; 3]` is flattened in place and handed to numpy as its buffer.
pub(crate) fn film_to_numpy(py: Python<'_>, film: Film) -> Bound<'_, PyArray3<f32>> {
    let shape = (film.height as usize, film.width as usize, 3);
    let values = film.pixels.into_flattened();
    let array = Array3::from_shape_vec(shape, values).expect("a film holds width * height pixels");
    PyArray3::from_owned_array(py, array)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Mesa's device-select layer off before any GPU instance: no stray lines on stderr.
    gpurt::gpu::quiet_device_select();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    let scene_error = m.py().get_type::<SceneError>();
    // The attributes every SceneError is given (`scene_error`), at their empty values on
    // the class, so that the type stubs' declarations of them hold on the class too.
    for (name, empty) in [("path", Some("")), ("reason", Some(""))] {
        scene_error.setattr(name, empty)?;
    }
    for name in ["line", "column", "offset"] {
        scene_error.setattr(name, m.py().None())?;
    }
    m.add("SceneError", scene_error)?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<renderer::Renderer>()?;
    m.add_function(wrap_pyfunction!(scene::render, m)?)?;
    m.add_function(wrap_pyfunction!(scene::info, m)?)?;
    m.add_function(wrap_pyfunction!(to_srgb8, m)?)?;
    m.add_function(wrap_pyfunction!(png, m)?)?;
    m.add_function(wrap_pyfunction!(shared::release, m)?)?;
    m.add_function(wrap_pyfunction!(shared::_devices_opened, m)?)?;
    Ok(())
}
