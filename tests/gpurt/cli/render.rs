//! `gpurt SCENE` as a user runs it: the image it writes in each format, where and how it
//! writes it, a view file's camera, the wireframe overlay, and the backend it picks.

use std::path::Path;

use glam::DVec3;
use gpurt::frame::Shading;
use gpurt::scene::{Scene, nff};

use crate::common::inputs::SCENE;
use crate::common::oracle::{Camera, d, lone_sphere};
use crate::common::{gpurt, stderr, workdir};

/// Holds the image file `path`, a render of `scene` (one lit ball), against what
/// docs/shading.md says each pixel shows, computed independently (`oracle::lone_sphere`):
/// every pixel away from the ball's outline within one 8-bit level and a half (8-bit
/// files are quantised; EXR keeps linear values). Returns the ball's pixels and the
/// background's.
fn check_ball_image(path: &Path, scene: &Scene, shading: Shading) -> (usize, usize) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb32f();
    let cam = Camera::sized(scene, img.width(), img.height());
    let (mut ball, mut background) = (0, 0);
    for (x, y) in cam.pixels() {
        let Some(want) = lone_sphere(scene, &cam, x, y, shading) else {
            continue;
        };
        let exr = path.extension().is_some_and(|e| e == "exr");
        let want = if exr {
            want
        } else {
            want.clamp(DVec3::ZERO, DVec3::ONE)
        };
        let got = DVec3::from(img.get_pixel(x, y).0.map(f64::from));
        assert!(
            (got - want).abs().max_element() <= 1.5 / 255.0,
            "{}: pixel ({x}, {y}) is {got}, shading.md says {want}",
            path.display()
        );
        if want == d(scene.background) {
            background += 1;
        } else {
            ball += 1;
        }
    }
    (ball, background)
}

