//! The two models of the specular highlight (`frame::Shading`): a pixel worked out by
//! hand for each, on both renderers; every pixel of a shiny sphere against the f64 oracle
//! under Blinn-Phong; every pixel the f64 tracer (`common::whitted`) can call of triangles
//! and glass under point, directional and area lights and an emitter, on both renderers;
//! and the GPU
//! specialisation that keeps Blinn-Phong out of Phong pipelines. GPU against CPU under
//! Blinn-Phong on every scene is a variant of `common::versus::check_variants`; Phong
//! images byte for byte as before are checked by rendering the image suite with the
//! binary before and after.

use std::path::Path;

use glam::DVec3;
use glam::Vec3;
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions, Shading};
use gpurt::gpu::specialization::Specialization;
use gpurt::gpu_types::*;
use gpurt::pack;
use gpurt::scene::{Material, MaterialId, Scene, Triangle, nff};

use crate::common::oracle::{Camera, lone_sphere};
use crate::common::versus::{self, Gpu};
use crate::common::whitted::{Met, Whitted};

/// A unit sphere at the origin seen along +y from (0, -5, 0) on a 3 x 3 image, whose
/// centre pixel's ray is exactly (0, 1, 0): it meets the sphere at P = (0, -1, 0), where
/// N = V = (0, -1, 0). The light at (3, -4, 0) lies 45 degrees off the normal:
/// L = (1, -1, 0) / sqrt(2), N.L = cos 45. The mirrored ray R = (0, -1, 0) = N, so Phong's
/// R.L = cos 45; Blinn-Phong's H lies halfway between L and V, 22.5 degrees off N, so
/// N.H = cos 22.5, whose square is (1 + cos 45) / 2.
const HAND: &str = "b 0 0 0
v from 0 -5 0 at 0 0 0 up 0 0 1 angle 40 hither 0.01 resolution 3 3
l 3 -4 0
f 1 1 1 0.5 0.4 2 0 1
s 0 0 0 1
";

/// The centre pixel of `HAND` by hand, in each channel: ambient 0.1 x Kd 0.5 (the default
/// ambient, white material), plus the light (intensity 1, alone) times Kd N.L + the
/// highlight Ks (c)^2 with Shine 2; the mirror ray leaves towards the black background.
fn by_hand(shading: Shading) -> f64 {
    let cos45 = 0.5f64.sqrt();
    let c_squared = match shading {
        Shading::Phong => cos45 * cos45,
        Shading::BlinnPhong => (1.0 + cos45) / 2.0,
    };
    0.1 * 0.5 + 0.5 * cos45 + 0.4 * c_squared
}

fn parse(src: &str) -> Scene {
    nff::parse(src.as_bytes(), "inline.nff", Path::new(".")).expect("inline scene parses")
}

/// Samples an emitter takes in these tests' renders along each side of its grid, where the
/// tracer integrates it on as many points: the estimate converges on the integral (to 0.3
/// levels here at worst, on the shiny sphere's highlight, where 8 x 8 leave 3.9).
const EMITTER_SAMPLES: u32 = 24;

/// The image of `scene` in `shading` on the CPU, or on the GPU given one (its emitters
/// taking `EMITTER_SAMPLES`).
fn render(scene: &Scene, shading: Shading, gpu: Option<&Gpu>) -> Film {
    let opts = RenderOptions {
        shading,
        ..RenderOptions::for_camera(&scene.camera)
    };
    let mut buffers = pack::pack(scene.clone()).expect("packs");
    for l in buffers
        .lights
        .iter_mut()
        .filter(|l| l.kind == LIGHT_EMITTER)
    {
        l.nu = EMITTER_SAMPLES;
    }
    versus::render_on(&buffers, &frame::globals(&buffers, &opts), gpu)
}

fn centre(film: &Film) -> DVec3 {
    DVec3::from(film.get(1, 1).map(f64::from))
}

