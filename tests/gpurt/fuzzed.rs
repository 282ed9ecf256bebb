//! Inputs the fuzz targets (fuzz/README.md) found, each kept as a regression test. They go
//! the way the `render` target takes them: read (as `scene::load` would), pack, the checks
//! the GPU relies on, and a small CPU render. A reader may refuse an input, with its
//! position; a scene it accepts must render to finite, non-negative pixels.

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use gpurt::frame::{self, RenderOptions};
use gpurt::scene::{self, MaterialId, Scene, Triangle, nff, stl};

use crate::common::inputs::parse_ok;
use crate::common::temp_dir;

/// Packs, checks and renders `scene` at 8 x 8, 1 sample, depth 4 (the `render` target's
/// frame), and asserts that every pixel is finite and not negative.
#[track_caller]
fn assert_renders_finite(scene: Scene) {
    let name = scene.name.clone();
    let mut opts = RenderOptions::for_camera(&scene.camera);
    (opts.width, opts.height, opts.max_depth) = (8, 8, 4);
    let buffers = gpurt::pack::pack(scene).unwrap_or_else(|e| panic!("{name}: {e}"));
    let globals = frame::globals(&buffers, &opts);
    buffers.check(&globals).unwrap();
    let never = AtomicBool::new(false);
    let (film, _) = gpurt::cpu::render(&buffers, &globals, &|_| {}, &never).unwrap();
    for (i, p) in film.pixels.iter().enumerate() {
        assert!(
            p.iter().all(|c| c.is_finite() && *c >= 0.0),
            "{name}: pixel ({}, {}) is {p:?}",
            i % 8,
            i / 8
        );
    }
}

/// `render` target: a `pp` patch whose vertex normals are zero made the interpolated shading
/// normal 0 / 0, and every pixel that saw the patch NaN. The patch is now shaded flat, with
/// a warning naming its line.
#[test]
fn patch_with_zero_vertex_normals_is_shaded_flat_with_a_warning() {
    let src = "v from 0 -5 0 at 0 0 0 up 0 0 1 angle 45\nl 1 -3 2\n\
               pp 3 -1 0 -1 0 0 0  1 0 -1 0 0 0  0 0 1 0 0 0\n\
               pp 3 -1 0 -1 0 -1 0  1 0 -1 0 -2 0  0 0 1 0 0 0\n";
    let scene = parse_ok(src);
    assert_eq!(scene.triangles.len(), 2);
    assert!(scene.triangles.iter().all(|t| t.n.is_none()));
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
    for (w, line) in scene.warnings.iter().zip([3, 4]) {
        assert!(w.starts_with(&format!("t.nff:{line}:1: ")), "{w}");
        assert!(w.contains("normal") && w.contains("flat"), "{w}");
    }
    assert_renders_finite(scene);
}

/// Found reviewing the patch finding: normals that are usable directions, but whose squared
/// length overflows f32, normalised to zero. Patch normals are now kept as unit vectors.
#[test]
fn patch_normals_too_long_to_square_are_kept_as_unit_vectors() {
    let src = "v from 0 -5 0 at 0 0 0 up 0 0 1 angle 45\nl 1 -3 2\n\
               pp 3 -1 0 -1 0 -3e38 0  1 0 -1 0 -2e20 1e20  0 0 1 0 -1e-30 0\n";
    let scene = parse_ok(src);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let n = scene.triangles[0].n.clone().expect("smooth");
    for n in *n {
        assert!((n.length() - 1.0).abs() < 1e-6, "{n}");
    }
    assert_renders_finite(scene);
}

