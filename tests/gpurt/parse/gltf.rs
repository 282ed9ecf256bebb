//! glTF 2.0: a model with nested TRS and matrix transforms gives the triangles the test
//! places itself (written as OBJ and read back), the same from `.gltf` with a data URI,
//! `.glb` and `.gltf` with its buffer beside it; its camera, lights and materials as
//! docs/scene-format.md maps them; strips and fans; and bad files, each a clear error.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use gpurt::scene::io::FileKind;
use gpurt::scene::{self, Light, Scene};
use serde_json::{Value, json};

use crate::common::{gpurt, temp_dir};

/// A unit cube's corners and its 12 triangles' indices.
fn cube() -> (Vec<[f32; 3]>, Vec<u16>) {
    let v = (0..8)
        .map(|i| [(i >> 2 & 1) as f32, (i >> 1 & 1) as f32, (i & 1) as f32])
        .collect();
    let f = [
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ];
    (v, f.concat())
}

/// The cube's buffer: positions, then indices.
fn buffer() -> Vec<u8> {
    let (v, ix) = cube();
    let mut b: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    b.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
    b
}

const ROTATION: [f32; 4] = [0.0, 0.0, 0.382_683_43, 0.923_879_5];

/// The model: the cube under a translated node, a rotated and scaled one, and one with a
/// matrix; a camera; a point and a directional light; a glass material. `uri` is the
/// buffer's (`None`: the `.glb` chunk).
fn model(uri: Option<&str>) -> Value {
    let b = buffer();
    let mut buf = json!({"byteLength": b.len()});
    if let Some(uri) = uri {
        buf["uri"] = json!(uri);
    }
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3, 4, 5]}],
        "nodes": [
            {"translation": [1, 0, 0], "children": [1]},
            {"rotation": ROTATION, "scale": [2, 1, 1], "children": [2]},
            {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0.5, 0, 1]},
            {"camera": 0, "translation": [1, 1.5, 6]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [2, 5, 4]},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-0.707_106_77, 0, 0, 0.707_106_77]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.5}}],
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1, 0.9, 0.8], "intensity": 10},
            {"type": "directional", "color": [0.5, 0.5, 0.5]}
        ]}},
        "materials": [{
            "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.95, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8}, "KHR_materials_ior": {"ior": 1.45}}
        }],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
            {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96},
            {"buffer": 0, "byteOffset": 96, "byteLength": 72}
        ],
        "buffers": [buf]
    })
}

fn data_uri() -> String {
    use base64::Engine;
    let b64 = base64::engine::general_purpose::STANDARD.encode(buffer());
    format!("data:application/octet-stream;base64,{b64}")
}

/// `.glb` of a JSON chunk and the buffer as its binary chunk.
fn glb(doc: &Value) -> Vec<u8> {
    crate::common::inputs::glb(&serde_json::to_vec(doc).unwrap(), &buffer())
}