/// Checks the centre pixel of `HAND` under each model on one renderer, and that the
/// check tells the models apart: each render fails the other model's value.
fn check_by_hand(gpu: Option<&Gpu>, what: &str) {
    let scene = parse(HAND);
    // Both renderers compute in f32; the values are around 0.6 to 0.75.
    let tol = 1e-5;
    assert!((by_hand(Shading::Phong) - by_hand(Shading::BlinnPhong)).abs() > 0.1);
    for (shading, other) in [
        (Shading::Phong, Shading::BlinnPhong),
        (Shading::BlinnPhong, Shading::Phong),
    ] {
        let got = centre(&render(&scene, shading, gpu));
        let want = DVec3::splat(by_hand(shading));
        let off = (got - want).abs().max_element();
        assert!(off <= tol, "{what} {shading:?}: {got}, by hand {want}");
        let off_other = (got - DVec3::splat(by_hand(other))).abs().max_element();
        assert!(off_other > tol, "{what} {shading:?} passes as {other:?}");
    }
}

#[test]
fn a_pixel_by_hand_for_each_model_on_the_cpu() {
    check_by_hand(None, "CPU");
}

#[test]
fn a_pixel_by_hand_for_each_model_on_the_gpu() {
    let Some(g) = versus::gpu() else {
        return;
    };
    check_by_hand(Some(g), "GPU");
}

/// Every pixel of a shiny sphere under two lights, Blinn-Phong against the f64 oracle
/// within one 8-bit level, with highlights on it; the Phong render of the same scene
/// fails that oracle.
#[test]
fn every_pixel_of_a_shiny_sphere_is_blinn_phong_on_the_cpu() {
    let scene = parse(
        "b 0.05 0.1 0.15
v from 0 -8 3 at 0 0 0.5 up 0 0 1 angle 35 hither 0.5 resolution 48 48
l 4 -5 6
l -6 -2 1
f 0.3 0.8 0.4 0.6 0.3 20 0 0
s 0.3 0.2 0.5 1.5
",
    );
    let cam = Camera::of(&scene);
    let worst = |film: &Film, shading: Shading| {
        cam.pixels()
            .filter_map(|(x, y)| {
                let want = lone_sphere(&scene, &cam, x, y, shading)?;
                let got = DVec3::from(film.get(x, y).map(f64::from));
                Some((got - want).abs().max_element())
            })
            .fold(0.0, f64::max)
    };
    let blinn = render(&scene, Shading::BlinnPhong, None);
    let phong = render(&scene, Shading::Phong, None);
    assert!(worst(&blinn, Shading::BlinnPhong) <= 1.0 / 255.0);
    assert!(worst(&phong, Shading::Phong) <= 1.0 / 255.0);
    assert!(
        worst(&phong, Shading::BlinnPhong) > 10.0 / 255.0,
        "Phong's image passes as Blinn-Phong's"
    );
}

/// A floor and a wall of triangles, an opaque shiny sphere and a glass one (refraction,
/// total internal reflection, tinted shadows), seen from one camera, under `lights`.
fn shapes_under(lights: &str) -> String {
    format!(
        "b 0.1 0.12 0.2
v from 0 -9 4 at 0 0 0.8 up 0 0 1 angle 38 hither 0.5 resolution 64 48
{lights}
f 0.8 0.75 0.7 0.7 0.15 12 0 1
p 4
-4 -3 0
4 -3 0
4 3 0
-4 3 0
f 0.35 0.5 0.9 0.6 0.3 20 0 1
p 3
-3.5 2.5 0
0 3 3
3.5 2.5 0
f 0.9 0.3 0.2 0.5 0.4 30 0 1
s -1.4 0.6 1 1
f 0.95 0.95 1 0.05 0.1 60 {GLASS}
s 1.3 -0.6 1 1
"
    )
}

/// The shapes under a point and a directional light.
fn hard() -> String {
    shapes_under("l 3 -4 7\ndl 1 -0.5 -2")
}

/// The shapes under one area light, 8 x 8 samples, with its soft and tinted shadows.
fn soft() -> String {
    shapes_under("al -1 -1 6 2 0 0 0 2 0 0.9 0.9 0.85 8 8")
}

