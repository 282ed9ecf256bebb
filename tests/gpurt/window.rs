//! `gpurt view` in a real window: Xvfb (a virtual X display) and whatever adapter
//! presents to it (lavapipe in CI). A scripted orbit's screenshot must be the offline
//! render of the view the viewer prints; the three display modes must show the image, the
//! wireframe, and the one over the other; and the screenshots in `docs/viewer/` (the
//! README's) must still be what the viewer shows.
//!
//! Without `xvfb-run` these tests skip with a message, except under `CI=true`, where they
//! fail (`.ci/run` installs it).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

use gpurt::compare::{self, Thresholds};
use gpurt::film;
use image::RgbImage;

use crate::common::{gpurt, in_ci, own_scenes, skip, workdir};

/// One X server at a time: `xvfb-run -a` picks a free display number, but two starting
/// together can pick the same one.
static XVFB: Mutex<()> = Mutex::new(());

/// `gpurt view ARGS` in `dir` on a fresh virtual display; `None` (skipped) when xvfb-run
/// is missing, except under `CI=true`.
fn view_in_xvfb(args: &[&str], dir: &Path) -> Option<Output> {
    let found = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !found {
        if in_ci() {
            panic!("xvfb-run is missing (required under CI=true; apt-get install xvfb xauth)");
        }
        skip("xvfb-run is missing (apt-get install xvfb xauth)");
        return None;
    }
    let _one = XVFB.lock().unwrap_or_else(|e| e.into_inner());
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_gpurt"))
        .arg("view")
        .args(args)
        .current_dir(dir)
        .env("GPURT_CACHE_DIR", "")
        .output()
        .expect("xvfb-run runs");
    assert!(
        out.status.success(),
        "gpurt view {args:?} failed ({}): {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    Some(out)
}

/// The NFF `v` block the viewer printed (key C), from `v` to `resolution`.
fn printed_view(stdout: &[u8]) -> String {
    let text = String::from_utf8_lossy(stdout);
    let start = text.find("v\nfrom ").expect("a printed v block");
    let block = &text[start..];
    let end = block.find("resolution").expect("a resolution line");
    let end = end + block[end..].find('\n').expect("a full line");
    block[..=end].to_string()
}

fn load(path: &Path) -> RgbImage {
    film::load_rgb8(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Whether two images agree within the project's GPU-vs-CPU thresholds.
fn agree(a: &RgbImage, b: &RgbImage) -> Result<(), String> {
    let stats =
        compare::diff(a, b, Thresholds::GPU_VS_CPU.tolerance_255).map_err(|e| e.to_string())?;
    Thresholds::GPU_VS_CPU.check(&stats)
}

fn mesh_scene() -> String {
    own_scenes().join("mesh.nff").display().to_string()
}

#[test]
fn after_a_scripted_orbit_the_window_shows_the_offline_render_of_the_view_it_prints() {
    let dir = workdir("window-orbit");
    std::fs::write(
        dir.join("orbit.txt"),
        "# orbit, dolly in, pan, then print the camera\n\
         drag 70 -25\nwheel 1.5\npan 8 -4\nkey c\nkey p\nwait 3\n",
    )
    .unwrap();
    let scene = mesh_scene();
    // The GPU tracer (lavapipe in CI); the modes test below takes the default backend.
    let size = [
        "--width",
        "320",
        "--height",
        "240",
        "--spp",
        "4",
        "--backend",
        "gpu",
    ];
    let Some(out) = view_in_xvfb(
        &[
            &[scene.as_str()][..],
            &size,
            &["--script", "orbit.txt", "--screenshot", "shot.png"],
        ]
        .concat(),
        &dir,
    ) else {
        return;
    };
    let view = printed_view(&out.stdout);
    assert!(view.contains("resolution 320 240"), "{view}");
    std::fs::write(dir.join("view.nff"), &view).unwrap();
    // The printed view alone, offline, with the scene's own size taken from the block.
    let offline = gpurt(
        &[
            &scene,
            "--view",
            "view.nff",
            "--spp",
            "4",
            "--backend",
            "gpu",
            "-o",
            "offline.png",
        ],
        &dir,
    );
    assert!(
        offline.status.success(),
        "{}",
        String::from_utf8_lossy(&offline.stderr)
    );
    let shot = load(&dir.join("shot.png"));
    let offline = load(&dir.join("offline.png"));
    agree(&offline, &shot).unwrap_or_else(|why| panic!("window vs offline render: {why}"));
    // P wrote the ray-traced view once it had its samples.
    let saved = load(&dir.join("mesh-view-1.png"));
    agree(&offline, &saved).unwrap_or_else(|why| panic!("P's image vs offline render: {why}"));

    // The comparison sees a wrong view and an empty window: the scene's own camera
    // (where the orbit started) and a black image both fail it.
    let home = gpurt(
        &[&[scene.as_str()][..], &size, &["-o", "home.png"]].concat(),
        &dir,
    );
    assert!(
        home.status.success(),
        "{}",
        String::from_utf8_lossy(&home.stderr)
    );
    assert!(
        agree(&offline, &load(&dir.join("home.png"))).is_err(),
        "the orbit moved nothing"
    );
    assert!(agree(&offline, &RgbImage::new(320, 240)).is_err());
}

/// Under either shading model: the window shows that model's offline render, which the
/// other model's does not pass for.
#[test]
fn an_empty_script_at_one_sample_shows_the_offline_render_of_the_scene() {
    let dir = workdir("window-empty");
    std::fs::write(dir.join("empty.txt"), "").unwrap();
    let scene = own_scenes().join("spheres.nff").display().to_string();
    let mut offline = Vec::new();
    for model in ["phong", "blinn-phong"] {
        let (shot, out) = (format!("shot-{model}.png"), format!("offline-{model}.png"));
        let args = [
            scene.as_str(),
            "--spp",
            "1",
            "--shading",
            model,
            "--script",
            "empty.txt",
            "--screenshot",
            &shot,
        ];
        let Some(_) = view_in_xvfb(&args, &dir) else {
            return;
        };
        let o = gpurt(&[&scene, "--shading", model, "-o", &out], &dir);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (image, shot) = (load(&dir.join(&out)), load(&dir.join(&shot)));
        assert_eq!(
            shot.dimensions(),
            image.dimensions(),
            "the scene's resolution"
        );
        agree(&image, &shot)
            .unwrap_or_else(|why| panic!("{model}: window vs offline render: {why}"));
        offline.push((image, shot));
    }
    assert!(
        agree(&offline[0].0, &offline[1].1).is_err(),
        "the Blinn-Phong window passes for the Phong render"
    );
}

/// The viewer's screenshot of `scene` after `script`, 400x300 at 4 samples per pixel.
fn screenshot(dir: &Path, name: &str, script: &str) -> Option<RgbImage> {
    std::fs::write(dir.join(format!("{name}.txt")), script).unwrap();
    let scene = mesh_scene();
    let shot = format!("{name}.png");
    let script = format!("{name}.txt");
    view_in_xvfb(
        &[
            &scene,
            "--width",
            "400",
            "--height",
            "300",
            "--spp",
            "4",
            "--script",
            &script,
            "--screenshot",
            &shot,
        ],
        dir,
    )?;
    Some(load(&dir.join(shot)))
}

#[test]
fn the_three_modes_show_the_image_the_wireframe_and_both_as_the_readme_shows_them() {
    let dir = workdir("window-modes");
    let turn = "drag 40 -12\n";
    let Some(traced) = screenshot(&dir, "ray-traced", turn) else {
        return;
    };
    let wire = screenshot(&dir, "wireframe", &format!("{turn}key m\n")).expect("xvfb-run ran");
    let overlay =
        screenshot(&dir, "overlay", &format!("{turn}key m\nkey m\n")).expect("xvfb-run ran");

    // The wireframe alone is lines on black, and the overlay is the ray-traced image
    // wherever the wireframe drew nothing: the same lines over the same image.
    let line = gpurt::view::wireframe::LINE_COLOR.map(film::quantize);
    let mut lit = 0;
    for ((w, o), t) in wire.pixels().zip(overlay.pixels()).zip(traced.pixels()) {
        if w.0 == [0, 0, 0] {
            assert_eq!(o, t, "overlay and image differ away from the lines");
        } else {
            assert_eq!(w.0, line[..3], "a wireframe pixel not of the line colour");
            assert_eq!(o.0, line[..3], "a line missing from the overlay");
            lit += 1;
        }
    }
    let pixels = 400 * 300;
    assert!(
        lit > pixels / 50 && lit < pixels / 2,
        "{lit} of {pixels} pixels lit"
    );
    assert!(
        agree(&traced, &overlay).is_err(),
        "the overlay shows its lines"
    );

    // The README's screenshots are these; GPURT_UPDATE_VIEWER_SHOTS=1 writes them after
    // a change that is meant to alter them, never otherwise.
    let docs = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/viewer");
    let update = std::env::var("GPURT_UPDATE_VIEWER_SHOTS").is_ok_and(|v| v == "1");
    let mut failures = Vec::new();
    for (name, img) in [
        ("ray-traced", &traced),
        ("wireframe", &wire),
        ("overlay", &overlay),
    ] {
        let path = docs.join(format!("{name}.png"));
        if update {
            film::save_rgb8(img, &path).unwrap();
            continue;
        }
        match film::load_rgb8(&path) {
            Ok(stored) => {
                if let Err(why) = agree(&stored, img) {
                    failures.push(format!("{}: {why}", path.display()));
                }
            }
            Err(e) => failures.push(format!(
                "{e} (GPURT_UPDATE_VIEWER_SHOTS=1 cargo test the_three_modes writes it)"
            )),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn without_a_display_the_viewer_says_so_in_one_line_and_exits_2() {
    let dir = workdir("window-none");
    let out = Command::new(env!("CARGO_BIN_EXE_gpurt"))
        .args(["view", &mesh_scene()])
        .current_dir(&dir)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("gpurt runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("gpurt: cannot open a window: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_bad_script_is_refused_with_its_line_and_column_before_any_window_opens() {
    let dir = workdir("window-script");
    std::fs::write(dir.join("bad.txt"), "drag 1 2\nwait 1\nkey z\n").unwrap();
    let out = gpurt(
        &[
            "view",
            &mesh_scene(),
            "--script",
            "bad.txt",
            "--screenshot",
            "s.png",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("gpurt: bad.txt:3:5: 'z' is not a key"),
        "{err}"
    );
    assert!(!dir.join("s.png").exists());
}

/// An animated scene steps through its frames: three steps on show frame 3, the offline
/// render of that frame's time, with the camera the animation moved; the image of
/// another frame does not pass for it.
#[test]
fn stepping_through_an_animation_shows_the_offline_render_of_the_frame() {
    let dir = workdir("window-animation");
    std::fs::write(dir.join("steps.txt"), "key .\nkey .\nkey .\nkey c\n").unwrap();
    let scene = own_scenes().join("orbit.aff").display().to_string();
    let size = ["--width", "160", "--height", "120", "--spp", "1"];
    let args = [
        &[scene.as_str()][..],
        &size,
        &["--script", "steps.txt", "--screenshot", "shot.png"],
    ]
    .concat();
    let Some(out) = view_in_xvfb(&args, &dir) else {
        return;
    };
    let o = gpurt(
        &[
            &[scene.as_str()][..],
            &size,
            &["--frames", "3", "-o", "f3.png"],
        ]
        .concat(),
        &dir,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let shot = load(&dir.join("shot.png"));
    agree(&load(&dir.join("f3.png")), &shot).unwrap_or_else(|why| panic!("frame 3: {why}"));
    let o = gpurt(
        &[
            &[scene.as_str()][..],
            &size,
            &["--frames", "20", "-o", "f20.png"],
        ]
        .concat(),
        &dir,
    );
    assert!(o.status.success());
    assert!(
        agree(&load(&dir.join("f20.png")), &shot).is_err(),
        "another frame passes"
    );
    // The camera printed is the animation's at frame 3 (it moves along x).
    let view = printed_view(&out.stdout);
    assert!(
        !view.contains("from -1.5 -9 3.5"),
        "the first frame's camera: {view}"
    );
}