/// The model as `.gltf` with a data URI and as `.glb`, for the random mutations.
pub(super) fn samples() -> [(&'static str, Vec<u8>); 2] {
    [
        (
            "m.gltf",
            serde_json::to_vec(&model(Some(&data_uri()))).unwrap(),
        ),
        ("m.glb", glb(&model(None))),
    ]
}

fn parse(bytes: &[u8], name: &str, dir: &Path) -> Result<Scene, gpurt::Error> {
    scene::parse(bytes, FileKind::Gltf, name, dir)
}

#[test]
fn nested_transforms_place_the_triangles_as_an_obj_written_by_hand_does() {
    let dir = temp_dir("gltf-place");
    let json = serde_json::to_vec(&model(Some(&data_uri()))).unwrap();
    let got = parse(&json, "m.gltf", &dir).expect("reads");
    // The same triangles placed here: translate, then rotate and scale, then the matrix's
    // translation, written as an OBJ.
    let world = Mat4::from_translation(Vec3::X)
        * Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 1.0),
            Quat::from_array(ROTATION),
            Vec3::ZERO,
        )
        * Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0));
    let (v, ix) = cube();
    let mut obj = String::new();
    for p in &v {
        let p = world.transform_point3(Vec3::from(*p));
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in ix.chunks(3) {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    let want = scene::obj::parse(obj.as_bytes(), "m.obj").expect("the OBJ reads");
    assert_eq!(got.triangles.len(), 12);
    for (a, b) in got.triangles.iter().zip(&want) {
        for (p, q) in a.v.iter().zip(&b.v) {
            assert!((*p - *q).length() < 1e-5, "{p} vs {q}");
        }
    }
    // The same scene from a .glb and from a .gltf whose buffer is a file beside it.
    let from_glb = parse(&glb(&model(None)), "m.glb", &dir).expect("the .glb reads");
    std::fs::write(dir.join("cube data.bin"), buffer()).unwrap();
    let beside = serde_json::to_vec(&model(Some("cube%20data.bin"))).unwrap();
    let from_file = parse(&beside, "m.gltf", &dir).expect("the buffer beside it reads");
    for other in [&from_glb, &from_file] {
        assert_eq!(other.triangles, got.triangles);
        assert_eq!(other.camera, got.camera);
        assert_eq!(other.materials, got.materials);
    }
}

#[test]
fn camera_lights_and_materials_are_mapped_as_documented() {
    let json = serde_json::to_vec(&model(Some(&data_uri()))).unwrap();
    let s = parse(&json, "m.gltf", Path::new(".")).expect("reads");
    let c = &s.camera;
    assert_eq!(
        (c.from, c.at, c.up),
        (Vec3::new(1.0, 1.5, 6.0), Vec3::new(1.0, 1.5, 5.0), Vec3::Y)
    );
    assert!((c.angle - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!((c.width, c.height, c.hither), (768, 512, 0.1));
    assert_eq!(s.lights.len(), 2);
    assert_eq!(
        s.lights[0],
        Light::Point {
            position: Vec3::new(2.0, 5.0, 4.0),
            color: Some(Vec3::new(1.0, 0.9, 0.8))
        }
    );
    let Light::Directional { direction, color } = s.lights[1] else {
        panic!("{:?}", s.lights[1])
    };
    assert!((direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
    assert_eq!(color, Some(Vec3::splat(0.5)));
    // Glass: smooth dielectric, 80% transmitted at index 1.45.
    let m = s.materials[s.triangles[0].material.0 as usize];
    assert_eq!(m.color, Vec3::new(0.9, 0.95, 1.0));
    assert_eq!((m.t, m.ior, m.ks), (0.8, 1.45, 0.04));
    assert!((m.kd - 0.2).abs() < 1e-6 && m.shine == 1e4, "{m:?}");
    // A rough metal and a half-rough plastic, by the table.
    for (metal, rough, kd, ks, shine) in [(1.0, 0.5, 0.0, 0.5, 30.0), (0.0, 0.5, 1.0, 0.02, 30.0)] {
        let mut doc = model(Some(&data_uri()));
        doc["materials"][0] =
            json!({"pbrMetallicRoughness": {"metallicFactor": metal, "roughnessFactor": rough}});
        let s = parse(&serde_json::to_vec(&doc).unwrap(), "m.gltf", Path::new(".")).unwrap();
        let m = s.materials[s.triangles[0].material.0 as usize];
        assert_eq!((m.color, m.t), (Vec3::ONE, 0.0));
        assert!(
            (m.kd - kd).abs() < 1e-6 && (m.ks - ks).abs() < 1e-6 && (m.shine - shine).abs() < 1e-3,
            "{m:?}"
        );
    }
    // Without a camera the model is framed as a bare mesh, with the file's lights.
    let mut doc = model(Some(&data_uri()));
    doc["scenes"][0]["nodes"] = json!([0, 4]);
    let s = parse(&serde_json::to_vec(&doc).unwrap(), "m.gltf", Path::new(".")).unwrap();
    assert!(s.camera.fit.is_some());
    assert_eq!(s.lights.len(), 1);
    // An emitter's radiance: the factor times the strength. A model lit by emitters alone
    // gets no light of its own, framed or seen through its camera; one without emitters
    // or lights gets one.
    for (nodes, emits, lights) in [
        (json!([0]), true, 0),
        (json!([0, 3]), true, 0),
        (json!([0]), false, 1),
        (json!([0, 3]), false, 1),
    ] {
        let mut doc = model(Some(&data_uri()));
        doc["scenes"][0]["nodes"] = nodes;
        if emits {
            doc["materials"][0] = json!({
                "emissiveFactor": [1, 0.5, 0.25],
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}}
            });
        }
        let s = parse(&serde_json::to_vec(&doc).unwrap(), "m.gltf", Path::new(".")).unwrap();
        let m = s.materials[s.triangles[0].material.0 as usize];
        let radiance = if emits {
            Vec3::new(8.0, 4.0, 2.0)
        } else {
            Vec3::ZERO
        };
        assert_eq!((m.emission, s.lights.len()), (radiance, lights), "{s:?}");
    }
}

/// The cube's triangles wind counter-clockwise seen from outside; so they stay under a
/// transform that mirrors it (glTF turns the winding where the determinant is negative),
/// which keeps an emitter's front where its author put it.
#[test]
fn a_mirroring_transform_keeps_the_front_outside() {
    for scale in [
        [2.0, 1.0, 1.0],
        [-2.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, -1.0, -1.0],
    ] {
        let mut doc = model(Some(&data_uri()));
        doc["nodes"][1]["scale"] = json!(scale);
        let s = parse(&serde_json::to_vec(&doc).unwrap(), "m.gltf", Path::new(".")).unwrap();
        let (lo, hi) = s
            .triangles
            .iter()
            .flat_map(|t| t.v)
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        let centre = 0.5 * (lo + hi);
        assert_eq!(s.triangles.len(), 12);
        for t in &s.triangles {
            let outward = (t.v[0] + t.v[1] + t.v[2]) / 3.0 - centre;
            assert!(
                t.cross().dot(outward) > 0.0,
                "scale {scale:?}: {t:?} faces in"
            );
        }
    }
}

#[test]
fn strips_and_fans_are_triangles_and_points_are_skipped_with_a_warning() {
    let mut doc = model(Some(&data_uri()));
    // Corners 0, 1, 2, 3 of the cube: the face x = 0, as a strip and as a fan.
    doc["accessors"][1] =
        json!({"bufferView": 1, "componentType": 5123, "count": 4, "type": "SCALAR"});
    let (v, _) = cube();
    for (mode, want) in [(5, [[0, 1, 2], [2, 1, 3]]), (6, [[0, 1, 2], [0, 2, 3]])] {
        doc["meshes"][0]["primitives"][0]["mode"] = json!(mode);
        doc["buffers"][0] =
            json!({"byteLength": 104, "uri": data_uri_of(&[&v.concat(), &[0u16, 1, 2, 3]])});
        doc["bufferViews"][1] = json!({"buffer": 0, "byteOffset": 96, "byteLength": 8});
        let mut flat = doc.clone();
        flat["nodes"][0] = json!({"children": [1]});
        flat["nodes"][1] = json!({"children": [2]});
        flat["nodes"][2] = json!({"mesh": 0});
        let s = parse(
            &serde_json::to_vec(&flat).unwrap(),
            "m.gltf",
            Path::new("."),
        )
        .unwrap();
        let got: Vec<[Vec3; 3]> = s.triangles.iter().map(|t| t.v).collect();
        let want: Vec<[Vec3; 3]> = want.iter().map(|t| t.map(|i| Vec3::from(v[i]))).collect();
        assert_eq!(got, want, "mode {mode}");
    }
    // Points beside the triangles: skipped, and said so.
    let prims = &mut doc["meshes"][0]["primitives"];
    let points = json!({"attributes": {"POSITION": 0}, "mode": 0});
    *prims = json!([points, prims[0].clone()]);
    let s = parse(&serde_json::to_vec(&doc).unwrap(), "m.gltf", Path::new(".")).unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("mesh 0 primitive 0 skipped: gpurt renders triangles, not Points")),
        "{:?}",
        s.warnings
    );
}

fn data_uri_of(parts: &[&dyn AsBytes]) -> String {
    use base64::Engine;
    let bytes: Vec<u8> = parts.iter().flat_map(|p| p.bytes()).collect();
    let b64 = base64::engine::general_purpose::STANDARD.encode(bytes);
    format!("data:application/octet-stream;base64,{b64}")
}

trait AsBytes {
    fn bytes(&self) -> Vec<u8>;
}
impl AsBytes for Vec<f32> {
    fn bytes(&self) -> Vec<u8> {
        self.iter().flat_map(|x| x.to_le_bytes()).collect()
    }
}
impl AsBytes for [u16; 4] {
    fn bytes(&self) -> Vec<u8> {
        self.iter().flat_map(|x| x.to_le_bytes()).collect()
    }
}

fn error(doc: &Value, dir: &Path) -> String {
    let bytes = serde_json::to_vec(doc).unwrap();
    parse(&bytes, "m.gltf", dir)
        .expect_err("an error")
        .to_string()
}

#[test]
fn bad_files_are_errors_that_say_what_is_wrong() {
    let dir = temp_dir("gltf-bad");
    let good = model(Some(&data_uri()));
    let with = |path: &[&str], v: Value| {
        let mut d = good.clone();
        let mut at = &mut d;
        for k in path {
            at = match k.parse::<usize>() {
                Ok(i) => &mut at[i],
                Err(_) => &mut at[*k],
            };
        }
        *at = v;
        d
    };
    // An accessor past its view, a view past its buffer.
    let e = error(&with(&["accessors", "1", "count"], json!(37)), &dir);
    assert!(
        e.contains("accessor 1 (mesh 0 primitive 0 indices) reaches past its buffer view"),
        "{e}"
    );
    let e = error(&with(&["bufferViews", "1", "byteLength"], json!(720)), &dir);
    assert!(
        e.contains("reaches past its buffer view, or its view past buffer 0"),
        "{e}"
    );
    // Buffers outside the model's folder, absolute or climbing out.
    for uri in [
        "../../etc/passwd",
        "/etc/passwd",
        "file:///etc/passwd",
        "sub/../../x.bin",
    ] {
        let e = error(&with(&["buffers", "0", "uri"], json!(uri)), &dir);
        assert!(e.contains("is outside the model's folder"), "{uri}: {e}");
    }
    let e = error(&with(&["buffers", "0", "uri"], json!("missing.bin")), &dir);
    assert!(e.contains("buffer 0: cannot read 'missing.bin'"), "{e}");
    // A buffer shorter than it says, bad base64, an index past the vertices.
    let e = error(&with(&["buffers", "0", "byteLength"], json!(1000)), &dir);
    assert!(
        e.contains("buffer 0 declares 1000 bytes but holds 168"),
        "{e}"
    );
    let e = error(
        &with(
            &["buffers", "0", "uri"],
            json!("data:application/octet-stream;base64,@@@@"),
        ),
        &dir,
    );
    assert!(e.contains("bad base64"), "{e}");
    let mut far = cube().1;
    far[5] = 8;
    let bytes: Vec<u8> = cube()
        .0
        .concat()
        .bytes()
        .into_iter()
        .chain(far.iter().flat_map(|i| i.to_le_bytes()))
        .collect();
    let b64 = {
        use base64::Engine;
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    };
    let e = error(
        &with(
            &["buffers", "0", "uri"],
            json!(format!("data:application/octet-stream;base64,{b64}")),
        ),
        &dir,
    );
    assert!(
        e.contains("mesh 0 primitive 0 refers to vertex 8; it has 8"),
        "{e}"
    );
    // A node that is its own ancestor.
    let e = error(&with(&["nodes", "2", "children"], json!([0])), &dir);
    assert!(e.contains("a cycle in the node hierarchy"), "{e}");
    // JSON that does not parse: its line and column.
    let e = parse(
        b"{\"asset\": {\"version\": \"2.0\"},\n  \"scenes\": [}",
        "m.gltf",
        &dir,
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("m.gltf:2:14: not glTF JSON"), "{e}");
    // A .glb whose chunk lengths lie.
    let mut lie = glb(&model(None));
    let n = lie.len();
    lie[12..16].copy_from_slice(&(n as u32 * 4).to_le_bytes());
    let e = parse(&lie, "m.glb", &dir).unwrap_err().to_string();
    assert!(
        e.starts_with("m.glb: not a glTF file gpurt can read"),
        "{e}"
    );
    lie.truncate(n - 40);
    assert!(parse(&lie, "m.glb", &dir).is_err());
    // From the command line: exit 2 and no picture; a good model renders.
    std::fs::write(
        dir.join("bad.gltf"),
        serde_json::to_vec(&with(&["nodes", "2", "children"], json!([0]))).unwrap(),
    )
    .unwrap();
    let out = gpurt(&["bad.gltf", "-o", "bad.png"], &dir);
    assert_eq!(out.status.code(), Some(2));
    assert!(!dir.join("bad.png").exists());
    std::fs::write(dir.join("m.glb"), glb(&model(None))).unwrap();
    let out = gpurt(
        &[
            "m.glb",
            "-o",
            "m.png",
            "--width",
            "24",
            "--height",
            "16",
            "--backend",
            "cpu",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