/// The shapes lit by an emitter alone: a 2 x 2 square of two triangles facing down, 6
/// above the floor, where `soft`'s area light is (OBJ and glTF give emitters; NFF has no
/// statement for one, so the test adds it to the scene read).
fn emitter_over(scene: &mut Scene) {
    let lamp = MaterialId(scene.materials.len() as u32);
    scene.materials.push(Material {
        emission: Vec3::new(25.0, 24.0, 22.0),
        ..Material::DEFAULT
    });
    let (a, b, c, e) = (
        Vec3::new(-1.0, -1.0, 6.0),
        Vec3::new(1.0, -1.0, 6.0),
        Vec3::new(1.0, 1.0, 6.0),
        Vec3::new(-1.0, 1.0, 6.0),
    );
    for v in [[a, e, c], [a, c, b]] {
        scene.triangles.push(Triangle {
            v,
            n: None,
            material: lamp,
            uv: None,
        });
    }
}

/// The glass's transmission and index of refraction.
const GLASS: &str = "0.85 1.5";

/// Every pixel of `src` that the f64 tracer can call, rendered under Blinn-Phong on one
/// renderer, within `tol` of the tracer; most pixels called, each of `wanted`'s features
/// met by many of them; and two renders of other scenes failing that oracle: the same
/// scene under Phong, and with glass of another index.
fn check_whitted(src: &str, add: fn(&mut Scene), gpu: Option<&Gpu>, tol: f64, wanted: &[Feature]) {
    let parse = |src: &str| {
        let mut scene = parse(src);
        add(&mut scene);
        scene
    };
    let scene = parse(src);
    let cam = Camera::of(&scene);
    let oracle = Whitted::new(&scene, Shading::BlinnPhong, 5);
    let called: Vec<_> = cam
        .pixels()
        .filter_map(|(x, y)| Some(((x, y), oracle.pixel(&cam, x, y)?)))
        .collect();
    let pixels = (cam.width * cam.height) as usize;
    assert!(
        called.len() * 10 >= pixels * 7,
        "the tracer calls {} of {pixels} pixels",
        called.len()
    );
    for (name, met) in wanted {
        let n = called.iter().filter(|(_, (_, m))| met(m)).count();
        assert!(n >= 40, "{name}: met by {n} pixels");
    }
    let worst = |film: &Film| {
        called
            .iter()
            .map(|&((x, y), (want, _))| {
                let got = DVec3::from(film.get(x, y).map(f64::from));
                ((got - want).abs().max_element(), (x, y))
            })
            .fold((0.0, (0, 0)), |a, b| if b.0 > a.0 { b } else { a })
    };
    let (off, at) = worst(&render(&scene, Shading::BlinnPhong, gpu));
    assert!(off <= tol, "{off} off the f64 tracer at {at:?}");
    let (off, _) = worst(&render(&scene, Shading::Phong, gpu));
    assert!(off > 4.0 * tol, "Phong's image passes ({off})");
    let bent = parse(&src.replace(GLASS, "0.85 1.4"));
    let (off, _) = worst(&render(&bent, Shading::BlinnPhong, gpu));
    assert!(off > 4.0 * tol, "glass of index 1.4 passes for 1.5 ({off})");
}

