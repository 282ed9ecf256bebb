//! Python arguments into the library's types: the frame's `Overrides` (checked against the
//! same limits as the command line's flags), the `Backend`, the AOV, the shading model
//! and the camera dict. Bad values raise ValueError, wrong types TypeError: never a panic.

use glam::Vec3;
use gpurt::frame::{Overrides, Shading};
use gpurt::gpu_types::{AOV_COLOR, AOV_COST, AOV_DEPTH, AOV_NORMAL, AOV_UV};
use gpurt::limits::{MAX_DEPTH, MAX_IMAGE_SIDE, MAX_SPP};
use gpurt::scene::Camera;
use gpurt::session::Backend;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// A whole number in `1..=max`, named `what` in the message. Taken as i64 so that a
/// negative or huge number is a ValueError, not the OverflowError of a u32 conversion.
fn count(value: Option<i64>, what: &str, max: u32) -> PyResult<Option<u32>> {
    match value {
        None => Ok(None),
        Some(v) if (1..=i64::from(max)).contains(&v) => Ok(Some(v as u32)),
        Some(v) => Err(PyValueError::new_err(format!(
            "{what} must be 1 to {max}, got {v}"
        ))),
    }
}

/// The ambient light: one non-negative number (grey) or three (RGB), as `--ambient`.
fn ambient(value: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec3>> {
    let Some(value) = value else {
        return Ok(None);
    };
    let rgb = if let Ok(g) = value.extract::<f64>() {
        [g; 3]
    } else if value.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(
            "ambient must be a number or three numbers, not a string",
        ));
    } else {
        let v: Vec<f64> = value.extract().map_err(|_| {
            PyTypeError::new_err("ambient must be a number or a sequence of three numbers")
        })?;
        <[f64; 3]>::try_from(v.as_slice()).map_err(|_| {
            PyValueError::new_err(format!("ambient takes three numbers, got {}", v.len()))
        })?
    };
    if !rgb.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "ambient must be finite and not negative, got {rgb:?}"
        )));
    }
    Ok(Some(Vec3::from_array(rgb.map(|c| c as f32))))
}

/// The shader's AOV for `aov=`: None or "color" for the image, "normal", "depth", "cost",
/// "uv".
pub fn aov_code(aov: Option<&str>) -> PyResult<u32> {
    match aov {
        None | Some("color") => Ok(AOV_COLOR),
        Some("normal") => Ok(AOV_NORMAL),
        Some("depth") => Ok(AOV_DEPTH),
        Some("cost") => Ok(AOV_COST),
        Some("uv") => Ok(AOV_UV),
        Some(other) => Err(PyValueError::new_err(format!(
            "aov must be None, 'color', 'normal', 'depth', 'cost' or 'uv', got {other:?} \
             (the wireframe is drawn by the command line and the viewer only)"
        ))),
    }
}

/// `backend=`: "auto", "gpu" or "cpu", chosen as the command line's `--backend`.
pub fn backend(name: &str) -> PyResult<Backend> {
    match Backend::from_name(name) {
        Some(b) if b != Backend::Both => Ok(b),
        _ => Err(PyValueError::new_err(format!(
            "backend must be 'auto', 'gpu' or 'cpu', got {name:?}"
        ))),
    }
}

/// `shading=`: None keeps the default (Phong), else a model by the name `--shading` takes:
/// "phong" or "blinn-phong".
pub fn shading(name: Option<&str>) -> PyResult<Option<Shading>> {
    let Some(name) = name else {
        return Ok(None);
    };
    Shading::from_name(name).map(Some).ok_or_else(|| {
        let names: Vec<String> = Shading::ALL
            .iter()
            .map(|s| format!("'{}'", s.name()))
            .collect();
        PyValueError::new_err(format!(
            "shading must be None or one of {}, got {name:?}",
            names.join(", ")
        ))
    })
}

/// What a render call sets over the scene's camera and the defaults.
#[derive(Default)]
pub struct Frame<'a, 'py> {
    pub width: Option<i64>,
    pub height: Option<i64>,
    pub spp: Option<i64>,
    pub depth: Option<i64>,
    pub ambient: Option<&'a Bound<'py, PyAny>>,
    pub aov: Option<&'a str>,
    pub shading: Option<&'a str>,
}

impl Frame<'_, '_> {
    /// The library's `Overrides` for these arguments, checked.
    pub fn overrides(&self) -> PyResult<Overrides> {
        Ok(Overrides {
            width: count(self.width, "width", MAX_IMAGE_SIDE)?,
            height: count(self.height, "height", MAX_IMAGE_SIDE)?,
            spp: count(self.spp, "spp", MAX_SPP)?,
            max_depth: count(self.depth, "depth", MAX_DEPTH)?,
            ambient: ambient(self.ambient)?,
            aov: Some(aov_code(self.aov)?),
            seed: None,
            shading: shading(self.shading)?,
        })
    }
}

/// Later overrides win where they set something.
pub fn layer(base: &Overrides, top: &Overrides) -> Overrides {
    Overrides {
        width: top.width.or(base.width),
        height: top.height.or(base.height),
        spp: top.spp.or(base.spp),
        max_depth: top.max_depth.or(base.max_depth),
        ambient: top.ambient.or(base.ambient),
        aov: top.aov.or(base.aov),
        seed: top.seed.or(base.seed),
        shading: top.shading.or(base.shading),
    }
}

fn point(dict: &Bound<'_, PyDict>, key: &str) -> PyResult<Option<Vec3>> {
    let Some(value) = dict.get_item(key)? else {
        return Ok(None);
    };
    let v: [f32; 3] = value
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("camera['{key}'] must be three numbers")))?;
    Ok(Some(Vec3::from_array(v)))
}

/// `home` with what the camera dict sets in its place: `eye`, `look_at`, `up` (three
/// numbers each) and `fov` (the vertical angle in degrees, NFF's `angle`), checked as the
/// NFF reader checks a `v` block.
pub fn camera(home: &Camera, dict: &Bound<'_, PyAny>) -> PyResult<Camera> {
    const KEYS: [&str; 4] = ["eye", "look_at", "up", "fov"];
    let dict = dict.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err("camera must be a dict with keys eye, look_at, up and fov")
    })?;
    for key in dict.keys() {
        let key: String = key.extract()?;
        if !KEYS.contains(&key.as_str()) {
            return Err(PyValueError::new_err(format!(
                "unknown camera key {key:?}; the keys are eye, look_at, up and fov"
            )));
        }
    }
    let mut c = home.clone();
    c.from = point(dict, "eye")?.unwrap_or(c.from);
    c.at = point(dict, "look_at")?.unwrap_or(c.at);
    c.up = point(dict, "up")?.unwrap_or(c.up);
    if let Some(fov) = dict.get_item("fov")? {
        let fov: f64 = fov.extract()?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(PyValueError::new_err(format!(
                "camera fov must be in (0, 180) degrees, got {fov}"
            )));
        }
        c.angle = fov as f32;
    }
    if let Some(problem) = c.view_problem() {
        return Err(PyValueError::new_err(format!("camera: {problem}")));
    }
    Ok(c)
}
