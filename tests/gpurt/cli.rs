//! The `gpurt` command as a user runs it: exit codes, messages, files written or not.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::{gpurt, workdir};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const SCENE: &str = "b 0.1 0.2 0.3
v
from 0 -4 1
at 0 0 0
up 0 0 1
angle 40
resolution 32 32
l 2 -3 4
f 1 0.5 0.2 0.8 0.2 20 0 1
s 0 0 0 1
";

#[test]
fn renders_to_the_default_name_and_to_each_format() {
    let d = workdir("formats");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "--backend", "cpu"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(d.join("ball.png")).expect("ball.png written");
    assert_eq!((img.width(), img.height()), (32, 32));
    for ext in ["ppm", "bmp", "exr"] {
        let out = format!("ball.{ext}");
        let o = gpurt(
            &["ball.nff", "--backend", "cpu", "-o", &out, "--width", "20"],
            &d,
        );
        assert!(o.status.success(), "{ext}: {}", stderr(&o));
        let img = image::open(d.join(&out)).unwrap_or_else(|e| panic!("{out}: {e}"));
        assert_eq!(img.width(), 20);
    }
}

#[test]
fn bad_scene_reports_file_line_column_exits_2_and_writes_nothing() {
    let d = workdir("bad-scene");
    std::fs::write(
        d.join("bad.nff"),
        SCENE.replace("s 0 0 0 1", "s 0 0 zero 1"),
    )
    .unwrap();
    let o = gpurt(&["bad.nff", "-o", "out.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("bad.nff:10:7:"), "{err}");
    assert!(!d.join("out.png").exists());
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "no stray files");
}

#[test]
fn unknown_output_format_is_refused_before_rendering() {
    let d = workdir("bad-format");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "-o", "out.jpg"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("jpg"), "{}", stderr(&o));
    assert!(!d.join("out.jpg").exists());
}