/// A feature of the model by name, and whether a pixel's paths met it.
type Feature = (&'static str, fn(&Met) -> bool);

const HARD_MET: [Feature; 4] = [
    ("triangles", |m| m.triangle),
    ("refraction", |m| m.refraction),
    ("the directional light", |m| m.directional),
    ("shadows through glass", |m| m.tinted_shadow),
];

const SOFT_MET: [Feature; 4] = [
    ("triangles", |m| m.triangle),
    ("refraction", |m| m.refraction),
    ("the area light", |m| m.area),
    ("shadows through glass", |m| m.tinted_shadow),
];

const EMITTER_MET: [Feature; 4] = [
    ("triangles", |m| m.triangle),
    ("refraction", |m| m.refraction),
    ("the emitter", |m| m.emitter),
    ("shadows through glass", |m| m.tinted_shadow),
];

/// Both renderers meet the tracer to about 3e-6 here: the tolerance leaves a margin of 30.
const HARD_TOL: f64 = 1e-4;

#[test]
fn triangles_and_glass_under_point_and_directional_lights_are_blinn_phong_on_the_cpu() {
    check_whitted(&hard(), |_| {}, None, HARD_TOL, &HARD_MET);
}

#[test]
fn triangles_and_glass_under_point_and_directional_lights_are_blinn_phong_on_the_gpu() {
    let Some(g) = versus::gpu() else {
        return;
    };
    check_whitted(&hard(), |_| {}, Some(g), HARD_TOL, &HARD_MET);
}

/// The renderers estimate the area light from 64 jittered samples where the tracer
/// integrates it: a smooth integrand (penumbrae are not called), so within one and a
/// half 8-bit levels (both meet it to 0.7 here).
#[test]
fn an_area_light_over_triangles_and_glass_is_blinn_phong_on_the_cpu() {
    check_whitted(&soft(), |_| {}, None, 1.5 / 255.0, &SOFT_MET);
}

#[test]
fn an_area_light_over_triangles_and_glass_is_blinn_phong_on_the_gpu() {
    let Some(g) = versus::gpu() else {
        return;
    };
    check_whitted(&soft(), |_| {}, Some(g), 1.5 / 255.0, &SOFT_MET);
}

/// An emitter's light is the integral of its radiance over its triangles (docs/model.md),
/// estimated from 24 x 24 samples where the tracer integrates it on a grid: within one
/// and a half 8-bit levels, as the area light.
#[test]
fn an_emitter_over_triangles_and_glass_lights_them_by_its_integral_on_the_cpu() {
    check_whitted(
        &shapes_under(""),
        emitter_over,
        None,
        1.5 / 255.0,
        &EMITTER_MET,
    );
}

#[test]
fn an_emitter_over_triangles_and_glass_lights_them_by_its_integral_on_the_gpu() {
    let Some(g) = versus::gpu() else {
        return;
    };
    check_whitted(
        &shapes_under(""),
        emitter_over,
        Some(g),
        1.5 / 255.0,
        &EMITTER_MET,
    );
}

/// The model is a pipeline constant of colour frames only: Phong and Blinn-Phong frames
/// compile apart, and the AOVs, which shade nothing, share one pipeline whatever the model.
#[test]
fn the_model_selects_the_pipeline_of_colour_frames_only() {
    let scene = parse(HAND);
    let buffers = pack::pack(scene.clone()).expect("packs");
    let spec = |shading: Shading, aov: u32| {
        let opts = RenderOptions {
            shading,
            aov,
            ..RenderOptions::for_camera(&scene.camera)
        };
        Specialization::of(&buffers, &frame::globals(&buffers, &opts))
    };
    let constant = |s: Specialization| {
        s.constants()
            .into_iter()
            .find(|(name, _)| *name == "SHADING")
            .map(|(_, v)| v)
    };
    assert_eq!(
        constant(spec(Shading::Phong, AOV_COLOR)),
        Some(f64::from(SHADING_PHONG))
    );
    assert_eq!(
        constant(spec(Shading::BlinnPhong, AOV_COLOR)),
        Some(f64::from(SHADING_BLINN_PHONG))
    );
    for aov in [AOV_NORMAL, AOV_DEPTH, AOV_COST] {
        assert_eq!(spec(Shading::Phong, aov), spec(Shading::BlinnPhong, aov));
    }
}

/// Each model's name reads back to it, and nothing else reads as a model.
#[test]
fn models_are_named_one_way() {
    for s in Shading::ALL {
        assert_eq!(Shading::from_name(s.name()), Some(s));
    }
    assert_eq!(Shading::default(), Shading::Phong);
    assert_eq!(Shading::from_name("Phong"), None);
    assert_eq!(Shading::from_name("blinn"), None);
}