/// `render` target, as a bare STL: a facet normal of 3e38 0 0 is finite and non-zero, but
/// its squared length is infinite, so normalising it gave zero shading normals and NaN
/// pixels. It now reads as the unit normal it points along.
#[test]
fn stl_facet_normal_too_long_to_square_reads_as_a_unit_normal() {
    let tri = Triangle {
        v: [Vec3::ZERO, Vec3::X, Vec3::Y],
        n: Some(Box::new([Vec3::new(3e38, 0.0, 0.0); 3])),
        material: MaterialId(0),
        uv: None,
    };
    let bytes = stl::write_binary(&[tri], &[b'x'; 80]);
    let tris = stl::parse(&bytes, "t.stl").unwrap();
    assert_eq!(tris[0].n.as_deref(), Some(&[Vec3::X; 3]));
    let dir = temp_dir("fuzzed-stl");
    let path = dir.join("huge-normal.stl");
    std::fs::write(&path, &bytes).unwrap();
    assert_renders_finite(scene::load(&path).unwrap());
}

/// Found reviewing the STL finding: a `mesh` scaled by 1e-20 along x turns its shading
/// normals (by the inverse transpose) into vectors of length 1e20, whose squared length
/// overflows; they normalised to zero and rendered NaN.
#[test]
fn mesh_with_extreme_non_uniform_scale_keeps_unit_normals() {
    let dir = temp_dir("fuzzed-mesh-scale");
    let obj = "v -1 0 -1\nv 1 0 -1\nv 0 0 1\nvn 1 -1 0\nvn 1 -1 0\nvn 1 -1 0\nf 1//1 2//2 3//3\n";
    std::fs::write(dir.join("tri.obj"), obj).unwrap();
    let src = "v from 0 -5 0 at 0 0 0 up 0 0 1 angle 45\nl 1 -3 2\n\
               mesh tri.obj scale 1e-20 1 1\n";
    let scene = nff::parse(src.as_bytes(), "t.nff", &dir).unwrap();
    let n = scene.triangles[0].n.clone().expect("smooth");
    for n in *n {
        assert!((n.length() - 1.0).abs() < 1e-6, "{n}");
    }
    assert_renders_finite(scene);
}

/// Whatever a library caller puts in a `Scene`, `pack` gives the renderers unit shading
/// normals or none: a triangle with a normal that has no direction is packed flat.
#[test]
fn pack_shades_triangles_with_unusable_normals_flat() {
    let mut scene = parse_ok("v from 0 -5 0 at 0 0 0 up 0 0 1 angle 45\nl 1 -3 2\n");
    let v = [
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::Z,
    ];
    let bad = [Vec3::ZERO, Vec3::NAN, Vec3::INFINITY];
    for b in bad {
        scene.triangles.push(Triangle {
            v,
            n: Some(Box::new([Vec3::NEG_Y, b, Vec3::NEG_Y])),
            material: MaterialId(0),
            uv: None,
        });
    }
    scene.triangles.push(Triangle {
        v,
        n: Some(Box::new([Vec3::new(0.0, -3e38, 3e38); 3])),
        material: MaterialId(0),
        uv: None,
    });
    scene.materials.push(scene::Material::DEFAULT);
    let buffers = gpurt::pack::pack(scene.clone()).unwrap();
    assert_eq!(
        buffers.tri_normals.len(),
        1,
        "only the last triangle is smooth"
    );
    let n = buffers.tri_normals[0];
    for n in [n.n0, n.n1, n.n2] {
        assert!((n.length() - 1.0).abs() < 1e-6, "{n}");
    }
    assert_renders_finite(scene);
}

/// `render` target (minimised from its crash artifact): seen from inside a sphere of radius
/// 6.7e7, a mirror ray comes back from 6.7e7 away to a sphere of radius 0.5, and rounding
/// at that distance (8 units) puts the hit point exactly on the small sphere's centre,
/// where `normalize(x - centre)` is 0 / 0. The pixel was NaN; a hit whose normal is
/// undefined now faces the ray.
#[test]
fn hit_point_rounded_onto_a_sphere_centre_renders_finite() {
    let src = "v from 2 3 7 at 0 0 0 up 0 0 1 angle 45\nl 4 3 2\n\
               f 1 1 0 0 1 0 0 1\ns 0 0 0 .5\ns 0 0 6 66616067\n";
    assert_renders_finite(parse_ok(src));
}

