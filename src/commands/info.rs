//! `gpurt info`: what a scene holds, as text or as one JSON object (its schema:
//! `docs/info-json.md`).

use glam::Vec3;
use serde_json::{Value, json};

use crate::pack::EMITTER_SAMPLES;
use crate::scene::animation::Animation;
use crate::scene::{FlatScene, Light, MaterialId, Wrap};
use crate::util::limits::DEFAULT_AMBIENT;

/// An f32 as the shortest decimal that reads back as the same f32 (`0.05`, not the
/// `0.05000000074505806` its f64 widening prints); null when not finite.
fn num(x: f32) -> Value {
    x.to_string()
        .parse::<f64>()
        .ok()
        .and_then(serde_json::Number::from_f64)
        .map_or(Value::Null, Value::Number)
}

fn vec3(v: Vec3) -> Value {
    Value::Array(v.to_array().map(num).to_vec())
}

fn colour(c: Option<Vec3>) -> Value {
    c.map_or(Value::Null, vec3)
}

fn light(l: &Light) -> Value {
    match l {
        Light::Point { position, color } => json!({
            "kind": "point",
            "position": vec3(*position),
            "color": colour(*color),
        }),
        Light::Directional { direction, color } => json!({
            "kind": "directional",
            "direction": vec3(*direction),
            "color": colour(*color),
        }),
        Light::Area {
            corner,
            u,
            v,
            color,
            samples,
        } => json!({
            "kind": "area",
            "corner": vec3(*corner),
            "u": vec3(*u),
            "v": vec3(*v),
            "color": vec3(*color),
            "samples": samples,
        }),
    }
}

/// The emitters' light (`pack::EMITTER_SAMPLES`): an emissive material's triangles.
struct Emitter {
    material: usize,
    radiance: Vec3,
    triangles: usize,
    area: f64,
}

/// The scene's emitters: each material that emits, with triangles of some area.
fn emitters(f: &FlatScene) -> impl Iterator<Item = Emitter> + '_ {
    (f.scene.materials.iter().enumerate()).filter_map(|(i, m)| {
        let (triangles, area) = f.prims.surface(MaterialId(i as u32));
        (m.emits() && triangles > 0).then_some(Emitter {
            material: i,
            radiance: m.emission,
            triangles,
            area,
        })
    })
}

/// The whole scene description: camera, image, background and ambient light, bounds,
/// counts per primitive kind (after triangulation), every light and material with its
/// parameters, and the reader's warnings. From a scene read as `scene::summary` reads
/// it (or any `FlatScene`).
/// A wrap mode as `info` names it.
fn wrap_name(w: Wrap) -> &'static str {
    match w {
        Wrap::Repeat => "repeat",
        Wrap::Clamp => "clamp",
        Wrap::Mirror => "mirror",
    }
}

pub fn to_json(f: &FlatScene) -> Value {
    let (s, b, [spheres, triangles, cones, boxes]) = (&f.scene, f.bounds(), f.counts());
    let c = &s.camera;
    let bounds = if b.is_empty() {
        Value::Null
    } else {
        json!({ "min": vec3(b.min), "max": vec3(b.max) })
    };
    let materials: Vec<Value> = s
        .materials
        .iter()
        .map(|m| {
            json!({
                "color": vec3(m.color),
                "kd": num(m.kd),
                "ks": num(m.ks),
                "shine": num(m.shine),
                "t": num(m.t),
                "ior": num(m.ior),
                "emission": vec3(m.emission),
                "texture": m.texture,
                "ambient": m.ambient.map(vec3),
            })
        })
        .collect();
    let textures: Vec<Value> = s
        .textures
        .iter()
        .map(|t| {
            json!({
                "name": t.name,
                "width": t.width,
                "height": t.height,
                "texels": t.texels.len(),
                "wrap": t.wrap.map(wrap_name),
            })
        })
        .collect();
    json!({
        "file": s.name,
        "camera": {
            "from": vec3(c.from),
            "at": vec3(c.at),
            "up": vec3(c.up),
            "angle": num(c.angle),
            "hither": num(c.hither),
            "aperture": num(c.aperture),
            "focal": num(c.focal_distance()),
        },
        "resolution": [c.width, c.height],
        "background": vec3(s.background),
        "ambient": colour(s.ambient),
        "ambient_used": vec3(s.ambient.unwrap_or(Vec3::splat(DEFAULT_AMBIENT))),
        "bounds": bounds,
        "spheres": spheres,
        "triangles": triangles,
        "planes": s.planes.len(),
        "cones": cones,
        "boxes": boxes,
        "lights": s.lights.iter().map(light).chain(emitters(f).map(|e| json!({
            "kind": "emitter",
            "material": e.material,
            "color": vec3(e.radiance),
            "triangles": e.triangles,
            "area": num(e.area as f32),
            "samples": [EMITTER_SAMPLES, EMITTER_SAMPLES],
        }))).collect::<Vec<_>>(),
        "materials": materials,
        "textures": textures,
        "animation": s.animation.as_deref().map(animation_json),
        "warnings": s.warnings,
    })
}

