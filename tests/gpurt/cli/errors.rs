//! The command line's failures: bad scenes, formats, arguments and adapters refused with
//! exit code 2 and nothing written, an interrupt that stops without a partial file, and
//! GPU faults (a lost device, an out-of-memory upload) that leave no output behind.

use std::path::Path;
use std::process::Command;

use crate::common::inputs::SCENE;
use crate::common::{gpurt, stderr, workdir};

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
    // The first line names file, line and column; under it the line with a caret under
    // the offending token, as rustc draws one.
    assert_eq!(
        err,
        "gpurt: bad.nff:10:7: expected sphere centre (a number), found 'zero'\n   |\n10 | s 0 0 zero 1\n   |       ^^^^\n"
    );
    assert!(!d.join("out.png").exists());
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "no stray files");
}

/// The excerpt is the line as the reader had it: from a gzip file too, a tab kept under
/// its caret, a huge line cut around the column, escaped bytes shown one
/// way; a misspelt view keyword is named on its own line, with the word it resembles.
#[test]
fn parse_errors_show_their_line_from_any_input() {
    let d = workdir("excerpts");
    let text = SCENE.replace("angle 40", "angel 40");
    let gz = crate::common::inputs::gzip(text.as_bytes());
    crate::common::inputs::write(&d.join("view.nff.gz"), &gz);
    let o = gpurt(&["view.nff.gz", "-o", "out.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.starts_with("gpurt: view.nff.gz:6:1: expected a view keyword")
            && err.contains("found 'angel'; did you mean 'angle'?\n  |\n6 | angel 40\n  | ^^^^^\n"),
        "{err}"
    );
    // A tab and an ESC sequence in a CRLF file.
    let bad = SCENE
        .replace("s 0 0 0 1", "s 0\t0 \x1b[2J 1")
        .replace('\n', "\r\n");
    std::fs::write(d.join("esc.nff"), bad).unwrap();
    let o = gpurt(&["esc.nff", "-o", "out.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.ends_with("found '\\x1b[2J'\n   |\n10 | s 0 0 \\x1b[2J 1\n   |       ^^^^^^^\n"),
        "{err}"
    );
    // A line of 150 000 numbers: the excerpt is a window around the column.
    let long = format!("{SCENE}p 50000 {}0 0 oops\n", "0 0 0 ".repeat(49_999));
    std::fs::write(d.join("long.nff"), long).unwrap();
    let o = gpurt(&["long.nff", "-o", "out.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    let shown = err.lines().nth(2).expect("the excerpt's line");
    assert!(
        shown.starts_with("11 | ...") && shown.ends_with(" oops"),
        "{shown}"
    );
    assert!(shown.len() < 130, "{} bytes", shown.len());
    assert!(err.lines().nth(3).unwrap().ends_with("^^^^"), "{err}");
    // An OBJ corner found bad only at the end of the file (a face may refer to vertices
    // defined later) is quoted too, while the reader still holds its line.
    std::fs::write(d.join("ahead.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 7\nv 0 1 0\n").unwrap();
    let o = gpurt(&["ahead.obj", "-o", "out.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.starts_with("gpurt: ahead.obj:3:7: face corner refers to a vertex that does not exist")
            && err.ends_with("\n  |\n3 | f 1 2 7\n  |       ^\n"),
        "{err}"
    );
}

/// The small messages: each starts with what the user gave, says what is wrong with it,
/// and the command writes nothing.
#[test]
fn small_messages_name_what_was_given() {
    let d = workdir("small-messages");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    std::fs::create_dir(d.join("renders")).unwrap();
    let cases: [(&[&str], &str); 7] = [
        (
            &["ball.nff", "ball.nff"],
            "gpurt: ball.nff, ball.nff: 2 scenes, but one is rendered at a time; give --out-dir DIR",
        ),
        (
            &["ball.nff", "--spp", "-1"],
            "error: invalid value '-1' for '--spp <SPP>': -1 is not in 1..=4096",
        ),
        (
            &["ball.nff", "-o", "renders"],
            "gpurt: renders: is a directory; give an image file name (such as renders/image.png)",
        ),
        (
            &["diff", "ball.nff", "ball.nff"],
            "gpurt: ball.nff: not an image by its content nor by its extension (images: png, ppm, bmp, exr)",
        ),
        (
            &["bench", "nope.nff", "--backend", "cpu"],
            "gpurt: nope.nff: No such file or directory",
        ),
        (
            &["ball.nff", "-o", "out.jpeg"],
            "gpurt: out.jpeg: unsupported image extension '.jpeg'; supported: png, ppm, bmp, exr",
        ),
        (
            &["inof", "ball.nff"],
            "gpurt: 'inof' is neither a scene file nor a command; did you mean `gpurt info`?",
        ),
    ];
    for (args, first_line) in cases {
        let o = gpurt(args, &d);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        // After the lines bench prints about its machine, if any.
        let first = err
            .lines()
            .find(|l| l.starts_with("gpurt: ") || l.starts_with("error: "));
        assert!(
            first.is_some_and(|l| l.starts_with(first_line)),
            "{args:?}: {err}"
        );
        assert!(!err.contains("use '--"), "{args:?}: {err}");
        // bench prints no table header before its error.
        assert!(
            o.stdout.is_empty(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stdout)
        );
    }
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2, "nothing written");
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

/// An output in a folder that does not exist is refused before rendering, naming the
/// folder rather than giving the system's bare "No such file or directory".
#[test]
fn an_output_in_a_missing_folder_names_the_folder() {
    let d = workdir("missing-folder");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = gpurt(&["ball.nff", "-o", "nodir/out.png", "--backend", "cpu"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the folder nodir does not exist"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("nodir").exists());
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
        stderr(&o).contains("2 scenes, but one is rendered at a time"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("a.png").exists() && !d.join("b.png").exists());
}

/// Runs `gpurt SCENE --backend gpu -o out.png ARGS` in `d` with `GPURT_FAULT=fault` and
/// the environment `envs`: it must exit 2 and leave nothing in `d` but the scene (no
/// output file, partial or temporary), and the same command without the fault must write
/// its image. Returns the faulty run's error output.
fn a_gpu_fault_exits_2_without_an_output_file(
    d: &Path,
    scene: &str,
    args: &[&str],
    envs: &[(&str, &str)],
    fault: &str,
) -> String {
    let run = |fault: &str| {
        Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args([scene, "--backend", "gpu", "-o", "out.png"])
            .args(args)
            .current_dir(d)
            .envs(envs.iter().copied())
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
/// output file, partial or temporary. On every adapter: on an H100 and H200s the suite with
/// it stopped making progress, a deadlock in NVIDIA's driver between EGL and Vulkan
/// (docs/gpu.md, "A suite that stopped"), gone since gpurt leaves GL out there.
#[test]
fn a_device_lost_mid_render_exits_non_zero_without_an_output_file() {
    let Some(ctx) = crate::common::gpu_context() else {
        return;
    };
    drop(ctx);
    let d = workdir("device-lost");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    // Several bands on every adapter: a software adapter's take 2^18 samples, and
    // GPURT_BAND_BYTES caps a GPU's at 512 rows (of 512 pixels of 16 bytes), where its
    // own bands (256 MiB) would hold the whole image, read back before the fault.
    let size = ["--width", "512", "--height", "2048", "--spp", "4"];
    let bands = [("GPURT_BAND_BYTES", "4194304")];
    let err =
        a_gpu_fault_exits_2_without_an_output_file(&d, "ball.nff", &size, &bands, "lose-device");
    assert!(err.contains("GPU error: reading back"), "{err}");
}

/// A GPU that does not finish its work within `GPURT_WAIT_LIMIT` (here a microsecond,
/// which a frame of a million pixel samples outlasts on any adapter, lavapipe's first
/// dispatch, which compiles the pipeline, too) ends the command with an error saying so,
/// exit 2 and no output file, instead of waiting for ever; a limit that is not a number
/// of seconds is refused. (The default, `WAIT_LIMIT`, is ten minutes.)
#[test]
fn a_gpu_that_does_not_finish_is_an_error_not_a_hang() {
    let Some(ctx) = crate::common::gpu_context() else {
        return;
    };
    drop(ctx);
    let d = workdir("wait-limit");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    for (limit, says) in [
        (
            "0.000001",
            "GPU error: the GPU did not finish its work within 0.000001 s",
        ),
        ("soon", "GPURT_WAIT_LIMIT=soon: expected seconds above 0"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_gpurt"))
            .args(["ball.nff", "--backend", "gpu", "-o", "out.png"])
            .args(["--width", "512", "--height", "512", "--spp", "4"])
            .current_dir(&d)
            .env("GPURT_CACHE_DIR", "")
            .env("GPURT_WAIT_LIMIT", limit)
            .output()
            .expect("gpurt runs");
        assert_eq!(o.status.code(), Some(2), "{limit}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{limit}: {}", stderr(&o));
        assert!(!d.join("out.png").exists(), "{limit}: no output");
    }
    let o = gpurt(&["ball.nff", "--backend", "gpu", "-o", "out.png"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Through wgpu's GL backend, asked for by name (`WGPU_BACKEND=gl`; gpurt otherwise
/// leaves GL out where Vulkan, Metal or DX12 has an adapter), a render ends in an image or
/// in an error with exit 2 and no file, never in wgpu's panic for an error it was not told
/// to catch: Mesa's GL compiler refuses the GLSL that naga writes for the shader (an
/// internal error, not a validation error), and one without a GL adapter has none to
/// offer.
#[test]
fn a_gl_adapter_renders_or_fails_with_an_error() {
    let d = workdir("gl-backend");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_gpurt"))
        .args(["ball.nff", "--backend", "gpu", "-o", "out.png"])
        .args(["--width", "32", "--height", "32"])
        .current_dir(&d)
        .env("GPURT_CACHE_DIR", "")
        .env("WGPU_BACKEND", "gl")
        .output()
        .expect("gpurt runs");
    let err = stderr(&o);
    println!("WGPU_BACKEND=gl: {:?}, {err}", o.status.code());
    match o.status.code() {
        Some(0) => assert!(d.join("out.png").exists()),
        Some(2) => {
            assert!(err.starts_with("gpurt: "), "{err}");
            assert!(!err.contains("panicked"), "{err}");
            assert!(!d.join("out.png").exists(), "no output");
        }
        code => panic!("exit {code:?}: {err}"),
    }
}

/// A GPU out of memory on upload (`GPURT_FAULT=out-of-memory` allocates each texture, or
/// storage buffer where the adapter reads the scene from buffers, on its own with the process's address space capped just above its size, and
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
    if !gpurt::gpu::is_software(&ctx.info) {
        // A GPU's memory is its own: the address-space cap meets only wgpu's host side,
        // and the upload succeeds (`fault::Fault::OutOfMemory`).
        crate::common::skip(&format!(
            "{}: the out-of-memory fault runs out of memory only on a software adapter",
            ctx.info.name
        ));
        return;
    }
    drop(ctx);
    let d = workdir("out-of-memory");
    let mut scene = String::from(SCENE);
    for i in 0..1_000_000 {
        scene += &format!("s {} {} -900 0.4\n", i % 1000 - 500, i / 1000 - 500);
    }
    std::fs::write(d.join("many.nff"), scene).unwrap();
    let err = a_gpu_fault_exits_2_without_an_output_file(&d, "many.nff", &[], &[], "out-of-memory");
    assert!(
        err.contains("GPU error: uploading the scene: Out of Memory")
            && (err.contains("create_texture") || err.contains("create_buffer")),
        "{err}"
    );
}
