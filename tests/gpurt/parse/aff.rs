//! BART's animated NFF (AFF): objects placed where the keyframe splines put them, checked
//! against Kochanek-Bartels' formula written out here; fixed and animated blocks nested;
//! visibility, the camera and lights; the statements gpurt reads but does not render
//! warned of; and bad input refused at its line and column.

use glam::Vec3;
use gpurt::Error;
use gpurt::scene::Scene;

use crate::common::inputs::{VIEW, assert_error, parse_nff, parse_ok};

/// Kochanek-Bartels through `keys` (time, value, tension, continuity, bias) at time `t`
/// in the segment from key `i` to key `i + 1`, as the textbook writes it: Hermite between
/// the two keys, the outgoing tangent of key `i` and the incoming tangent of key `i + 1`
/// each a weighted sum of the chords either side, scaled for the keys' spacing in time.
fn kochanek_bartels(keys: &[(f64, f64, f64, f64, f64)], i: usize, t: f64) -> f64 {
    let p = |k: usize| keys[k].1;
    let time = |k: usize| keys[k].0;
    let (_, _, tn, c, b) = keys[i];
    let outgoing = 2.0 * (time(i + 1) - time(i)) / (time(i + 1) - time(i - 1))
        * ((1.0 - tn) * (1.0 + c) * (1.0 + b) / 2.0 * (p(i) - p(i - 1))
            + (1.0 - tn) * (1.0 - c) * (1.0 - b) / 2.0 * (p(i + 1) - p(i)));
    let (_, _, tn, c, b) = keys[i + 1];
    let incoming = 2.0 * (time(i + 1) - time(i)) / (time(i + 2) - time(i))
        * ((1.0 - tn) * (1.0 - c) * (1.0 + b) / 2.0 * (p(i + 1) - p(i))
            + (1.0 - tn) * (1.0 + c) * (1.0 - b) / 2.0 * (p(i + 2) - p(i + 1)));
    let s = (t - time(i)) / (time(i + 1) - time(i));
    let (h00, h10) = (
        2.0 * s.powi(3) - 3.0 * s * s + 1.0,
        s.powi(3) - 2.0 * s * s + s,
    );
    let (h01, h11) = (-2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
    h00 * p(i) + h10 * outgoing + h01 * p(i + 1) + h11 * incoming
}

/// Keys unevenly spaced in time, with tension, continuity and bias of every sign.
const KEYS: [(f64, f64, f64, f64, f64); 5] = [
    (-0.5, 2.0, 0.0, 0.0, 0.0),
    (0.0, 0.0, 0.3, -0.2, 0.4),
    (0.4, 3.0, -0.1, 0.5, -0.3),
    (1.5, -1.0, 0.2, 0.1, 0.0),
    (2.0, 4.0, 0.0, 0.0, 0.0),
];

fn key_rows(angle: bool) -> String {
    KEYS.iter()
        .map(|(t, v, tn, c, b)| match angle {
            // A turn of v * 30 degrees about z.
            true => format!("{t} 0 0 1 {}  {tn} {c} {b}\n", v * 30.0),
            // A move along x, the others still.
            false => format!("{t} {v} 5 -2  {tn} {c} {b}\n"),
        })
        .collect()
}

fn ball_at(scene: &Scene) -> Vec3 {
    assert_eq!(scene.spheres.len(), 1, "one ball");
    scene.spheres[0].center
}

#[test]
fn a_translation_follows_the_kochanek_bartels_spline() {
    let src = format!(
        "{VIEW}a 0 1.5 10\nx ball {{\n s 0 0 0 0.5\n}}\nk ball {{\n transl 5\n{}}}\n",
        key_rows(false)
    );
    let scene = parse_ok(&src);
    assert!(
        scene.spheres.is_empty(),
        "the ball moves: not among the still primitives"
    );
    for t in [0.0, 0.1, 0.25, 0.4, 0.7, 1.0, 1.3, 1.5] {
        let i = if t < 0.4 { 1 } else { 2 };
        let want = kochanek_bartels(&KEYS, i, t);
        let at = ball_at(&scene.clone().at(t));
        assert!(
            (f64::from(at.x) - want).abs() < 1e-5,
            "t = {t}: x = {} against the formula's {want}",
            at.x
        );
        assert_eq!((at.y, at.z), (5.0, -2.0), "t = {t}");
    }
    // Outside the keys that the curve spans, it holds still at their ends.
    assert_eq!(ball_at(&scene.clone().at(-3.0)), Vec3::new(0.0, 5.0, -2.0));
    assert_eq!(ball_at(&scene.clone().at(9.0)), Vec3::new(-1.0, 5.0, -2.0));
}

#[test]
fn a_rotation_about_one_axis_follows_the_spline_of_its_angles() {
    // Squad about one axis is the Hermite curve of the angles (BART's quaternion keys
    // reduce to its position formula there).
    let src = format!(
        "{VIEW}x arm {{\n s 1 0 0 0.1\n}}\nk arm {{\n rot 5\n{}}}\n",
        key_rows(true)
    );
    let scene = parse_ok(&src);
    for t in [0.0, 0.2, 0.4, 0.9, 1.5] {
        let i = if t < 0.4 { 1 } else { 2 };
        let want = kochanek_bartels(&KEYS, i, t) * 30.0;
        let c = ball_at(&scene.clone().at(t));
        let got = f64::from(c.y.atan2(c.x).to_degrees());
        let diff = (got - want).rem_euclid(360.0);
        assert!(
            diff.min(360.0 - diff) < 1e-3,
            "t = {t}: {got} degrees against {want}"
        );
        assert!((c.length() - 1.0).abs() < 1e-5);
    }
}

#[test]
fn blocks_nest_fixed_and_animated_transforms_in_order() {
    // Scale 2 then move by (10, 0, 0), around a block moving by the track, around a
    // sphere at (1, 0, 0): T_fixed * T_track(t) * p.
    let src = format!(
        "{VIEW}xs 2 2 2  0 0 1 0  10 0 0 {{\n x slide {{\n  s 1 0 0 0.25\n }}\n p 3\n 0 0 0\n 1 0 0\n 0 1 0\n}}\n\
         k slide {{\n transl 4\n 0 0 0 0 0 0 0\n 1 0 0 0 0 0 0\n 2 0 3 0 0 0 0\n 3 0 3 0 0 0 0\n}}\n"
    );
    let scene = parse_ok(&src);
    // The still triangle is placed once, as it is read.
    assert_eq!(scene.triangles[0].v[1], Vec3::new(12.0, 0.0, 0.0));
    let at = |t| scene.clone().at(t);
    assert_eq!(ball_at(&at(1.0)), Vec3::new(12.0, 0.0, 0.0));
    assert_eq!(at(1.0).spheres[0].radius, 0.5);
    let end = ball_at(&at(2.0));
    assert!((end - Vec3::new(12.0, 6.0, 0.0)).length() < 1e-5, "{end}");
}

#[test]
fn visibility_keys_hide_and_show_and_the_camera_and_lights_move() {
    let src = format!(
        "{VIEW}la lamp 0 0 1\nx blink {{\n s 0 0 0 1\n}}\n\
         k blink {{\n visibility 2\n 1 0\n 2 1\n}}\n\
         k lamp {{\n transl 4\n 0 0 0 0 0 0 0\n 1 0 0 0 0 0 0\n 2 4 0 0 0 0 0\n 3 4 0 0 0 0 0\n}}\n\
         k camera {{\n transl 4\n 0 0 -5 0 0 0 0\n 1 0 -5 0 0 0 0\n 2 0 -9 0 0 0 0\n 3 0 -9 0 0 0 0\n\
         rot 4\n 0 1 0 0 90 0 0 0\n 1 1 0 0 90 0 0 0\n 2 1 0 0 90 0 0 0\n 3 1 0 0 90 0 0 0\n}}\n"
    );
    let scene = parse_ok(&src);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(
        scene.clone().at(0.5).spheres.len(),
        1,
        "shown before the first key"
    );
    assert!(scene.clone().at(1.5).spheres.is_empty(), "hidden from 1");
    assert_eq!(scene.clone().at(2.0).spheres.len(), 1, "shown again from 2");
    let later = scene.clone().at(2.0);
    let gpurt::scene::Light::Point { position, .. } = later.lights[0] else {
        panic!("a point light")
    };
    assert_eq!(position, Vec3::new(4.0, 0.0, 1.0));
    // The camera moved to the track's translation, looking down its local -z turned 90
    // degrees about x: along +y, with its local y (now +z) up.
    let cam = &later.camera;
    assert_eq!(cam.from, Vec3::new(0.0, -9.0, 0.0));
    let dir = (cam.at - cam.from).normalize();
    assert!((dir - Vec3::Y).length() < 1e-5, "{dir}");
    assert!((cam.up - Vec3::Z).length() < 1e-5, "{}", cam.up);
}

#[test]
fn aff_meshes_materials_and_includes_are_read() {
    let d = crate::common::workdir("aff-include");
    std::fs::write(
        d.join("part.aff"),
        "m vertices 4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\ntriangles 2\n0 1 2\n0 2 3\n",
    )
    .unwrap();
    std::fs::write(d.join("fine.aff"), "s 0 0 0 1\n").unwrap();
    let src = format!(
        "{VIEW}fm 0.1 0.05 0  0.5 0.25 0.1  0.6 0.6 0.6  30 0 1\nd 1\nxs 1 1 1 0 0 1 0 0 0 5 {{\n i 1 part.aff\n}}\ni 2 fine.aff\n"
    );
    let scene = gpurt::scene::nff::parse(src.as_bytes(), "t.aff", &d).unwrap();
    assert_eq!(scene.triangles.len(), 2, "the mesh, placed by its block");
    assert_eq!(scene.triangles[1].v[2], Vec3::new(0.0, 1.0, 5.0));
    assert!(
        scene.spheres.is_empty(),
        "level 2 is above the detail level 1"
    );
    let m = scene.materials[scene.triangles[0].material.0 as usize];
    assert_eq!(
        (m.color, m.kd, m.ks, m.shine, m.ambient),
        (
            Vec3::new(0.5, 0.25, 0.1),
            1.0,
            0.6,
            30.0,
            Some(Vec3::new(0.1, 0.05, 0.0))
        )
    );
}

#[test]
fn textures_are_found_beside_the_file_or_in_texture_files_beside_its_folder() {
    let d = crate::common::workdir("aff-textures");
    std::fs::create_dir_all(d.join("aff")).unwrap();
    std::fs::create_dir_all(d.join("TextureFiles")).unwrap();
    // A 2 x 1 PPM (P3), red and blue, as BART's textures are (binary there).
    std::fs::write(
        d.join("TextureFiles/wood.ppm"),
        "P3\n2 1\n255\n255 0 0  0 0 255\n",
    )
    .unwrap();
    let src = format!(
        "{VIEW}f 1 1 1 1 0 1 0 1\ntt wood.ppm\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n\
         m vertices 3\n0 0 1\n1 0 1\n0 1 1\ntexturecoords 3 wood.ppm\n0 0\n1 0\n0 1\n\
         triangles 1\n0 1 2 0 1 2\ns 0 0 5 1\n"
    );
    let scene = gpurt::scene::nff::parse(src.as_bytes(), "t.aff", &d.join("aff")).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.textures.len(), 1, "read once for both");
    assert_eq!((scene.textures[0].width, scene.textures[0].height), (2, 1));
    let texture_of = |m: gpurt::scene::MaterialId| scene.materials[m.0 as usize].texture;
    assert_eq!(texture_of(scene.triangles[0].material), Some(0));
    assert_eq!(texture_of(scene.triangles[1].material), Some(0));
    assert_eq!(
        texture_of(scene.spheres[0].material),
        None,
        "the current material stays"
    );
}