#[test]
fn missing_scene_and_bad_arguments_fail_cleanly() {
    let d = workdir("missing");
    let o = gpurt(&["nope.nff"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("nope.nff"), "{}", stderr(&o));
    // A bad argument is refused for itself: the scene exists and is valid.
    std::fs::write(d.join("x.nff"), SCENE).unwrap();
    let o = gpurt(&["x.nff", "--depth", "99", "--backend", "cpu"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--depth"), "{}", stderr(&o));
    assert!(stderr(&o).contains("99"), "{}", stderr(&o));
    assert!(!d.join("x.png").exists());
    let o = gpurt(&["x.nff", "--backend", "cpu"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn info_json_has_the_documented_keys() {
    let d = workdir("info");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    std::fs::write(
        d.join("full.nff"),
        format!("{SCENE}am 0.05 0.05 0.05\nal 0 0 5 1 0 0 0 1 0 0.5 0.5 0.5 2 3\n"),
    )
    .unwrap();
    let o = gpurt(&["info", "ball.nff", "--json"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    for key in ["spheres", "triangles", "planes", "cones", "boxes"] {
        assert!(v[key].is_u64(), "{key} missing or not an integer in {v}");
    }
    assert_eq!(v["spheres"], 1);
    assert!(v["warnings"].is_array());
    assert!(v["ambient"].is_null());
    assert_eq!(v["ambient_used"], serde_json::json!([0.1, 0.1, 0.1]));

    // docs/info-json.md: every light and material with its parameters, the ambient, and
    // floats as the shortest decimal of the f32.
    let o = gpurt(&["info", "full.nff", "--json"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(!text.contains("0.0500000"), "{text}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    assert_eq!(v["ambient"], serde_json::json!([0.05, 0.05, 0.05]));
    let lights = v["lights"].as_array().expect("lights array");
    assert_eq!(lights.len(), 2, "{v}");
    assert_eq!(lights[0]["kind"], "point");
    assert_eq!(lights[0]["position"], serde_json::json!([2.0, -3.0, 4.0]));
    assert!(lights[0]["color"].is_null());
    assert_eq!(lights[1]["kind"], "area");
    assert_eq!(lights[1]["samples"], serde_json::json!([2, 3]));
    assert_eq!(lights[1]["color"], serde_json::json!([0.5, 0.5, 0.5]));
    let m = &v["materials"][0];
    assert_eq!(m["color"], serde_json::json!([1.0, 0.5, 0.2]));
    assert_eq!(
        (m["kd"].as_f64(), m["shine"].as_f64()),
        (Some(0.8), Some(20.0))
    );

    let o = gpurt(&["info", "full.nff"], &d);
    assert!(String::from_utf8_lossy(&o.stdout).contains("ambient     0.05 0.05 0.05"));
}

#[test]
fn diff_exit_codes_and_heat_map() {
    let d = workdir("diff");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let a = gpurt(&["ball.nff", "--backend", "cpu", "-o", "a.png"], &d);
    assert!(a.status.success(), "{}", stderr(&a));
    std::fs::copy(d.join("a.png"), d.join("same.png")).unwrap();
    let o = gpurt(
        &[
            "diff",
            "a.png",
            "same.png",
            "--max-flip",
            "0.01",
            "--max-bad",
            "0.005",
        ],
        &d,
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("PSNR"));

    let b = gpurt(
        &[
            "ball.nff",
            "--backend",
            "cpu",
            "-o",
            "b.png",
            "--ambient",
            "0.6",
        ],
        &d,
    );
    assert!(b.status.success(), "{}", stderr(&b));
    let o = gpurt(
        &[
            "diff",
            "a.png",
            "b.png",
            "-o",
            "heat.png",
            "--max-flip",
            "0.01",
            "--max-bad",
            "0.005",
        ],
        &d,
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let heat = image::open(d.join("heat.png")).expect("heat map written");
    assert_eq!(
        (heat.width(), heat.height()),
        (96, 32),
        "A | B | difference"
    );

    // With no flags the GPU-vs-CPU limits apply: the same images pass, different ones
    // fail; a flag loosens the limit it names.
    let o = gpurt(&["diff", "a.png", "same.png"], &d);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = gpurt(&["diff", "a.png", "b.png"], &d);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let o = gpurt(
        &[
            "diff",
            "a.png",
            "b.png",
            "--max-bad",
            "1",
            "--max-flip",
            "1",
        ],
        &d,
    );
    assert_eq!(o.status.code(), Some(1), "the bias limit still applies");

    let o = gpurt(&["diff", "a.png", "missing.png"], &d);
    assert_eq!(o.status.code(), Some(2));
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

/// Ctrl-C (SIGINT) stops a render cleanly: exit code 130, a message, and no output file.
#[test]
fn interrupt_stops_without_writing_a_partial_file() {
    for signal in ["INT", "TERM"] {
        let d = workdir(&format!("interrupt-{signal}"));
        std::fs::write(d.join("ball.nff"), SCENE).unwrap();
        // Some seconds of work on two cores; interrupted long before it ends.
        let child = Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args([
                "ball.nff",
                "--backend",
                "cpu",
                "--width",
                "2048",
                "--height",
                "2048",
            ])
            .args(["--spp", "64", "-o", "out.png"])
            .current_dir(&d)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("gpurt starts");
        std::thread::sleep(std::time::Duration::from_millis(700));
        let killed = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .expect("kill runs");
        assert!(killed.success());
        let out = child.wait_with_output().expect("gpurt ends");
        assert_eq!(
            out.status.code(),
            Some(130),
            "SIG{signal}: {}",
            stderr(&out)
        );
        assert!(stderr(&out).contains("interrupted"), "{}", stderr(&out));
        assert!(!d.join("out.png").exists());
        let leftovers: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(leftovers.len(), 1, "only the scene remains: {leftovers:?}");
    }
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

/// A reader that goes away (`gpurt info scene | true`) ends the command quietly: no
/// panic, exit 0, and `diff` still writes its heat map.
#[test]
fn closed_stdout_ends_quietly() {
    let d = workdir("closed-stdout");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "--backend", "cpu", "-o", "a.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::copy(d.join("a.png"), d.join("b.png")).unwrap();
    let closed = |args: &[&str]| {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args(args)
            .current_dir(&d)
            .stdout(writer)
            .output()
            .expect("gpurt runs")
    };
    for args in [
        &["info", "ball.nff"][..],
        &["info", "ball.nff", "--json"],
        &["diff", "a.png", "b.png", "-o", "heat.png"],
    ] {
        let o = closed(args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
    }
    assert!(d.join("heat.png").is_file());
}

/// An adapter asked for by name that does not exist is an error (exit 2, no image), not a
/// silent fallback to the CPU; a non-finite `diff` threshold is refused.
#[test]
fn missing_named_adapter_and_nan_thresholds_are_refused() {
    let d = workdir("named-adapter");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(
        &[
            "ball.nff",
            "--adapter",
            "no-such-adapter-xyz",
            "-o",
            "out.png",
        ],
        &d,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no-such-adapter-xyz"), "{}", stderr(&o));
    assert!(!d.join("out.png").exists());

    let o = gpurt(&["ball.nff", "--backend", "cpu", "-o", "a.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    for bad in ["nan", "inf", "-1"] {
        let o = gpurt(&["diff", "a.png", "a.png", "--max-flip", bad], &d);
        assert_eq!(o.status.code(), Some(2), "--max-flip {bad}: {}", stderr(&o));
        let o = gpurt(&["diff", "a.png", "a.png", "--max-bad", bad], &d);
        assert_eq!(o.status.code(), Some(2), "--max-bad {bad}: {}", stderr(&o));
    }
    let o = gpurt(&["diff", "a.png", "a.png", "--max-flip", "0.01"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Two scenes are refused with a message saying one is rendered at a time (not clap's
/// "the subcommand 'b.nff' cannot be used"), and nothing is written.
#[test]
fn two_scenes_are_refused_with_a_clear_message() {
    let d = workdir("two-scenes");
    std::fs::write(d.join("a.nff"), SCENE).unwrap();
    std::fs::write(d.join("b.nff"), SCENE).unwrap();
    let o = gpurt(&["a.nff", "b.nff", "--backend", "cpu"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("one scene is rendered at a time"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("a.png").exists() && !d.join("b.png").exists());
}

/// `--view FILE` takes the camera from a file's `v` block: the image is the one of the
/// scene with that block in place of its own, to the bit (CPU backend).
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
    std::fs::write(d.join("moved.nff"), moved).unwrap();
    for (scene, out, extra) in [
        ("scene.nff", "a.png", vec!["--view", "view.nff"]),
        ("moved.nff", "b.png", vec![]),
        ("scene.nff", "c.png", vec![]),
    ] {
        let mut args = vec![scene, "--backend", "cpu", "-o", out];
        args.extend(extra);
        let o = gpurt(&args, &d);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |f: &str| image::open(d.join(f)).unwrap().to_rgb8();
    assert_eq!(read("a.png").dimensions(), (40, 30));
    assert_eq!(read("a.png"), read("b.png"));
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

/// Runs `gpurt SCENE --backend gpu -o out.png ARGS` in `d` with `GPURT_FAULT=fault`: it
/// must exit 2 and leave nothing in `d` but the scene (no output file, partial or
/// temporary), and the same command without the fault must write its image. Returns the
/// faulty run's error output.
fn a_gpu_fault_exits_2_without_an_output_file(
    d: &Path,
    scene: &str,
    args: &[&str],
    fault: &str,
) -> String {
    let run = |fault: &str| {
        Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args([scene, "--backend", "gpu", "-o", "out.png"])
            .args(args)
            .current_dir(d)
            .env("GPURT_CACHE_DIR", "")
            .env("GPURT_FAULT", fault)
            .output()
            .expect("gpurt runs")
    };
    let o = run(fault);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let left: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, [scene], "no output file, partial or temporary");
    let ok = run("");
    assert!(ok.status.success(), "{}", stderr(&ok));
    assert!(d.join("out.png").exists());
    stderr(&o)
}

/// A GPU lost mid-render (`GPURT_FAULT=lose-device` destroys the device once the first
/// band is in) ends the command with an error naming the step, a non-zero exit and no
/// output file, partial or temporary.
#[test]
fn a_device_lost_mid_render_exits_non_zero_without_an_output_file() {
    let Some(ctx) = crate::common::gpu_context() else {
        return;
    };
    drop(ctx);
    let d = workdir("device-lost");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    // Four bands on a software adapter (2^18 samples a band), several on any other.
    let size = ["--width", "512", "--height", "2048", "--spp", "4"];
    let err = a_gpu_fault_exits_2_without_an_output_file(&d, "ball.nff", &size, "lose-device");
    assert!(err.contains("GPU error: reading back"), "{err}");
}

/// A GPU out of memory on upload (`GPURT_FAULT=out-of-memory` allocates each texture of
/// the scene on its own with the process's address space capped just above its size, and
/// lavapipe's device memory is the process's own: `fault.rs`) ends in an error naming the
/// upload and the allocation that failed, exit 2, and no output file. The scene's arrays
/// (a million spheres, 48 MB of them primitives) are larger than the cap leaves, and than
/// the 32 MiB above which glibc always maps fresh memory (a smaller texture may fit in
/// heap space freed by the BVH build).
#[cfg(target_os = "linux")]
#[test]
fn an_out_of_memory_on_upload_exits_non_zero_without_an_output_file() {
    let Some(ctx) = crate::common::gpu_context() else {
        return;
    };
    drop(ctx);
    let d = workdir("out-of-memory");
    let mut scene = String::from(SCENE);
    for i in 0..1_000_000 {
        scene += &format!("s {} {} -900 0.4\n", i % 1000 - 500, i / 1000 - 500);
    }
    std::fs::write(d.join("many.nff"), scene).unwrap();
    let err = a_gpu_fault_exits_2_without_an_output_file(&d, "many.nff", &[], "out-of-memory");
    assert!(
        err.contains("GPU error: uploading the scene: Out of Memory")
            && err.contains("create_texture"),
        "{err}"
    );
}

#[test]
fn a_batch_renders_every_scene_it_can_into_its_directory_and_reports_the_rest() {
    let d = workdir("batch");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    std::fs::write(d.join("broken.nff"), "v\nfrom 0 0\n").unwrap();
    std::fs::copy(
        crate::common::own_scenes().join("icosahedron.stl"),
        d.join("ico.stl"),
    )
    .unwrap();
    let size = ["--width", "40", "--height", "30", "--backend", "cpu"];
    let o = gpurt(
        &[
            &["ball.nff", "broken.nff", "ico.stl", "--out-dir", "out"][..],
            &size,
        ]
        .concat(),
        &d,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("gpurt: broken.nff: skipped: broken.nff:3:1: "),
        "{err}"
    );
    assert!(err.contains("2 of 3 scenes rendered"), "{err}");
    assert!(!d.join("out/broken.png").exists());
    // Each image is the one a render of its scene alone writes, to the byte.
    for scene in ["ball", "ico"] {
        let input = if scene == "ball" {
            "ball.nff"
        } else {
            "ico.stl"
        };
        let alone = format!("{scene}-alone.png");
        let o = gpurt(&[&[input, "-o", alone.as_str()][..], &size].concat(), &d);
        assert!(o.status.success(), "{}", stderr(&o));
        let batch = std::fs::read(d.join(format!("out/{scene}.png"))).unwrap();
        assert_eq!(batch, std::fs::read(d.join(&alone)).unwrap(), "{scene}");
    }
    // Two scenes with one name are refused before anything renders.
    std::fs::create_dir_all(d.join("other")).unwrap();
    std::fs::write(d.join("other/ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "other/ball.nff", "--out-dir", "clash"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("would both be written to clash/ball.png"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("clash").exists());
}

#[test]
fn batch_shards_run_as_separate_processes_write_the_whole_batch_between_them() {
    let d = workdir("batch-shards");
    let names = ["a", "b", "c", "d", "e"];
    for (k, n) in names.iter().enumerate() {
        // Five scenes that differ (the ball moves), so a mix-up shows.
        let scene = SCENE.replace("s 0 0 0 1", &format!("s {} 0 0 1", k as f32 * 0.2));
        std::fs::write(d.join(format!("{n}.nff")), scene).unwrap();
    }
    let scenes: Vec<String> = names.iter().map(|n| format!("{n}.nff")).collect();
    let args = |dir: &str, shard: Option<&str>| {
        let mut a: Vec<String> = scenes.clone();
        a.extend(["--out-dir", dir, "--backend", "cpu"].map(String::from));
        if let Some(s) = shard {
            a.extend(["--shard".to_string(), s.to_string()]);
        }
        a
    };
    let run = |a: &[String], task: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_gpurt"));
        c.args(a).current_dir(&d);
        if let Some(t) = task {
            c.env("SLURM_ARRAY_TASK_ID", t);
        }
        let o = c.output().expect("gpurt runs");
        assert!(o.status.success(), "{}", stderr(&o));
    };
    run(&args("whole", None), None);
    // Task 0 from the job array's variable, task 1 given outright.
    run(&args("sharded", Some("/2")), Some("0"));
    let first: Vec<String> = crate::common::files_with(&d.join("sharded"), &[".png"])
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(first, ["a.png", "c.png", "e.png"]);
    run(&args("sharded", Some("1/2")), None);
    for n in names {
        let whole = std::fs::read(d.join(format!("whole/{n}.png"))).unwrap();
        let shard = std::fs::read(d.join(format!("sharded/{n}.png"))).unwrap();
        assert_eq!(whole, shard, "{n}");
    }
    let o = gpurt(&[&scenes[0], "--out-dir", "x", "--shard", "2/2"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("the shard index must be 0 to 1"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn image_shards_run_as_separate_processes_merge_into_the_single_process_image() {
    let d = workdir("image-shards");
    let glass = crate::common::own_scenes().join("glass.nff");
    let glass = glass.to_str().unwrap();
    let frame = [
        "--width",
        "61",
        "--height",
        "47",
        "--spp",
        "3",
        "--backend",
        "cpu",
    ];
    let shard = |i: &str, dir: &str, scene: &str| {
        let o = gpurt(
            &[&[scene, "--shard", i, "-o", dir][..], &frame].concat(),
            &d,
        );
        assert!(o.status.success(), "shard {i}: {}", stderr(&o));
    };
    for i in ["0/3", "1/3", "2/3"] {
        shard(i, "parts", glass);
    }
    let o = gpurt(&["merge", "parts", "-o", "merged.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = gpurt(&[&[glass, "-o", "single.png"][..], &frame].concat(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(d.join("merged.png")).unwrap(),
        std::fs::read(d.join("single.png")).unwrap(),
        "byte-identical"
    );

    // By samples: 7 samples in runs of 2, 2 and 3, merged in sample order.
    let seven = [
        "--width",
        "61",
        "--height",
        "47",
        "--spp",
        "7",
        "--backend",
        "cpu",
    ];
    for i in ["0/3", "1/3", "2/3"] {
        let args = [
            &[glass, "--shard", i, "--shard-by", "samples", "-o", "runs"][..],
            &seven,
        ];
        let o = gpurt(&args.concat(), &d);
        assert!(o.status.success(), "shard {i}: {}", stderr(&o));
    }
    let o = gpurt(&["merge", "runs", "-o", "merged7.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = gpurt(&[&[glass, "-o", "single7.png"][..], &seven].concat(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(d.join("merged7.png")).unwrap(),
        std::fs::read(d.join("single7.png")).unwrap(),
        "byte-identical by samples"
    );
    // A tiles shard among samples shards belongs to another render.
    for ext in ["json", "rgbf32"] {
        let f = format!("shard-1-of-3.{ext}");
        std::fs::copy(d.join("parts").join(&f), d.join("runs").join(&f)).unwrap();
    }
    let o = gpurt(&["merge", "runs", "-o", "mixed.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("belongs to another render"),
        "{}",
        stderr(&o)
    );

    // A missing shard is named, and nothing is written.
    std::fs::create_dir_all(d.join("gap")).unwrap();
    for ext in ["json", "rgbf32"] {
        let f = format!("shard-0-of-3.{ext}");
        std::fs::copy(d.join("parts").join(&f), d.join("gap").join(&f)).unwrap();
        let f = format!("shard-2-of-3.{ext}");
        std::fs::copy(d.join("parts").join(&f), d.join("gap").join(&f)).unwrap();
    }
    let o = gpurt(&["merge", "gap", "-o", "gap.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("shard 1 of 3 is missing"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("gap.png").exists());

    // A shard of another scene in the set is named as foreign.
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    shard("1/3", "gap", "ball.nff");
    let o = gpurt(&["merge", "gap", "-o", "gap.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("shard-1-of-3.json belongs to another render"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("gap.png").exists());
}