#[test]
fn renders_to_the_default_name_and_to_each_format() {
    let d = workdir("formats");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let scene = nff::parse(SCENE.as_bytes(), "ball.nff", Path::new(".")).expect("parses");
    let o = gpurt(&["ball.nff", "--backend", "cpu"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(d.join("ball.png")).expect("ball.png written");
    assert_eq!((img.width(), img.height()), (32, 32));
    // Background 0.1 0.2 0.3, scaled by 255 and rounded (0.1 as an f32 is a little over).
    assert_eq!(img.to_rgb8().get_pixel(0, 0).0, [26, 51, 77], "a corner");
    let (ball, background) = check_ball_image(&d.join("ball.png"), &scene, Shading::Phong);
    assert!(
        ball > 300 && background > 500,
        "{ball} ball, {background} background"
    );
    for ext in ["ppm", "bmp", "exr"] {
        let out = format!("ball.{ext}");
        let o = gpurt(
            &["ball.nff", "--backend", "cpu", "-o", &out, "--width", "20"],
            &d,
        );
        assert!(o.status.success(), "{ext}: {}", stderr(&o));
        let img = image::open(d.join(&out)).unwrap_or_else(|e| panic!("{out}: {e}"));
        assert_eq!(img.width(), 20);
        let (ball, background) = check_ball_image(&d.join(&out), &scene, Shading::Phong);
        assert!(
            ball > 200 && background > 200,
            "{out}: {ball} ball, {background} background"
        );
    }
}

/// `--shading blinn-phong` gives the Blinn-Phong highlight docs/model.md describes, on
/// either backend, and an image that is not the Phong one; a model it does not know is
/// refused with exit 2 and no file.
#[test]
fn the_shading_flag_picks_the_highlight_model_on_both_backends() {
    let d = workdir("shading");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let scene = nff::parse(SCENE.as_bytes(), "ball.nff", Path::new(".")).expect("parses");
    for backend in ["cpu", "gpu"] {
        let out = format!("blinn-{backend}.exr");
        let args = [
            "ball.nff",
            "--shading",
            "blinn-phong",
            "--backend",
            backend,
            "-o",
            &out,
        ];
        let o = gpurt(&args, &d);
        assert!(o.status.success(), "{backend}: {}", stderr(&o));
        let (ball, _) = check_ball_image(&d.join(&out), &scene, Shading::BlinnPhong);
        assert!(ball > 300, "{backend}: {ball} ball pixels");
    }
    let o = gpurt(&["ball.nff", "--backend", "cpu", "-o", "phong.exr"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    check_ball_image(&d.join("phong.exr"), &scene, Shading::Phong);
    let read = |f: &str| image::open(d.join(f)).unwrap().to_rgb32f();
    let (phong, blinn) = (read("phong.exr"), read("blinn-cpu.exr"));
    let most = phong
        .pixels()
        .zip(blinn.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| (a.0[c] - b.0[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(most > 0.05, "the two models' images differ by only {most}");

    let o = gpurt(&["ball.nff", "--shading", "gouraud", "-o", "no.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("[possible values: phong, blinn-phong]"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("no.png").exists());
}

/// A successful render prints no `error:` line (Mesa's device-select layer printed two on
/// headless machines).
#[test]
fn a_successful_render_prints_no_error_lines() {
    let d = workdir("no-error-lines");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "-v", "-o", "out.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("error"), "{}", stderr(&o));
}

/// Writing an output: through a symbolic link to its target (the link stays), keeping an
/// existing file's permissions, with a 250-byte name (the temporary name stays within the
/// limit), and refused before rendering when the directory is missing or not writable.
#[test]
fn outputs_follow_links_keep_permissions_and_are_checked_first() {
    use std::os::unix::fs::PermissionsExt;
    let d = workdir("outputs");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let render = |out: &str| gpurt(&["ball.nff", "--backend", "cpu", "-o", out], &d);

    std::fs::create_dir(d.join("renders")).unwrap();
    std::os::unix::fs::symlink("renders/v1.png", d.join("latest.png")).unwrap();
    let o = render("latest.png");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::symlink_metadata(d.join("latest.png"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(d.join("renders/v1.png").is_file());

    std::fs::write(d.join("private.png"), b"old").unwrap();
    std::fs::set_permissions(
        d.join("private.png"),
        std::fs::Permissions::from_mode(0o600),
    )
    .unwrap();
    let o = render("private.png");
    assert!(o.status.success(), "{}", stderr(&o));
    let mode = std::fs::metadata(d.join("private.png"))
        .unwrap()
        .permissions()
        .mode();
    assert_eq!(mode & 0o777, 0o600);
    assert_ne!(std::fs::read(d.join("private.png")).unwrap(), b"old");

    let long = format!("{}.png", "a".repeat(246));
    assert_eq!(long.len(), 250);
    let o = render(&long);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join(&long).is_file());

    let t = std::time::Instant::now();
    let o = gpurt(
        &[
            "ball.nff",
            "--backend",
            "cpu",
            "--spp",
            "4096",
            "-o",
            "missing/out.png",
        ],
        &d,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("missing/out.png"), "{}", stderr(&o));
    assert!(
        t.elapsed() < std::time::Duration::from_secs(5),
        "refused only after rendering"
    );

    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

/// `--view FILE` takes the camera from a file's `v` block: the image is the one of the
/// scene with that block in place of its own, to the bit (CPU backend), and what
/// docs/shading.md says that camera sees; the scene's own camera at the same size (the
/// control) sees something else, so the view moved more than the image's size.
#[test]
fn a_view_file_replaces_the_scene_camera() {
    let d = workdir("view-file");
    let view = "v\nfrom 1.5 -3 2\nat 0.2 0 0\nup 0 0 1\nangle 35\nhither 0.01\nresolution 40 30\n";
    std::fs::write(d.join("scene.nff"), SCENE).unwrap();
    std::fs::write(d.join("view.nff"), view).unwrap();
    let moved = SCENE.replace(
        "v\nfrom 0 -4 1\nat 0 0 0\nup 0 0 1\nangle 40\nresolution 32 32\n",
        view,
    );
    assert_ne!(moved, SCENE);
    std::fs::write(d.join("moved.nff"), &moved).unwrap();
    for (scene, out, extra) in [
        ("scene.nff", "a.png", vec!["--view", "view.nff"]),
        ("moved.nff", "b.png", vec![]),
        (
            "scene.nff",
            "c.png",
            vec!["--width", "40", "--height", "30"],
        ),
    ] {
        let mut args = vec![scene, "--backend", "cpu", "-o", out];
        args.extend(extra);
        let o = gpurt(&args, &d);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |f: &str| image::open(d.join(f)).unwrap().to_rgb8();
    assert_eq!(read("a.png").dimensions(), (40, 30));
    assert_eq!(read("a.png"), read("b.png"));
    let seen = nff::parse(moved.as_bytes(), "moved.nff", Path::new(".")).expect("parses");
    let (ball, background) = check_ball_image(&d.join("a.png"), &seen, Shading::Phong);
    assert!(
        ball > 100 && background > 100,
        "{ball} ball, {background} background"
    );
    assert_eq!(read("c.png").dimensions(), (40, 30));
    assert!(
        read("a.png") != read("c.png"),
        "the view file's camera changed nothing"
    );
    let o = gpurt(&["scene.nff", "--view", "missing.nff", "-o", "x.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(!d.join("x.png").exists());
}

/// `--overlay wireframe` draws the wireframe (`--aov wireframe` alone) over the image:
/// every pixel is either the plain render's or the line colour, the lines are where the
/// wireframe alone has them, and there are some.
#[test]
fn the_wireframe_overlay_is_the_render_plus_the_lines() {
    if crate::common::gpu_context().is_none() {
        return;
    }
    let d = workdir("overlay");
    std::fs::write(d.join("scene.nff"), SCENE).unwrap();
    for (out, extra) in [
        ("plain.png", vec![]),
        ("over.png", vec!["--overlay", "wireframe"]),
        ("wire.png", vec!["--aov", "wireframe"]),
    ] {
        let mut args = vec!["scene.nff", "--backend", "cpu", "--width", "61", "-o", out];
        args.extend(extra);
        let o = gpurt(&args, &d);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |f: &str| image::open(d.join(f)).unwrap().to_rgb8();
    let (plain, over, wire) = (read("plain.png"), read("over.png"), read("wire.png"));
    let line = gpurt::view::wireframe::LINE_COLOR.map(gpurt::film::quantize);
    let mut lines = 0;
    for ((p, o), w) in plain.pixels().zip(over.pixels()).zip(wire.pixels()) {
        if w.0 == [0, 0, 0] {
            assert_eq!(o, p, "off the lines the overlay is the render");
        } else {
            assert_eq!(w.0, line[..3]);
            assert_eq!(o.0, line[..3]);
            lines += 1;
        }
    }
    let n = plain.pixels().len();
    assert!(
        lines > n / 50 && lines < n / 2,
        "{lines} of {n} pixels are lines"
    );
}

#[test]
fn the_default_backend_is_the_cpu_on_software_adapters_and_the_gpu_on_hardware_and_says_why() {
    let Some(ctx) = crate::common::gpu_context() else {
        return;
    };
    let software = gpurt::gpu::is_software(&ctx.info);
    if ctx.info.name.to_lowercase().contains("llvmpipe") {
        assert!(software, "{} is Mesa's software rasteriser", ctx.describe());
    }
    drop(ctx);
    let d = workdir("auto-backend");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "-v", "-o", "auto.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let ran: Vec<&str> = err
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|w| *w == "cpu" || *w == "gpu")
        .collect();
    if software {
        // Software adapters only: said so, or (Linux) no GPU device node to look at.
        assert!(
            err.contains("backend     cpu: the GPU adapters here are software rasterisers")
                || err.contains("backend     cpu: there is no GPU device here"),
            "{err}"
        );
        assert_eq!(ran, ["cpu"], "{err}");
        // The very image `--backend cpu` writes.
        let o = gpurt(&["ball.nff", "--backend", "cpu", "-o", "cpu.png"], &d);
        assert!(o.status.success(), "{}", stderr(&o));
        let a = gpurt::film::load_rgb8(&d.join("auto.png")).unwrap();
        assert_eq!(a, gpurt::film::load_rgb8(&d.join("cpu.png")).unwrap());
    } else {
        assert!(err.contains("backend     gpu: "), "{err}");
        assert_eq!(ran, ["gpu"], "{err}");
    }
    // `--backend gpu` takes any adapter, software or not.
    let o = gpurt(&["ball.nff", "--backend", "gpu", "-v", "-o", "gpu.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).lines().any(|l| l.starts_with("gpu ")),
        "{}",
        stderr(&o)
    );
}

/// `GPURT_BVH` builds every tree at the quality it names, whatever the render's length
/// (`--stats` says which on its `build` line): a short render of a scene above
/// `THOROUGH_BUILD_MAX_PRIMS` gets the medium tree unless `high` is asked for, a small
/// scene the high one unless `medium` is; the same image either way (the trees differ,
/// the hits do not), and a value it does not know is refused before anything is written.
#[test]
fn gpurt_bvh_collapse_and_stack_choose_the_trees_and_the_stack_for_measuring() {
    let d = workdir("bvh-quality");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let n = gpurt::bvh::THOROUGH_BUILD_MAX_PRIMS + 1;
    let mut many = String::from(
        "v\nfrom 0 0 -40\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 16 16\nl 0 0 -40\nf 1 1 1 1 0 0 0 0\n",
    );
    for i in 0..n {
        let (x, y) = ((i % 150) as f32 - 75.0, (i / 150) as f32 - 75.0);
        many += &format!("s {} {} 0 0.4\n", x * 0.2, y * 0.2);
    }
    std::fs::write(d.join("many.nff"), many).unwrap();
    let build = |scene: &str, bvh: &str, out: &str| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args([scene, "--backend", "cpu", "--stats", "-o", out])
            .current_dir(&d)
            .env("GPURT_CACHE_DIR", "")
            .env("GPURT_BVH", bvh)
            .output()
            .expect("gpurt runs");
        assert!(o.status.success(), "{bvh}: {}", stderr(&o));
        let err = stderr(&o);
        let line = err
            .lines()
            .find(|l| l.starts_with("build "))
            .unwrap_or_default();
        line.to_string()
    };
    assert!(build("many.nff", "", "a.png").contains("medium quality"));
    assert!(build("many.nff", "high", "b.png").contains("high quality"));
    assert!(build("ball.nff", "", "c.png").contains("high quality"));
    assert!(build("ball.nff", "medium", "d.png").contains("medium quality"));
    let same = gpurt(&["diff", "a.png", "b.png", "--max-bad", "0"], &d);
    assert!(same.status.success(), "{}", stderr(&same));

    // A setting the renderer does not know: exit 2, the variable named, no image.
    let refused = |backend: &str, var: &str, value: &str, message: &str| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args(["ball.nff", "--backend", backend, "-o", "bad.png"])
            .current_dir(&d)
            .env(var, value)
            .output()
            .expect("gpurt runs");
        assert_eq!(o.status.code(), Some(2), "{var}={value}");
        let err = stderr(&o);
        assert!(err.contains(&format!("{var}={value}: {message}")), "{err}");
        assert!(!d.join("bad.png").exists(), "{var}={value}");
    };
    refused("cpu", "GPURT_BVH", "mid", "expected medium or high");

    // The GPU's wide walk of many.nff with `var` set to `value`: its eye rays' line of
    // `--stats`.
    let walk = |var: &str, value: &str, out: &str| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args(["many.nff", "--backend", "gpu", "--stats", "-o", out])
            .args(["--width", "48", "--height", "48"])
            .current_dir(&d)
            .env("GPURT_CACHE_DIR", "")
            .env("GPURT_TRAVERSAL", "wide")
            .env(var, value)
            .output()
            .expect("gpurt runs");
        assert!(o.status.success(), "{var}={value}: {}", stderr(&o));
        let err = stderr(&o);
        let line = err.lines().find(|l| l.starts_with("gpu eye"));
        line.expect("an eye-ray line").to_string()
    };
    // The GPU's wide tree, gathered greedily (the default) or SAH-optimally: another
    // tree, so other node counts, and the same image.
    let greedy = walk("GPURT_COLLAPSE", "", "greedy.png");
    assert_eq!(walk("GPURT_COLLAPSE", "greedy", "greedy-named.png"), greedy);
    assert_ne!(walk("GPURT_COLLAPSE", "optimal", "optimal.png"), greedy);
    let same = gpurt(&["diff", "greedy.png", "optimal.png"], &d);
    assert!(same.status.success(), "{}", stderr(&same));
    refused(
        "gpu",
        "GPURT_COLLAPSE",
        "best",
        "expected greedy or optimal",
    );

    // A floor under the traversal stack (`GPURT_STACK`) changes its size, never what the
    // walk finds: the largest stack renders the same pixels and fetches the same nodes.
    assert_eq!(walk("GPURT_STACK", "64", "stack-64.png"), greedy);
    let same = gpurt(
        &["diff", "greedy.png", "stack-64.png", "--max-bad", "0"],
        &d,
    );
    assert!(same.status.success(), "{}", stderr(&same));
    refused(
        "gpu",
        "GPURT_STACK",
        "deep",
        "expected a whole number above 0",
    );
}

/// The node bytes a secondary ray fetches on the high-quality tree, held where docs/bvh.md
/// gives them ("One word a lane: 224-byte nodes"): `--stats` of a 512x512 render, 1 spp,
/// depth 5, on the CPU backend with `GPURT_BVH=high`, held to AVX2 as they were measured
/// (reflected and refracted rays go in packets of 8 where they start together, sharing
/// each node's fetch): at most 332 bytes a ray on gears-4 and 230 on mount-9, within 1%
/// (the figure is printed rounded). A change to the build, the collapse, the wide node or
/// the packets that makes these rays fetch more fails here; one that makes them fetch less
/// should bring the docs down with it. Skipped where the processor has no AVX2.
#[test]
fn secondary_rays_fetch_no_more_node_bytes_than_the_docs_say() {
    let Some(dir) = crate::common::shared_scenes() else {
        return;
    };
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    let avx2 = false;
    if !avx2 {
        crate::common::skip("the figures are those of AVX2's packets of 8");
        return;
    }
    let d = workdir("node-bytes");
    for (scene, documented) in [("gears-4.nff", 332.0), ("mount-9.nff.gz", 230.0)] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .arg(dir.join("spd").join(scene))
            .args(["--backend", "cpu", "--stats", "-o", "out.png"])
            .current_dir(&d)
            .env("GPURT_CACHE_DIR", "")
            .env("GPURT_BVH", "high")
            .env("GPURT_SIMD", "avx2")
            .output()
            .expect("gpurt runs");
        assert!(o.status.success(), "{scene}: {}", stderr(&o));
        let err = stderr(&o);
        // "cpu secondary 187863 rays, 3.2 nodes/ray, 712 node bytes/ray (224 B a node)"
        let bytes: f64 = err
            .lines()
            .find(|l| l.starts_with("cpu secondary"))
            .and_then(|l| l.split(", ").find_map(|p| p.split_once(" node bytes/ray")))
            .and_then(|(n, _)| n.parse().ok())
            .unwrap_or_else(|| panic!("{scene}: no secondary node bytes in\n{err}"));
        assert!(
            bytes <= documented * 1.01,
            "{scene}: secondary rays fetch {bytes} node bytes a ray, the docs say {documented}"
        );
    }
}
