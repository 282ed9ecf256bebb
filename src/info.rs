//! `gpurt info`: what a scene holds, as text or as one JSON object.

use serde_json::json;

use crate::scene::{Light, Scene};

/// Counts per primitive kind, after triangulation.
pub fn to_json(s: &Scene) -> serde_json::Value {
    let b = s.bounds();
    let c = &s.camera;
    let bounds = if b.is_empty() {
        serde_json::Value::Null
    } else {
        json!({ "min": b.min.to_array(), "max": b.max.to_array() })
    };
    let count = |f: fn(&Light) -> bool| s.lights.iter().filter(|l| f(l)).count();
    json!({
        "file": s.name,
        "camera": {
            "from": c.from.to_array(),
            "at": c.at.to_array(),
            "up": c.up.to_array(),
            "angle": c.angle,
            "hither": c.hither,
            "aperture": c.aperture,
            "focal": c.focal_distance(),
        },
        "resolution": [c.width, c.height],
        "background": s.background.to_array(),
        "bounds": bounds,
        "spheres": s.spheres.len(),
        "triangles": s.triangles.len(),
        "planes": s.planes.len(),
        "cones": s.cones.len(),
        "boxes": s.boxes.len(),
        "lights": s.lights.len(),
        "point_lights": count(|l| matches!(l, Light::Point { .. })),
        "directional_lights": count(|l| matches!(l, Light::Directional { .. })),
        "area_lights": count(|l| matches!(l, Light::Area { .. })),
        "materials": s.materials.len(),
        "warnings": s.warnings,
    })
}

pub fn to_text(s: &Scene) -> String {
    use std::fmt::Write;
    let c = &s.camera;
    let b = s.bounds();
    let v = |v: glam::Vec3| format!("{} {} {}", v.x, v.y, v.z);
    let mut o = String::new();
    let _ = writeln!(o, "scene       {}", s.name);
    let _ = writeln!(
        o,
        "camera      from {}  at {}  up {}  angle {} deg  hither {}",
        v(c.from),
        v(c.at),
        v(c.up),
        c.angle,
        c.hither
    );
    if c.aperture > 0.0 {
        let _ = writeln!(
            o,
            "lens        aperture {}  focal {}",
            c.aperture,
            c.focal_distance()
        );
    }
    let _ = writeln!(o, "resolution  {}x{}", c.width, c.height);
    let _ = writeln!(o, "background  {}", v(s.background));
    if b.is_empty() {
        let _ = writeln!(o, "bounds      (no bounded primitives)");
    } else {
        let _ = writeln!(o, "bounds      {}  ..  {}", v(b.min), v(b.max));
    }
    let _ = writeln!(
        o,
        "primitives  {} spheres, {} triangles, {} planes, {} cones, {} boxes",
        s.spheres.len(),
        s.triangles.len(),
        s.planes.len(),
        s.cones.len(),
        s.boxes.len()
    );
    let _ = writeln!(o, "lights      {}", s.lights.len());
    for l in &s.lights {
        let line = match l {
            Light::Point { position, color } => format!(
                "point at {}{}",
                v(*position),
                color
                    .map(|c| format!(", colour {}", v(c)))
                    .unwrap_or_default()
            ),
            Light::Directional { direction, color } => format!(
                "directional towards {}{}",
                v(*direction),
                color
                    .map(|c| format!(", colour {}", v(c)))
                    .unwrap_or_default()
            ),
            Light::Area {
                corner,
                u,
                v: e,
                color,
                samples,
            } => format!(
                "area at {} edges {} / {}, colour {}, {}x{} samples",
                v(*corner),
                v(*u),
                v(*e),
                v(*color),
                samples[0],
                samples[1]
            ),
        };
        let _ = writeln!(o, "  {line}");
    }
    let _ = writeln!(o, "materials   {}", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let _ = writeln!(
            o,
            "  {i}: colour {}  Kd {}  Ks {}  Shine {}  T {}  ior {}",
            v(m.color),
            m.kd,
            m.ks,
            m.shine,
            m.t,
            m.ior
        );
    }
    let _ = writeln!(o, "warnings    {}", s.warnings.len());
    for w in &s.warnings {
        let _ = writeln!(o, "  {w}");
    }
    o
}
