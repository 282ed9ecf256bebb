//! The CPU reference renderer against closed forms: scenes written inline as NFF, expected
//! pixel values computed here in f64 from docs/shading.md (camera rays, sphere and plane
//! intersections, Lambert, Phong, ambient, shadows, mirrors, Snell), never stored numbers.
//! Plus: every shared scene and every scene of our own renders to finite values, with
//! hits and background where the scene's own geometry puts them; renders are bit-for-bit
//! deterministic (also across thread counts), and the AOVs are sane.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use glam::{DVec3, Vec3};
use gpurt::cpu::shade::trace;
use gpurt::cpu::tracer::Alone;
use gpurt::cpu::types::{Bindings, Ray, RayCounts};
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::*;
use gpurt::limits::DEFAULT_AMBIENT;
use gpurt::pack;
use gpurt::scene::{self, Scene};

use crate::common::inputs::HALF_COLUMN;
use crate::common::oracle::{Camera, column_mean, d, sphere_hit, triangle_hit};
use crate::common::{files_with, shared_scenes};

/// The spec's 8-bit quantum: analytic values must match to within one level.
const ONE_LEVEL: f64 = 1.0 / 255.0;

fn parse(src: &str) -> Scene {
    scene::nff::parse(src.as_bytes(), "inline", Path::new(".")).expect("inline scene parses")
}

fn render_with(scene: &Scene, opts: &RenderOptions) -> Film {
    let buffers = pack::pack(scene.clone()).expect("scene packs");
    let globals = frame::globals(&buffers, opts);
    let never = AtomicBool::new(false);
    let (film, _) = gpurt::cpu::render(&buffers, &globals, &|_| {}, &never)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
    film
}

fn render(scene: &Scene) -> Film {
    render_with(scene, &RenderOptions::for_camera(&scene.camera))
}

fn pixel(film: &Film, x: u32, y: u32) -> DVec3 {
    let [r, g, b] = film.get(x, y);
    DVec3::new(r as f64, g as f64, b as f64)
}

