//! The pipeline the command line drives: load -> pack -> render -> displayable film.

use std::path::Path;
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::error::Result;
use crate::film::Film;
use crate::gpu_types::{AOV_COST, AOV_DEPTH};
use crate::pack::{self, SceneBuffers};
use crate::scene::{self, Scene};

/// A scene read and flattened, with the time each step took.
pub struct Prepared {
    pub scene: Scene,
    pub buffers: SceneBuffers,
    pub parse_time: Duration,
    pub build_time: Duration,
}

pub fn prepare(path: &Path) -> Result<Prepared> {
    let t0 = Instant::now();
    let scene = scene::load(path)?;
    let t1 = Instant::now();
    let buffers = pack::pack(&scene)?;
    Ok(Prepared {
        scene,
        buffers,
        parse_time: t1 - t0,
        build_time: t1.elapsed(),
    })
}

/// Maps raw AOV values to something an 8-bit image can show: depth as grey scaled by
/// the largest distance, cost as a heat ramp scaled by the largest count. Colour and
/// normals pass through. Float formats (EXR) are written from the raw film instead.
pub fn display_film(film: &Film, aov: u32) -> Film {
    if aov != AOV_DEPTH && aov != AOV_COST {
        return film.clone();
    }
    let max = film
        .pixels
        .iter()
        .map(|p| p[0])
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max)
        .max(1e-30);
    let mut out = film.clone();
    for p in &mut out.pixels {
        let v = (p[0] / max).clamp(0.0, 1.0);
        *p = if aov == AOV_DEPTH {
            [v; 3]
        } else {
            heat(v).to_array()
        };
    }
    out
}

/// Black -> blue -> red -> yellow -> white.
fn heat(v: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    let x = v * 4.0;
    let i = (x.floor() as usize).min(3);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

/// Peak resident memory of this process in bytes (Linux; `None` elsewhere).
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