/// The same undefined normals at the unit level: a hit on a sphere's centre, on a cone's
/// axis, and a shading normal that interpolates to zero between opposite vertex normals
/// all give finite unit normals.
#[test]
fn surface_normals_are_finite_where_the_geometry_has_none() {
    use gpurt::cpu::shade::surface;
    use gpurt::cpu::types::{Bindings, Hit, Ray};
    let src = "v from 0 -5 0 at 0 0 0 up 0 0 1 angle 45\nl 1 -3 2\n\
               s 0 0 0 1\nc 3 0 0 1 3 0 2 0\n\
               pp 3 -1 1 -1 1 0 0  1 1 -1 -1 0 0  0 1 1 1 0 0\n";
    let buffers = gpurt::pack::pack(parse_ok(src)).unwrap();
    let scene = parse_ok(src);
    let opts = RenderOptions::for_camera(&scene.camera);
    let globals = frame::globals(&buffers, &opts);
    let b = Bindings::new(&buffers, &globals);
    let prim = |kind: u32| buffers.prims.iter().position(|p| p.kind() == kind).unwrap() as u32;
    // Barycentrics (u, v) halfway between the two corners with opposite normals.
    let n = buffers.tri_normals[0];
    let edge = if n.n0 == -n.n1 {
        (0.5, 0.0)
    } else if n.n0 == -n.n2 {
        (0.0, 0.5)
    } else {
        assert_eq!(n.n1, -n.n2);
        (0.5, 0.5)
    };
    let cases = [
        // The ray's hit point is the sphere's centre.
        (
            prim(gpurt::gpu_types::PRIM_SPHERE),
            Vec3::new(0.0, -5.0, 0.0),
            5.0,
            (0.0, 0.0),
        ),
        // The cone's apex, on its axis.
        (
            prim(gpurt::gpu_types::PRIM_CONE),
            Vec3::new(3.0, -5.0, 2.0),
            5.0,
            (0.0, 0.0),
        ),
        // Halfway between two of the patch's corners whose normals are +x and -x.
        (
            prim(gpurt::gpu_types::PRIM_TRIANGLE),
            Vec3::new(0.0, -4.0, -1.0),
            5.0,
            edge,
        ),
    ];
    for (i, (prim, origin, t, (u, v))) in cases.into_iter().enumerate() {
        let ray = Ray {
            origin,
            dir: Vec3::Y,
        };
        let hit = Hit {
            t,
            prim,
            u,
            v,
            cost: 0,
            nodes: 0,
        };
        let s = surface(&b, &ray, &hit);
        for n in [s.ng, s.ns] {
            assert!(
                n.is_finite() && (n.length() - 1.0).abs() < 1e-5,
                "case {i}: {n}"
            );
        }
    }
}

/// `gltf` target: an image with neither a `uri` nor a `bufferView` panicked inside the
/// `gltf` crate (`Image::source` unwraps one of them, as it does a buffer view's
/// `mimeType`), which its validation lets through. Both are now warnings naming the image,
/// and the surfaces keep their material's colour.
#[test]
fn gltf_images_without_a_source_or_a_mime_type_are_warnings() {
    let glb = std::fs::read(crate::common::own_scenes().join("textured.glb")).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let images = doc["images"].as_array_mut().unwrap();
    images[0].as_object_mut().unwrap().clear();
    images[1].as_object_mut().unwrap().remove("mimeType");
    // The binary chunk: its length, its type, its bytes.
    let bin = &glb[20 + json_len + 8..];
    let out = crate::common::inputs::glb(doc.to_string().as_bytes(), bin);
    let path = temp_dir("fuzzed-gltf-image").join("no-source.glb");
    std::fs::write(&path, out).unwrap();
    let s = scene::load(&path).expect("reads");
    assert!(s.textures.is_empty());
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);
    assert!(s.warnings[0].contains(
        "image 0 (the base colour of material 0) is not used: neither a uri nor a buffer view"
    ));
    assert!(s.warnings[1].contains(
        "image 1 (the base colour of material 1) is not used: a buffer view without a mimeType"
    ));
    assert_renders_finite(s);
}