#[test]
fn what_gpurt_does_not_render_is_warned_of_at_its_place() {
    let src = format!(
        "{VIEW}tt wood.ppm\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\ntpa 1\n0\n{}",
        "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"
    );
    let scene = parse_ok(&src);
    assert_eq!(scene.triangles.len(), 1);
    assert!(scene.triangles[0].uv.is_some(), "texture coordinates kept");
    let w = scene.warnings.join("\n");
    assert!(
        w.contains("t.nff:6:1: texture 'wood.ppm' not applied: no such file"),
        "{w}"
    );
    assert!(
        w.contains("t.nff:10:1: animated triangles ('tpa') are not rendered"),
        "{w}"
    );
}

#[test]
fn bad_animation_input_is_refused_where_it_is() {
    let track = |rows: &str| format!("{VIEW}x b {{\n s 0 0 0 1\n}}\nk b {{\n{rows}}}\n");
    // Keys out of order: at the time that goes back.
    assert_error(
        &track("transl 4\n0 0 0 0 0 0 0\n1 0 0 0 0 0 0\n0.5 0 0 0 0 0 0\n2 0 0 0 0 0 0\n"),
        13,
        1,
        &["keyframe time 0.5 is before", "line 12"],
    );
    // A spline of one key.
    assert_error(
        &track("rot 1\n0 0 0 1 0 0 0 0\n"),
        10,
        5,
        &["'rot' needs at least 4 keys", "found 1"],
    );
    assert_error(&track("spin 4\n"), 10, 1, &["expected keyframes", "'spin'"]);
    assert_error(
        &format!("{VIEW}xs 1 1 1 0 0 1 0 0 0 0 {{\n s 0 0 0 1\n"),
        6,
        1,
        &["never closed"],
    );
    assert_error(&format!("{VIEW}}}\n"), 6, 1, &["closes no block"]);
    assert_error(&format!("{VIEW}a 0 1 0\n"), 6, 7, &["at least one frame"]);
    assert_error(
        &format!("{VIEW}xs 1 0 1 0 0 1 0 0 0 0 {{\n}}\n"),
        6,
        1,
        &["scale"],
    );
    // A transform whose name no keyframes define: at the name, in the file it is used.
    match parse_nff(&format!("{VIEW}s 0 0 0 1\nx ghost {{\n s 0 0 0 1\n}}\n")) {
        Err(Error::Parse {
            file,
            line,
            col,
            msg,
            ..
        }) => {
            assert_eq!((file.as_str(), line, col), ("t.nff", 7, 3));
            assert!(msg.contains("'ghost' has no keyframes"), "{msg}");
        }
        other => panic!("expected an error naming the transform, got {other:?}"),
    }
}

