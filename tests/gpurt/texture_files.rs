//! Textures read from files: one checkerboard PNG named by OBJ's `map_Kd` and by glTF's
//! `baseColorTexture` (a file beside the model, a data URI, a `.glb`'s buffer view) gives
//! one image, the checkerboard decoded from sRGB and filtered as defined; `map_Kd`'s
//! `-s`/`-o` and `KHR_texture_transform` move it as their definitions say; and a texture
//! that cannot be had is a warning naming it and its material, the surfaces in the
//! material's colour, with nothing allocated for a header that declares too much.

use std::io::Cursor;
use std::path::Path;

use base64::Engine;
use glam::{DVec2, Vec3};
use gpurt::frame::RenderOptions;
use gpurt::scene::{self, Scene, Texture, Wrap, images};
use serde_json::{Value, json};

use crate::common::{gpurt, stderr, temp_dir};
use crate::texture::{VIEW, check_texture_on_quad, render};

/// The checkerboard's two colours as the PNG holds them (sRGB).
const SQUARES: [[u8; 3]; 2] = [[250, 250, 245], [89, 124, 203]];

/// A 4 x 4 checkerboard as a PNG file's bytes.
fn checker_png() -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    image::RgbImage::from_fn(4, 4, |x, y| image::Rgb(SQUARES[((x + y) % 2) as usize]))
        .write_to(&mut out, image::ImageFormat::Png)
        .unwrap();
    out.into_inner()
}

/// The checkerboard as the renderers should hold it: each square's colour decoded from
/// sRGB to linear light.
fn checker_linear() -> Texture {
    let linear = |c: [u8; 3]| Vec3::from(c.map(|c| images::srgb_to_linear(f32::from(c) / 255.0)));
    Texture {
        name: "checker".into(),
        width: 4,
        height: 4,
        texels: (0..16)
            .map(|k| linear(SQUARES[(k % 4 + k / 4) % 2]))
            .collect(),
        wrap: [Wrap::Repeat; 2],
    }
}

/// The quad of `texture::VIEW` as glTF: the OBJ's corners (x, y in [-1, 1]), its
/// coordinates written as glTF writes them (v running down the image: `1 - v` of the
/// OBJ's), its two triangles as the OBJ's quad is split. With `image`, a material whose
/// base colour texture that is (`material` its `baseColorTexture` object's extra keys,
/// the sampler and image given in `rest`). `blob` bytes (a `.glb`'s image) go after the
/// geometry in the buffer, as buffer view 3. Returns the JSON and the buffer's bytes,
/// which the JSON holds as a data URI unless it is a `.glb`'s.
pub(crate) fn gltf_quad(material: Option<Value>, blob: &[u8]) -> (String, Vec<u8>) {
    let pos: [[f32; 3]; 4] = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];
    let uv: [[f32; 2]; 4] = [[0.0, 0.5], [2.0, 0.5], [2.0, -0.5], [0.0, -0.5]];
    let ix: [u16; 6] = [3, 0, 1, 3, 1, 2];
    let mut bytes: Vec<u8> = bytemuck::cast_slice(&pos).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&uv));
    bytes.extend_from_slice(bytemuck::cast_slice(&ix));
    bytes.extend_from_slice(&[0, 0]);
    let at = bytes.len();
    bytes.extend_from_slice(blob);
    let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": at, "byteLength": blob.len().max(1)}
        ],
        "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{data}")}]
    });
    if blob.is_empty() {
        doc["bufferViews"].as_array_mut().unwrap().pop();
    } else {
        doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    }
    if let Some(m) = material {
        for (k, v) in m.as_object().unwrap() {
            doc[k] = v.clone();
        }
        doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    }
    (doc.to_string(), bytes)
}

/// The material, texture, sampler and image keys of a glTF whose quad has the image
/// `image` as its base colour (white, not metallic, fully rough: Kd 1, Ks 0, as the
/// OBJ's), with the extra texture-info keys `info` and the sampler `sampler`.
fn textured(image: Value, info: Value, sampler: Value) -> Value {
    let mut texture_info = json!({"index": 0});
    for (k, v) in info.as_object().unwrap() {
        texture_info[k] = v.clone();
    }
    json!({
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": texture_info, "metallicFactor": 0, "roughnessFactor": 1}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [sampler],
        "images": [image],
    })
}