/// Distance from `c` to the segment `a -> b`.
fn segment_distance(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let ab = b - a;
    let s = ((c - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (a + s * ab - c).length()
}

fn assert_close(got: DVec3, want: DVec3, tol: f64, what: &str) {
    let err = (got - want).abs().max_element();
    assert!(
        err <= tol,
        "{what}: got {got}, want {want} (off by {err:.2e})"
    );
}

/// Pixels with nothing in view show the background, exactly, whatever the sampling.
#[test]
fn empty_scene_is_background_everywhere() {
    let scene = parse(
        "b 0.2 0.4 0.6\n\
         v from 1 2 3 at 0 0 0 up 0 0 1 angle 50 hither 0.01 resolution 20 12\n",
    );
    let mut opts = RenderOptions::for_camera(&scene.camera);
    for spp in [1, 5] {
        opts.spp = spp;
        let film = render_with(&scene, &opts);
        assert_eq!((film.width, film.height), (20, 12));
        for (i, p) in film.pixels.iter().enumerate() {
            assert_eq!(*p, [0.2, 0.4, 0.6], "pixel {i} at {spp} spp");
        }
    }
}

/// One sphere (convex: it never shadows itself), lit by uncoloured point lights:
/// ambient + sum over lights of I (Kd C N.L + Ks max(R.L, 0)^Shine) + Ks background,
/// with I = 1/sqrt(n_lights). Checked at every pixel away from the silhouette.
fn check_lit_sphere(material: &str, lights: &[DVec3]) {
    let (c, r) = (DVec3::new(0.3, 0.2, 0.5), 1.5);
    let mut src =
        "b 0.05 0.1 0.15\nv from 0 -8 3 at 0 0 0.5 up 0 0 1 angle 35 hither 0.5 resolution 48 48\n"
            .to_string();
    for l in lights {
        src += &format!("l {} {} {}\n", l.x, l.y, l.z);
    }
    src += &format!("f {material}\ns {} {} {} {r}\n", c.x, c.y, c.z);
    let scene = parse(&src);
    let bg = d(scene.background);
    let m = scene.materials[0];
    let (kd_c, ks, shine) = (m.kd as f64 * d(m.color), m.ks as f64, m.shine as f64);
    let intensity = 1.0 / (lights.len() as f64).sqrt();
    let film = render(&scene);
    let cam = Camera::of(&scene);
    let (mut lit, mut dark, mut highlit) = (0, 0, 0);
    for (x, y) in cam.pixels() {
        let dir = cam.dir(x, y);
        let (t, clarity) = sphere_hit(cam.from, dir, c, r, cam.hither);
        if clarity.abs() < 1e-3 {
            continue;
        }
        let Some(t) = t else {
            assert_close(pixel(&film, x, y), bg, 0.0, &format!("miss at ({x}, {y})"));
            continue;
        };
        let p = cam.from + t * dir;
        let n = (p - c) / r;
        let refl = dir - 2.0 * n.dot(dir) * n;
        let mut want = DEFAULT_AMBIENT as f64 * kd_c + ks * bg;
        for &light in lights {
            let l = (light - p).normalize();
            let ndotl = n.dot(l);
            if ndotl <= 0.0 {
                dark += 1;
                continue;
            }
            lit += 1;
            let highlight = ks * refl.dot(l).max(0.0).powf(shine);
            highlit += usize::from(highlight > 0.05);
            want += intensity * (kd_c * ndotl + DVec3::splat(highlight));
        }
        assert_close(
            pixel(&film, x, y),
            want,
            ONE_LEVEL,
            &format!("pixel ({x}, {y})"),
        );
    }
    // Both sides of the terminator must have been seen, or the test proved little.
    assert!(
        lit > 200 && dark > 20,
        "{lit} lit and {dark} dark pixel-light pairs"
    );
    if ks > 0.0 {
        assert!(highlit > 5, "only {highlit} highlight pixels");
    }
}

#[test]
fn matte_sphere_is_lambert_plus_ambient() {
    check_lit_sphere("0.9 0.6 0.3 0.75 0 1 0 0", &[DVec3::new(4.0, -5.0, 6.0)]);
}

#[test]
fn two_uncoloured_lights_share_one_over_sqrt_n() {
    check_lit_sphere(
        "0.9 0.6 0.3 0.75 0 1 0 0",
        &[DVec3::new(4.0, -5.0, 6.0), DVec3::new(-6.0, -2.0, -1.0)],
    );
}

#[test]
fn shiny_sphere_adds_phong_highlight_and_reflected_background() {
    check_lit_sphere("0.3 0.8 0.4 0.6 0.3 20 0 0", &[DVec3::new(4.0, -5.0, 6.0)]);
}

/// AFF's `fm` gives a material its own ambient colour: under ambient light alone every
/// pixel of the ball is the scene's ambient times that colour, to the bit, on the CPU and
/// on the GPU (not its diffuse colour, which NFF's `f` would use).
#[test]
fn an_fm_ambient_colour_is_the_ambient_term_on_both_backends() {
    let scene = parse(
        "b 0 0 0\n\
         v from 0 -6 0 at 0 0 0 up 0 0 1 angle 30 hither 0.1 resolution 32 32\n\
         am 0.5 0.5 0.5\n\
         fm 0.2 0.1 0.05  0.9 0.9 0.9  0 0 0  1 0 1\n\
         s 0 0 0 1\n",
    );
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let expected = (Vec3::splat(0.5) * Vec3::new(0.2, 0.1, 0.05)).to_array();
    let buffers = pack::pack(scene.clone()).unwrap();
    let globals = frame::globals(&buffers, &RenderOptions::for_camera(&scene.camera));
    let gpu = crate::common::versus::gpu();
    let mut films = vec![(
        "cpu",
        crate::common::versus::render_on(&buffers, &globals, None),
    )];
    if let Some(g) = gpu {
        films.push((
            "gpu",
            crate::common::versus::render_on(&buffers, &globals, Some(g)),
        ));
    }
    for (backend, film) in films {
        let ball: Vec<[f32; 3]> = (0..32)
            .flat_map(|y| (0..32).map(move |x| (x, y)))
            .map(|(x, y)| film.get(x, y))
            .filter(|p| p != &[0.0; 3])
            .collect();
        assert!(ball.len() > 100, "{backend}: {} ball pixels", ball.len());
        assert!(
            ball.iter().all(|p| p == &expected),
            "{backend}: {:?}",
            &ball[..3]
        );
    }
}

/// A floor quad under a sphere lit from straight above: floor points whose segment to the
/// light passes through the sphere get exactly the ambient term; the others, Lambert.
#[test]
fn shadowed_floor_gets_exactly_the_ambient_term() {
    let light = DVec3::new(0.0, 0.0, 10.0);
    let (c, r) = (DVec3::new(0.0, 0.0, 3.0), 1.0);
    let scene = parse(
        "b 0 0 0\n\
         v from 0 -10 8 at 0 0 0 up 0 0 1 angle 40 hither 0.1 resolution 64 64\n\
         l 0 0 10\n\
         f 0.8 0.7 0.6 0.9 0 1 0 0\n\
         p 4 -20 -20 0 20 -20 0 20 20 0 -20 20 0\n\
         f 0.3 0.3 0.9 0.8 0 1 0 0\n\
         s 0 0 3 1\n",
    );
    let floor = scene.materials[0];
    // The renderer's own f32 product, so "exactly" can be checked bit for bit.
    let ambient = Vec3::splat(DEFAULT_AMBIENT) * (floor.kd * floor.color);
    let kd_c = floor.kd as f64 * d(floor.color);
    let film = render(&scene);
    let cam = Camera::of(&scene);
    let (mut shadowed, mut lit) = (0, 0);
    for (x, y) in cam.pixels() {
        let dir = cam.dir(x, y);
        if dir.z >= 0.0 || sphere_hit(cam.from, dir, c, r, 0.0).1 > -0.05 {
            continue; // sky, or the sphere itself (or near its outline)
        }
        let p = cam.from + (-cam.from.z / dir.z) * dir;
        if p.x.abs() > 19.0 || p.y.abs() > 19.0 {
            continue;
        }
        let gap = segment_distance(p, light, c);
        let got = film.get(x, y);
        if gap < 0.95 * r {
            shadowed += 1;
            assert_eq!(got, ambient.to_array(), "shadowed floor at ({x}, {y}), {p}");
        } else if gap > 1.05 * r {
            lit += 1;
            let ndotl = (light - p).normalize().z;
            let want = DEFAULT_AMBIENT as f64 * kd_c + kd_c * ndotl;
            assert_close(
                pixel(&film, x, y),
                want,
                ONE_LEVEL,
                &format!("lit ({x}, {y})"),
            );
        }
    }
    assert!(shadowed > 30 && lit > 300, "{shadowed} shadowed, {lit} lit");
}

/// A mirror floor (`pl`, Kd 0.1, Ks 0.6) under a matte sphere, no lights, ambient 1: a
/// floor pixel is its own ambient term plus Ks times what the mirrored ray meets (the
/// sphere's ambient colour or the background). With depth 1 the reflection is not traced.
#[test]
fn mirror_reflects_with_weight_ks_up_to_the_depth_limit() {
    let (c, r) = (DVec3::new(0.0, 0.0, 2.0), 1.5);
    let scene = parse(
        "b 0.2 0.5 0.8\nam 1 1 1\n\
         v from 0 -10 4 at 0 0 1 up 0 0 1 angle 50 hither 0.1 resolution 64 64\n\
         f 1 1 1 0.1 0.6 100000 0 0\n\
         pl 0 0 0 1 0 0 0 1 0\n\
         f 0.9 0.2 0.1 0.8 0 1 0 0\n\
         s 0 0 2 1.5\n",
    );
    let bg = d(scene.background);
    let (mirror, ball) = (scene.materials[0], scene.materials[1]);
    let own = mirror.kd as f64 * d(mirror.color);
    let ball_colour = ball.kd as f64 * d(ball.color);
    let ks = mirror.ks as f64;
    let cam = Camera::of(&scene);
    let mut opts = RenderOptions::for_camera(&scene.camera);
    let film = render_with(&scene, &opts);
    opts.max_depth = 1;
    let flat = render_with(&scene, &opts);
    let (mut sees_ball, mut sees_sky) = (0, 0);
    for (x, y) in cam.pixels() {
        let dir = cam.dir(x, y);
        let (direct, clarity) = sphere_hit(cam.from, dir, c, r, cam.hither);
        if direct.is_some() || clarity > -0.05 || dir.z >= 0.0 {
            continue; // only pixels that clearly see the floor first
        }
        let p = cam.from + (-cam.from.z / dir.z) * dir;
        let mirrored = DVec3::new(dir.x, dir.y, -dir.z);
        let (hit, clarity) = sphere_hit(p, mirrored, c, r, 0.0);
        if clarity.abs() < 0.05 {
            continue;
        }
        let seen = if hit.is_some() {
            sees_ball += 1;
            ball_colour
        } else {
            sees_sky += 1;
            bg
        };
        let what = format!("floor pixel ({x}, {y})");
        assert_close(pixel(&film, x, y), own + ks * seen, 1e-5, &what);
        assert_close(pixel(&flat, x, y), own, 1e-6, &format!("{what} at depth 1"));
    }
    assert!(
        sees_ball > 50 && sees_sky > 50,
        "{sees_ball} see the ball, {sees_sky} the sky"
    );
}

/// A glass slab (`aabb`, z in [0, 1], ior 1.5, T 0.9, Kd = Ks = 0) over a target plane at
/// z = -2, red for x > 0 and green for x < 0. A ray at 40 degrees from the normal is
/// displaced as Snell says: sweeping its start along x, the colour must switch where the
/// refracted path meets the edge, not where the straight line would, and carry T^2.
#[test]
fn glass_slab_displaces_rays_as_snell_says() {
    let scene = parse(
        "b 0 0 0\nam 1 1 1\n\
         v from 0 0 10 at 0 0 0 up 0 1 0 angle 30 hither 0 resolution 8 8\n\
         f 1 1 1 0 0 1 0.9 1.5\n\
         aabb -50 50 -50 50 0 1\n\
         f 1 0 0 1 0 1 0 0\n\
         p 4 0 -50 -2 50 -50 -2 50 50 -2 0 50 -2\n\
         f 0 1 0 1 0 1 0 0\n\
         p 4 -50 -50 -2 0 -50 -2 0 50 -2 -50 50 -2\n",
    );
    let buffers = pack::pack(scene.clone()).unwrap();
    let globals = frame::globals(&buffers, &RenderOptions::for_camera(&scene.camera));
    let b = Bindings::new(&buffers, &globals);
    let theta = 40f64.to_radians();
    let dir = Vec3::new(theta.sin() as f32, 0.0, -theta.cos() as f32);
    let colour = |x0: f64| {
        let ray = Ray {
            origin: Vec3::new(x0 as f32, 0.3, 5.0),
            dir,
        };
        trace(&b, &mut Alone, &ray, &mut 0, &mut RayCounts::default())
    };
    let t2 = 0.9f32 * 0.9;
    let red = Vec3::new(t2, 0.0, 0.0);
    let green = Vec3::new(0.0, t2, 0.0);
    // Start at z = 5: 4 to the slab, 1 through it at the refracted angle, 2 below it;
    // each secondary ray starts `epsilon` past the surface it leaves (shading.md), which
    // shortens the next leg by that much in z (it moves the edge by 9e-4 here).
    let eps = buffers.epsilon as f64;
    let refracted = (theta.sin() / 1.5).asin();
    let edge = -(4.0 * theta.tan() + (1.0 - eps) * refracted.tan() + (2.0 - eps) * theta.tan());
    let straight = -7.0 * theta.tan();
    assert!(
        (edge - straight).abs() > 0.3,
        "the test must tell them apart"
    );
    let (mut lo, mut hi) = (edge - 1.0, edge + 1.0);
    let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
    assert!(near(colour(lo), green), "{}", colour(lo));
    assert!(near(colour(hi), red), "{}", colour(hi));
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        let c = colour(mid);
        assert!(near(c, red) || near(c, green), "at x = {mid}: {c}");
        if near(c, red) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    assert!(
        (hi - edge).abs() < 2e-5,
        "colour switches at x = {hi}, Snell says {edge} (straight line: {straight})"
    );
}

/// Every scene file of ours and every shared scene (including the big gzipped ones) at
/// 64 x 64: no error, every channel finite and not negative; and the image is the scene's,
/// by `check_against_the_scene`.
fn check_renders_finite(files: &[PathBuf]) {
    let mut seen = Vec::new();
    for path in files {
        let scene = scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut opts = RenderOptions::for_camera(&scene.camera);
        (opts.width, opts.height) = (64, 64);
        let buffers = pack::pack(scene.clone()).expect("scene packs");
        let render = |opts: &RenderOptions| {
            let never = AtomicBool::new(false);
            let globals = frame::globals(&buffers, opts);
            let (film, _) = gpurt::cpu::render(&buffers, &globals, &|_| {}, &never)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            film
        };
        let film = render(&opts);
        for (i, p) in film.pixels.iter().enumerate() {
            assert!(
                p.iter().all(|c| c.is_finite() && *c >= 0.0),
                "{}: pixel {i} is {p:?}",
                path.display()
            );
        }
        // A scene that renders uniformly would hide a broken camera or empty buffers.
        assert!(
            film.pixels.iter().any(|p| *p != film.pixels[0]),
            "{}: uniform image",
            path.display()
        );
        if scene.camera.aperture > 0.0 {
            // A thin lens has no one eye ray a pixel; its scene is checked elsewhere.
            continue;
        }
        let depth = render(&RenderOptions {
            aov: AOV_DEPTH,
            ..opts
        });
        let name = path.file_name().unwrap().to_string_lossy();
        let (hits, misses) = check_against_the_scene(&name, &scene, &film, &depth);
        seen.push(format!("{name} {hits}/{misses}"));
    }
    println!("pixels checked (hits/misses): {}", seen.join(", "));
}

/// Most spheres and most triangles of a scene whose crossings `check_against_the_scene`
/// computes for every pixel.
const PROBES: usize = 64;

/// Holds a 64 x 64 render (colour and the depth AOV, one sample a pixel, pinhole) against
/// what the scene itself says, computed here in f64 from the scene's camera and
/// primitives, not from the packed buffers: an eye ray that clearly crosses one of up to
/// `PROBES` spheres and triangles (taken evenly through the scene) hits something no
/// farther away; one that misses the primitives' bounds and every plane shows the
/// background, exactly, at depth 0. A flipped or shifted camera, or a traversal that loses
/// primitives, fails here. Returns the pixels checked each way; some must hit.
fn check_against_the_scene(name: &str, scene: &Scene, film: &Film, depth: &Film) -> (usize, usize) {
    let cam = Camera::sized(scene, film.width, film.height);
    // The bounds of every bounded primitive, a cone's taken as wide as its wider cap.
    let mut lo = DVec3::INFINITY;
    let mut hi = DVec3::NEG_INFINITY;
    let mut grow = |c: DVec3, r: f64| {
        lo = lo.min(c - r);
        hi = hi.max(c + r);
    };
    for s in &scene.spheres {
        grow(d(s.center), s.radius as f64);
    }
    for v in scene.triangles.iter().flat_map(|t| t.v) {
        grow(d(v), 0.0);
    }
    for c in &scene.cones {
        let r = c.base_radius.abs().max(c.apex_radius.abs()) as f64;
        grow(d(c.base), r);
        grow(d(c.apex), r);
    }
    for b in &scene.boxes {
        grow(d(b.min), 0.0);
        grow(d(b.max), 0.0);
    }
    let margin = 1e-3 * (hi - lo).max_element().max(1e-6);
    let (lo, hi) = (lo - margin, hi + margin);
    let misses_bounds = |dir: DVec3| {
        let (a, b) = ((lo - cam.from) / dir, (hi - cam.from) / dir);
        let (near, far) = (a.min(b).max_element(), a.max(b).min_element());
        !(near <= far && far > 0.0)
    };
    // A plane is missed when the ray runs away from it (or along it).
    let misses_planes = |dir: DVec3| {
        scene.planes.iter().all(|p| {
            let n = d(p.normal);
            let t = (d(p.point) - cam.from).dot(n) / dir.dot(n);
            !t.is_finite() || t < 0.0
        })
    };
    let step = |n: usize| n.div_ceil(PROBES).max(1);
    let spheres: Vec<_> = scene
        .spheres
        .iter()
        .step_by(step(scene.spheres.len()))
        .collect();
    let triangles: Vec<_> = scene
        .triangles
        .iter()
        .step_by(step(scene.triangles.len()))
        .collect();
    // A crossing the renderer's f32 rounding cannot move across the near plane.
    let clear = |t: f64| (t - cam.hither).abs() > 1e-3 * t.abs().max(cam.hither);
    let background = scene.background.to_array();
    let (mut hits, mut misses) = (0, 0);
    for (x, y) in cam.pixels() {
        let dir = cam.dir(x, y);
        let mut nearest = f64::INFINITY;
        for s in &spheres {
            let (c, r) = (d(s.center), s.radius as f64);
            let oc = cam.from - c;
            let b = oc.dot(dir);
            let disc = b * b - (oc.length_squared() - r * r);
            // Not near the silhouette, where f32 and f64 may disagree.
            if disc <= 1e-3 * r * r {
                continue;
            }
            let roots = [-b - disc.sqrt(), -b + disc.sqrt()];
            let first = roots.into_iter().find(|&t| t > cam.hither);
            if let Some(t) = first.filter(|_| roots.iter().all(|&t| clear(t))) {
                nearest = nearest.min(t);
            }
        }
        for t in &triangles {
            let t = triangle_hit(cam.from, dir, t.v.map(d), 1e-3);
            if let Some(t) = t.filter(|&t| t > cam.hither && clear(t)) {
                nearest = nearest.min(t);
            }
        }
        let got = f64::from(depth.get(x, y)[0]);
        if nearest.is_finite() {
            assert!(
                got > 0.0 && got <= nearest * (1.0 + 1e-3),
                "{name}: pixel ({x}, {y}) hits at depth {got}, but a primitive is {nearest} away"
            );
            hits += 1;
        } else if misses_bounds(dir) && misses_planes(dir) {
            assert_eq!(
                (film.get(x, y), got),
                (background, 0.0),
                "{name}: pixel ({x}, {y}) misses everything: background at depth 0"
            );
            misses += 1;
        }
    }
    assert!(
        hits > 0,
        "{name}: no pixel crosses a primitive of the scene"
    );
    (hits, misses)
}

#[test]
fn every_shared_scene_renders_finite_at_64() {
    let Some(dir) = shared_scenes() else { return };
    let files = files_with(&dir, &[".nff", ".nff.gz"]);
    assert!(files.len() >= 30, "only {} shared scenes", files.len());
    check_renders_finite(&files);
}

#[test]
fn every_scene_of_ours_renders_finite_at_64() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let files = files_with(&dir, &[".nff"]);
    assert!(files.len() >= 8, "only {} scenes in scenes/", files.len());
    check_renders_finite(&files);
}

/// Area light, thin lens, several samples per pixel, glass and a mirror: everything that
/// draws from the hash. Two renders must agree bit for bit, also on one thread.
#[test]
fn renders_are_bit_for_bit_deterministic() {
    let scene = parse(
        "b 0.1 0.1 0.2\n\
         v from 0 -6 2 at 0 0 0.8 up 0 0 1 angle 40 hither 0.1 resolution 48 40\n\
         aperture 0.3 focal 6\n\
         al -1 -1 5 2 0 0 0 2 0 1 1 1 3 3\n\
         l 3 -3 4\n\
         f 0.8 0.8 0.8 0.9 0 1 0 0\n\
         p 4 -5 -5 0 5 -5 0 5 5 0 -5 5 0\n\
         f 0.9 0.9 1 0.1 0.1 50 0.8 1.5\n\
         s -0.8 0 1 0.8\n\
         f 0.9 0.5 0.2 0.3 0.7 30 0 0\n\
         s 1 0.5 0.8 0.8\n",
    );
    let mut opts = RenderOptions::for_camera(&scene.camera);
    opts.spp = 4;
    opts.seed = 17;
    let a = render_with(&scene, &opts);
    let b = render_with(&scene, &opts);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let single = pool.install(|| render_with(&scene, &opts));
    let bits = |f: &Film| -> Vec<u32> { f.pixels.iter().flatten().map(|c| c.to_bits()).collect() };
    assert_eq!(bits(&a), bits(&b), "f32 films differ between two renders");
    assert_eq!(bits(&a), bits(&single), "f32 films differ on one thread");
    assert_eq!(a.to_rgb8().as_raw(), b.to_rgb8().as_raw());
    // The seed must matter, or "deterministic" could mean "ignores its samples".
    opts.seed = 18;
    let other = render_with(&scene, &opts);
    assert_ne!(bits(&a), bits(&other), "the seed changed nothing");
}

/// AOVs on a sphere seen head-on through the middle pixel of an odd-sized image (whose
/// ray is exactly the view direction): depth = distance to the centre - radius, normal =
/// towards the camera; every value finite; cost counts visited nodes (>= 1 on a hit).
#[test]
fn aovs_are_finite_and_depth_and_normal_match_at_the_centre() {
    let (from, c, r) = (DVec3::new(1.0, -7.0, 2.0), DVec3::new(0.5, 0.5, 0.25), 1.25);
    let scene = parse(&format!(
        "v from {} {} {} at {} {} {} up 0 0 1 angle 30 hither 0.01 resolution 65 65\n\
         l 5 -5 5\nf 1 1 1 1 0 1 0 0\ns {} {} {} {r}\ns 2 2 0 0.5\n",
        from.x, from.y, from.z, c.x, c.y, c.z, c.x, c.y, c.z
    ));
    let mut opts = RenderOptions::for_camera(&scene.camera);
    let mut aov = |code| {
        opts.aov = code;
        let film = render_with(&scene, &opts);
        assert!(
            film.pixels.iter().flatten().all(|v| v.is_finite()),
            "AOV {code} has non-finite values"
        );
        film
    };
    let depth = aov(AOV_DEPTH);
    let normal = aov(AOV_NORMAL);
    let cost = aov(AOV_COST);
    let want_depth = (c - from).length() - r;
    assert_close(
        pixel(&depth, 32, 32),
        DVec3::splat(want_depth),
        1e-5 * want_depth,
        "depth at the centre",
    );
    let towards_camera = (from - c).normalize();
    assert_close(
        pixel(&normal, 32, 32),
        0.5 * (towards_camera + 1.0),
        1e-5,
        "normal at the centre",
    );
    assert_eq!(depth.get(0, 0), [0.0; 3], "a corner misses: depth 0");
    assert!(cost.get(32, 32)[0] >= 1.0);
    assert!(
        cost.pixels
            .iter()
            .all(|p| p[0] >= 0.0 && p[0] == p[0].round()),
        "cost is a node count"
    );
}

/// `--backend both` fails on the verdict of `agreement::agreement`: a film equal to the
/// reference agrees, one with a brightened block does not (and the noise floor, measured
/// then, is zero on this scene, so it cannot excuse the block).
#[test]
fn agreement_rejects_a_perturbed_film() {
    let scene = parse(
        "v\nfrom 0 -6 2\nat 0 0 0.5\nup 0 0 1\nangle 40\nhither 0.01\nresolution 64 64\n\
         l 3 -4 6\nf 0.8 0.3 0.2 0.8 0.2 20 0 1\ns 0 0 0.5 1\np 4\n-5 -5 -0.5\n5 -5 -0.5\n5 5 -0.5\n-5 5 -0.5\n",
    );
    let opts = RenderOptions::for_camera(&scene.camera);
    let buffers = pack::pack(scene.clone()).expect("packs");
    let globals = frame::globals(&buffers, &opts);
    let reference = render_with(&scene, &opts);
    let same = gpurt::agreement::agreement(&buffers, &globals, &reference, &reference.clone())
        .expect("compares");
    assert!(same.verdict.is_ok() && same.noise_floor.is_none());
    let mut moved = reference.clone();
    for y in 20..40 {
        for x in 20..40 {
            let p = moved.get(x, y);
            moved.set(x, y, p.map(|c| c + 0.2));
        }
    }
    let moved =
        gpurt::agreement::agreement(&buffers, &globals, &reference, &moved).expect("compares");
    assert!(moved.verdict.is_err(), "{}", moved.stats);
    assert_eq!(moved.noise_floor, Some(0.0));
}

#[test]
fn every_sample_count_is_unbiased_on_an_edge() {
    let scene = parse(HALF_COLUMN);
    for spp in 1..=16 {
        let film = render_with(
            &scene,
            &RenderOptions {
                spp,
                ..RenderOptions::for_camera(&scene.camera)
            },
        );
        assert!(
            (column_mean(&film, 99) - 1.0).abs() < 1e-6,
            "{spp} spp: column 99"
        );
        assert!(column_mean(&film, 101) < 1e-6, "{spp} spp: column 101");
        if spp > 1 {
            let m = column_mean(&film, 100);
            assert!((m - 0.5).abs() <= 0.02, "{spp} spp: column 100 mean {m}");
        }
    }
}

/// Out-of-range material and light values (found by fuzzing the whole path) are held to
/// the documented ranges with a warning naming the line, so every pixel stays finite, on
/// both backends.
#[test]
fn out_of_range_materials_and_lights_are_held_and_pixels_stay_finite() {
    let scenes = [
        // Colour 7.7e17, Kd 5, T 9: transmission overflowed to infinity.
        (
            "f 1 1 777777777777777771 5 0.05 100 9 13",
            vec!["material colour", "Kd", "T"],
        ),
        // A negative Phong exponent: an infinite highlight.
        ("f 1 1 1 .9 0 -100000 0 5", vec!["Shine"]),
    ];
    for (material, held) in scenes {
        let src = format!(
            "v from 0 -4 1 at 0 0 0 up 0 0 1 angle 40 resolution 24 24
            b 0.1 0.2 0.3
            l 1 -3 4 3e38 3e38 3e38
            l -1 -3 4 3e38 3e38 3e38
            {material}
            s 0 0 0 1
            s 0.3 -1.5 0.2 0.3"
        );
        let scene = parse(&src);
        for what in held.iter().chain(&["light colour"]) {
            assert!(
                scene
                    .warnings
                    .iter()
                    .any(|w| w.starts_with("inline:") && w.contains(&format!("{what} "))),
                "{material}: no warning for {what}: {:?}",
                scene.warnings
            );
        }
        let opts = RenderOptions {
            spp: 4,
            ..RenderOptions::for_camera(&scene.camera)
        };
        let film = render_with(&scene, &opts);
        assert!(
            film.pixels.iter().flatten().all(|c| c.is_finite()),
            "{material}: non-finite pixels on the CPU"
        );
        if let Some(ctx) = crate::common::gpu_context() {
            let buffers = pack::pack(scene.clone()).expect("packs");
            let globals = frame::globals(&buffers, &opts);
            let (gpu, _) = gpurt::gpu::render_gpu(&ctx.device, &ctx.queue, &buffers, &globals)
                .expect("renders");
            assert!(
                gpu.pixels.iter().flatten().all(|c| c.is_finite()),
                "{material}: non-finite pixels on the GPU"
            );
        }
    }
}