#[test]
fn a_second_k_for_a_name_keeps_the_first_and_warns_only_where_keys_differ() {
    let keys = |x: f32| {
        format!(
            "k b {{\n transl 4\n 0 {x} 0 0 0 0 0\n 1 {x} 0 0 0 0 0\n 2 {x} 0 0 0 0 0\n 3 {x} 0 0 0 0 0\n}}\n"
        )
    };
    let src = format!("{VIEW}x b {{\n s 0 0 0 1\n}}\n{}{}", keys(1.0), keys(1.0));
    let scene = parse_ok(&src);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let src = format!("{VIEW}x b {{\n s 0 0 0 1\n}}\n{}{}", keys(1.0), keys(5.0));
    let scene = parse_ok(&src);
    assert_eq!(
        scene.clone().at(1.5).spheres[0].center.x,
        1.0,
        "the first keys"
    );
    assert!(
        scene.warnings[0].contains("t.nff:16:1: a second 'k b' with other keys"),
        "{:?}",
        scene.warnings
    );
}

/// What BART's own scenes hold that the format's rules refuse, read under `--lenient` as
/// BART's previewer reads it: keys that go back in time left out, a transform without
/// keys still; and `%` comments, which AFF has beside `#`.
#[test]
fn lenient_reads_what_barts_scenes_hold() {
    use gpurt::scene::{ReadOptions, nff};
    let lenient = ReadOptions {
        lenient: true,
        ..ReadOptions::default()
    };
    let src = format!(
        "{VIEW}% a comment in AFF's way\n%another-one 1 2 3\nx b {{\n s 0 0 0 1\n}}\nx still {{\n s 5 0 0 1\n}}\n\
         k b {{\n transl 6\n 0 0 0 0 0 0 0\n 1 1 0 0 0 0 0\n 2 2 0 0 0 0 0\n 3 3 0 0 0 0 0\n 1.5 9 9 9 0 0 0\n 4 4 0 0 0 0 0\n}}\n"
    );
    assert!(parse_nff(&src).is_err(), "refused by default");
    let scene =
        nff::parse_with(src.as_bytes(), "t.nff", std::path::Path::new("."), &lenient).unwrap();
    let w = scene.warnings.join("\n");
    assert!(
        w.contains("t.nff:20:2: keyframe time 1.5 is before the previous key's 3"),
        "{w}"
    );
    assert!(
        w.contains("t.nff:11:3: transform 'still' has no keyframes"),
        "{w}"
    );
    let at = scene.clone().at(2.0);
    let xs: Vec<f32> = at.spheres.iter().map(|s| s.center.x).collect();
    assert!(xs.contains(&2.0) && xs.contains(&5.0), "{xs:?}");
}