/// The primitives the animation's groups hold, by kind (sphere, triangle, cone, box).
fn moving(a: &Animation) -> [usize; 4] {
    a.groups.iter().fold([0; 4], |mut n, g| {
        for (n, c) in n.iter_mut().zip(g.prims.counts()) {
            *n += c;
        }
        n
    })
}

fn animation_json(a: &Animation) -> Value {
    let [spheres, triangles, cones, boxes] = moving(a);
    json!({
        "range": a.range.map(|r| json!({ "start": r.start, "end": r.end, "frames": r.frames })),
        "tracks": a.tracks.iter().map(|t| t.name.as_str()).filter(|n| !n.is_empty()).collect::<Vec<_>>(),
        "groups": a.groups.len(),
        "moving": { "spheres": spheres, "triangles": triangles, "cones": cones, "boxes": boxes },
        "moving_lights": a.lights.len(),
        "camera_moves": a.camera.is_some(),
    })
}

pub fn to_text(f: &FlatScene) -> String {
    use std::fmt::Write;
    let (s, b, [spheres, triangles, cones, boxes]) = (&f.scene, f.bounds(), f.counts());
    let c = &s.camera;
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
    match s.ambient {
        Some(a) => {
            let _ = writeln!(o, "ambient     {}", v(a));
        }
        None => {
            let _ = writeln!(
                o,
                "ambient     {DEFAULT_AMBIENT} (default; the scene sets none)"
            );
        }
    }
    if b.is_empty() {
        let _ = writeln!(o, "bounds      (no bounded primitives)");
    } else {
        let _ = writeln!(o, "bounds      {}  ..  {}", v(b.min), v(b.max));
    }
    let _ = writeln!(
        o,
        "primitives  {spheres} spheres, {triangles} triangles, {} planes, {cones} cones, {boxes} boxes",
        s.planes.len(),
    );
    if let Some(a) = s.animation.as_deref() {
        let [spheres, triangles, cones, boxes] = moving(a);
        let range = match a.range {
            Some(r) => format!("from {} to {} in {} frames", r.start, r.end, r.frames),
            None => "no time range ('a')".to_string(),
        };
        let _ = writeln!(
            o,
            "animation   {range}; {} groups move {spheres} spheres, {triangles} triangles, {cones} cones, {boxes} boxes (not counted above); {} moving lights; the camera {}",
            a.groups.len(),
            a.lights.len(),
            if a.camera.is_some() { "moves" } else { "stays" }
        );
    }
    let emitters: Vec<Emitter> = emitters(f).collect();
    let _ = writeln!(o, "lights      {}", s.lights.len() + emitters.len());
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
    for e in &emitters {
        let _ = writeln!(
            o,
            "  emitter: material {}, radiance {}, {} triangles of area {}, {EMITTER_SAMPLES}x{EMITTER_SAMPLES} samples",
            e.material,
            v(e.radiance),
            e.triangles,
            e.area as f32
        );
    }
    let _ = writeln!(o, "materials   {}", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let _ = writeln!(
            o,
            "  {i}: colour {}  Kd {}  Ks {}  Shine {}  T {}  ior {}{}{}{}",
            v(m.color),
            m.kd,
            m.ks,
            m.shine,
            m.t,
            m.ior,
            if m.emits() {
                format!("  emits {}", v(m.emission))
            } else {
                String::new()
            },
            m.texture
                .map_or(String::new(), |t| format!("  texture {t}")),
            m.ambient
                .map_or(String::new(), |a| format!("  ambient {}", v(a)))
        );
    }
    if !s.textures.is_empty() {
        let texels: usize = s.textures.iter().map(|t| t.texels.len()).sum();
        let _ = writeln!(
            o,
            "textures    {} ({texels} texels, {:.1} MiB on the device)",
            s.textures.len(),
            (texels * size_of::<glam::Vec4>()) as f64 / (1 << 20) as f64
        );
        for (i, t) in s.textures.iter().enumerate() {
            let _ = writeln!(
                o,
                "  {i}: {} x {}, wrap {} {}: {}",
                t.width,
                t.height,
                wrap_name(t.wrap[0]),
                wrap_name(t.wrap[1]),
                t.name
            );
        }
    }
    let _ = writeln!(o, "warnings    {}", s.warnings.len());
    for w in &s.warnings {
        let _ = writeln!(o, "  {w}");
    }
    o
}