/// The quad as OBJ, its material's `map_Kd` line `map` (in `quad.mtl`), in `dir`.
fn obj_quad(dir: &Path, map: &str) {
    std::fs::write(
        dir.join("quad.obj"),
        "mtllib quad.mtl\nusemtl board\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
         vt 0 0.5\nvt 2 0.5\nvt 2 1.5\nvt 0 1.5\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("quad.mtl"),
        format!("newmtl board\nKd 1 1 1\n{map}\n"),
    )
    .unwrap();
}

/// The model at `path` under `VIEW`'s camera, lit by an ambient light of 1 alone, so that
/// a pixel is its surface's Kd times colour: the texture's colour where there is one.
fn framed(path: &Path) -> Scene {
    let mut s = scene::load(path).expect("the model reads");
    let view = scene::nff::parse(VIEW.as_bytes(), "view.nff", Path::new(".")).unwrap();
    s.camera = view.camera;
    s.background = view.background;
    s.lights.clear();
    s.ambient = Some(Vec3::ONE);
    s
}

fn cpu_render(s: &Scene) -> gpurt::film::Film {
    render(s, None, RenderOptions::for_camera(&s.camera))
}

#[test]
fn obj_and_gltf_textures_from_files_data_uris_and_glb_give_one_image() {
    let dir = temp_dir("texture-files");
    let png = checker_png();
    std::fs::write(dir.join("check board.png"), &png).unwrap();
    obj_quad(&dir, "map_Kd check board.png");
    let repeat = json!({"wrapS": 10497, "wrapT": 10497});
    let file = textured(
        json!({"uri": "check%20board.png"}),
        json!({}),
        repeat.clone(),
    );
    std::fs::write(dir.join("quad.gltf"), gltf_quad(Some(file), &[]).0).unwrap();
    let data = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&png)
    );
    let uri = textured(json!({ "uri": data }), json!({}), repeat.clone());
    std::fs::write(dir.join("data.gltf"), gltf_quad(Some(uri), &[]).0).unwrap();
    let view = textured(
        json!({"bufferView": 3, "mimeType": "image/png"}),
        json!({}),
        repeat,
    );
    let (text, blob) = gltf_quad(Some(view), &png);
    std::fs::write(
        dir.join("quad.glb"),
        crate::common::inputs::glb(text.as_bytes(), &blob),
    )
    .unwrap();

    let obj = framed(&dir.join("quad.obj"));
    assert!(obj.warnings.is_empty(), "{:?}", obj.warnings);
    assert_eq!(obj.textures.len(), 1);
    let want = cpu_render(&obj);
    check_texture_on_quad(&obj, &want, &checker_linear(), |uv| uv);
    for name in ["quad.gltf", "data.gltf", "quad.glb"] {
        let s = framed(&dir.join(name));
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        assert_eq!(s.textures.len(), 1, "{name}");
        assert_eq!(s.textures[0].texels, obj.textures[0].texels, "{name}");
        let got = cpu_render(&s);
        let differ = (0..want.width)
            .flat_map(|x| (0..want.height).map(move |y| (x, y)))
            .filter(|&(x, y)| got.get(x, y) != want.get(x, y))
            .count();
        assert_eq!(differ, 0, "{name}: {differ} pixels differ from the OBJ's");
    }
}

/// `map_Kd -s 2 2 -o 0.25 0`: u and v scaled by 2, then u offset by a quarter;
/// `KHR_texture_transform`'s scale 2 and offset (0.25, 0.5) in glTF's coordinates (v
/// down) is, v turned over, u * 2 + 0.25 and v * 2 - 1.5; and the sampler's wraps read.
#[test]
fn map_kd_options_and_the_texture_transform_move_the_texture_as_defined() {
    let dir = temp_dir("texture-moved");
    std::fs::write(dir.join("board.png"), checker_png()).unwrap();
    obj_quad(&dir, "map_Kd -s 2 2 -o 0.25 0 -bm 1 board.png");
    let obj = framed(&dir.join("quad.obj"));
    assert_eq!(obj.warnings.len(), 1, "{:?}", obj.warnings);
    assert!(obj.warnings[0].contains("map_Kd's option '-bm' is not read"));
    let scaled = |uv: DVec2| DVec2::new(2.0 * uv.x + 0.25, 2.0 * uv.y);
    check_texture_on_quad(&obj, &cpu_render(&obj), &checker_linear(), scaled);

    let transform =
        json!({"extensions": {"KHR_texture_transform": {"offset": [0.25, 0.5], "scale": [2, 2]}}});
    let wraps = json!({"wrapS": 33648, "wrapT": 33071});
    let m = textured(json!({"uri": "board.png"}), transform, wraps);
    std::fs::write(dir.join("quad.gltf"), gltf_quad(Some(m), &[]).0).unwrap();
    let mut gltf = framed(&dir.join("quad.gltf"));
    assert_eq!(gltf.textures[0].wrap, [Wrap::Mirror, Wrap::Clamp]);
    gltf.textures[0].wrap = [Wrap::Repeat; 2];
    let moved = |uv: DVec2| DVec2::new(2.0 * uv.x + 0.25, 2.0 * uv.y - 1.5);
    check_texture_on_quad(&gltf, &cpu_render(&gltf), &checker_linear(), moved);
}