/// A frame packed with the still part's tree kept and the moving part's refitted holds the
/// same triangles as the whole scene packed anew: each with its own corners, shading
/// normals and texture coordinates, however the two parts' slots were renumbered when
/// joined (both parts have normals and coordinates here).
#[test]
fn a_frame_with_its_still_tree_kept_holds_what_a_whole_pack_holds() {
    use gpurt::pack::SceneBuffers;
    use gpurt::pack::frames::{FramePacker, FrameTree, TreeMode};
    use gpurt::scene::FlatScene;

    let d = crate::common::workdir("aff-frames");
    std::fs::write(d.join("wood.ppm"), "P3\n2 1\n255\n255 0 0  0 0 255\n").unwrap();
    // Two textured patches (corners, normals, coordinates), one still and one in a
    // moving block, and a plain mesh with normals in each part.
    let patch = |z: f32| {
        format!("ttp wood.ppm\n0 0 {z} 0 0 1 0 0\n1 0 {z} 0 0.6 0.8 1 0\n0 1 {z} 0.6 0 0.8 0 1\n")
    };
    let mesh = |z: f32| {
        format!(
            "m vertices 3\n0 0 {z}\n1 0 {z}\n0 1 {z}\nnormals 3\n0 0 1\n0 1 0\n1 0 0\ntriangles 1\n0 1 2 0 1 2\n"
        )
    };
    let src = format!(
        "{VIEW}a 0 1 4\nf 1 1 1 1 0 1 0 1\n{}{}x spin {{\n{}{}}}\n\
         k spin {{\n transl 4\n -1 0 0 0 0 0 0\n 0 0 0 0 0 0 0\n 1 2 0 0 0 0 0\n 2 2 0 0 0 0 0\n}}\n",
        patch(0.0),
        mesh(1.0),
        mesh(2.0),
        patch(3.0),
    );
    let mut scene = gpurt::scene::nff::parse(src.as_bytes(), "t.aff", &d).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let animation = *scene.animation.take().unwrap();
    let still = FlatScene::from_scene(scene);
    // Every triangle as the bits of its corners (first vertex and edges), normals and
    // coordinates, sorted: what a frame holds, whatever its order.
    let triangles = |b: &SceneBuffers| {
        let mut all: Vec<Vec<u32>> = b
            .prims
            .iter()
            .map(|p| {
                let mut v: Vec<f32> = [p.p0, p.p1, p.p2]
                    .iter()
                    .flat_map(|c| c.to_array())
                    .collect();
                if p.f1 >= 0.0 {
                    let n = b.tri_normals[p.f1 as usize];
                    v.extend([n.n0, n.n1, n.n2].iter().flat_map(|c| c.to_array()));
                }
                if p.f0 >= 0.0 {
                    let uv = b.tri_uvs[p.f0 as usize - b.tri_normals.len()];
                    v.extend([uv.uv0, uv.uv1, uv.uv2].iter().flat_map(|c| c.to_array()));
                }
                v.into_iter().map(f32::to_bits).collect()
            })
            .collect();
        all.sort();
        all
    };
    let packer = |mode| FramePacker::new(still.clone(), animation.clone(), true, 1, 4, mode);
    let (mut whole, mut kept) = (
        packer(TreeMode::Whole).unwrap(),
        packer(TreeMode::Refit).unwrap(),
    );
    for (frame, t) in [0.0, 0.5, 1.0].into_iter().enumerate() {
        let (a, how_a) = whole.pack(t).unwrap();
        let (b, how_b) = kept.pack(t).unwrap();
        assert_eq!(how_a, FrameTree::Whole);
        let expected = if frame == 0 {
            FrameTree::Rebuilt
        } else {
            FrameTree::Refitted(0.0)
        };
        assert_eq!(
            std::mem::discriminant(&how_b),
            std::mem::discriminant(&expected)
        );
        assert_eq!(a.prims.len(), 4);
        assert_eq!(triangles(&a), triangles(&b), "t = {t}");
        assert_eq!(a.bounds, b.bounds);
    }
}