/// What cannot be had: a missing file, a path outside the model's folder, bytes that are
/// no image, a truncated PNG, and a PNG whose header declares 100000 x 100000 texels.
/// Each is a warning naming the image and the material at the `map_Kd`'s place; the
/// render exits 0 and is the untextured quad's, in the material's colour.
#[test]
fn textures_that_cannot_be_had_are_warnings_and_the_materials_colour() {
    let dir = temp_dir("texture-bad");
    let png = checker_png();
    std::fs::write(dir.join("truncated.png"), &png[..png.len() / 2]).unwrap();
    std::fs::write(dir.join("noise.png"), b"\x89PNG but not one at all").unwrap();
    std::fs::write(dir.join("huge.png"), huge_png()).unwrap();
    std::fs::write(dir.parent().unwrap().join("outside.png"), &png).unwrap();
    let plain = dir.join("plain");
    std::fs::create_dir_all(&plain).unwrap();
    obj_quad(&plain, "");
    let run = |d: &Path| {
        let out = gpurt(&["quad.obj", "--backend", "cpu", "-o", "out.png"], d);
        assert!(out.status.success(), "{}", stderr(&out));
        (
            stderr(&out),
            image::open(d.join("out.png")).unwrap().to_rgb8(),
        )
    };
    let (_, untextured) = run(&plain);
    for (map, why) in [
        ("missing.png", "cannot read 'missing.png'"),
        ("../outside.png", "outside the model's folder"),
        ("noise.png", ""),
        ("truncated.png", ""),
        ("huge.png", "declares 100000 x 100000 texels"),
    ] {
        obj_quad(&dir, &format!("map_Kd {map}"));
        let (err, image) = run(&dir);
        let warning = format!("quad.mtl:3:1: texture '{map}' of material 'board' is not used: ");
        assert!(err.contains(&warning) && err.contains(why), "{map}: {err}");
        assert!(
            err.contains("its faces keep the material's colour"),
            "{err}"
        );
        assert!(image == untextured, "{map}: not the material's colour");
    }
}

/// A PNG of one texel whose header says 100000 x 100000 (its checksum made right).
fn huge_png() -> Vec<u8> {
    let mut bytes = checker_png();
    bytes[16..24].copy_from_slice(&[100_000u32.to_be_bytes(), 100_000u32.to_be_bytes()].concat());
    let mut crc = flate2::Crc::new();
    crc.update(&bytes[12..29]);
    let crc = crc.sum();
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// A `.glb` whose image (a buffer view) declares 100000 x 100000 texels renders, its
/// quad in the material's colour, with a warning, and allocates nothing for the image:
/// its peak memory, sampled from /proc, stays that of a small scene.
#[test]
fn a_glb_image_declaring_ten_billion_texels_allocates_nothing() {
    let dir = temp_dir("texture-huge-glb");
    let png = huge_png();
    let view = textured(
        json!({"bufferView": 3, "mimeType": "image/png"}),
        json!({}),
        json!({}),
    );
    let (text, blob) = gltf_quad(Some(view), &png);
    std::fs::write(
        dir.join("huge.glb"),
        crate::common::inputs::glb(text.as_bytes(), &blob),
    )
    .unwrap();
    let (out, peak_kib, _) = crate::hostile::render_sampling_peak(&dir, "huge.glb");
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("huge.glb: image 0 (the base colour of material 0) is not used: its header declares 100000 x 100000 texels"),
        "{err}"
    );
    assert!(dir.join("out.png").is_file());
    // Ten billion texels would be 120 GB as gpurt holds them; the render needs tens of MiB.
    assert!(peak_kib < 200 << 10, "peak {peak_kib} KiB");
}
