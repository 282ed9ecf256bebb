//! An animated scene's frames from the command line: a sequence in one process, the same
//! shared out as a farm's array tasks and resumed after a restart, one frame alone with
//! `--time`, and bad ranges and names refused before anything is written.

use std::path::Path;
use std::process::Command;

use crate::common::{gpurt, own_scenes, stderr, workdir};

const SMALL: [&str; 6] = ["--width", "40", "--height", "30", "--backend", "cpu"];

fn frames(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    files.sort();
    files
}

#[test]
fn a_sharded_and_resumed_sequence_writes_the_frames_one_process_does() {
    let d = workdir("sequence");
    let scene = own_scenes().join("orbit.aff");
    let scene = scene.to_str().unwrap();
    let run = |extra: &[&str], task: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_gpurt"));
        c.args([&[scene][..], &SMALL, extra].concat())
            .current_dir(&d)
            .env("GPURT_CACHE_DIR", "");
        if let Some(t) = task {
            c.env("SLURM_ARRAY_TASK_ID", t);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        o
    };
    run(&["--frames", "10..15", "-o", "one/f-%03d.png"], None);
    let one = frames(&d.join("one"));
    let names: Vec<&str> = one.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "f-010.png",
            "f-011.png",
            "f-012.png",
            "f-013.png",
            "f-014.png",
            "f-015.png"
        ]
    );
    // The frames differ (things move), so a frame written for another shows.
    assert!(one.windows(2).all(|w| w[0].1 != w[1].1));
    // Three array tasks, each its index from Slurm's variable.
    for task in ["0", "1", "2"] {
        run(
            &[
                "--frames",
                "10..15",
                "-o",
                "farm/f-%03d.png",
                "--shard",
                "/3",
            ],
            Some(task),
        );
    }
    assert_eq!(
        frames(&d.join("farm")),
        one,
        "the farm's frames are the process's"
    );
    // A task restarted after a frame was lost writes that frame only.
    std::fs::remove_file(d.join("farm/f-013.png")).unwrap();
    let before = std::fs::metadata(d.join("farm/f-010.png"))
        .unwrap()
        .modified()
        .unwrap();
    let o = run(
        &["--frames", "10..15", "-o", "farm/f-%03d.png", "--resume"],
        None,
    );
    assert!(
        stderr(&o).contains("5 of 6 frames written already (--resume); rendering 1"),
        "{}",
        stderr(&o)
    );
    assert_eq!(frames(&d.join("farm")), one);
    let after = std::fs::metadata(d.join("farm/f-010.png"))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(before, after, "a frame written already is left alone");
    // One frame alone, by its time: frame 12 of 48 over [0, 2] is at t = 24/47.
    let t = format!("{}", 24.0 / 47.0);
    run(&["--time", &t, "-o", "alone.png"], None);
    assert_eq!(std::fs::read(d.join("alone.png")).unwrap(), one[2].1);
}

#[test]
fn bad_ranges_and_names_are_refused_before_anything_renders() {
    let d = workdir("sequence-errors");
    let orbit = own_scenes().join("orbit.aff");
    let orbit = orbit.to_str().unwrap();
    let still = own_scenes().join("spheres.nff");
    let still = still.to_str().unwrap();
    let refused = |args: &[&str], words: &[&str]| {
        let o = gpurt(&[args, &SMALL].concat(), &d);
        assert!(!o.status.success(), "{args:?} should fail");
        let err = stderr(&o);
        for w in words {
            assert!(err.contains(w), "{args:?}: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            0,
            "{args:?} wrote nothing"
        );
    };
    refused(
        &[orbit, "--frames", "40..60", "-o", "out/f-%d.png"],
        &["frames 40..60 are outside the animation", "0..47"],
    );
    refused(
        &[orbit, "--frames", "0..3", "-o", "out.png"],
        &["4 frames would all be written to out.png", "%04d"],
    );
    refused(
        &[orbit, "--frames", "0..3", "-o", "f-%d-%d.png"],
        &["two frame numbers"],
    );
    refused(
        &[orbit, "--frames", "3..1", "-o", "f-%d.png"],
        &["ends before it starts"],
    );
    refused(
        &[still, "--frames", "0..3", "-o", "f-%d.png"],
        &["spheres.nff", "needs an animated scene", "nothing moves"],
    );
    refused(
        &[still, "--time", "1", "-o", "x.png"],
        &["--time is for scenes that move"],
    );
    // A scene whose transform has no keyframes: its name, line and column.
    std::fs::write(
        d.join("ghost.aff"),
        "v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 45\na 0 1 5\nx ghost {\n s 0 0 0 1\n}\n",
    )
    .unwrap();
    let o = gpurt(
        &[
            &["ghost.aff", "--frames", "all", "-o", "f-%d.png"][..],
            &SMALL,
        ]
        .concat(),
        &d,
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("ghost.aff:7:3: transform 'ghost' has no keyframes"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("f-0.png").exists());
}

#[test]
fn info_says_what_moves() {
    let d = workdir("sequence-info");
    let orbit = own_scenes().join("orbit.aff");
    let o = gpurt(
        &[&["info", orbit.to_str().unwrap(), "--json"][..]].concat(),
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let a = &v["animation"];
    assert_eq!(
        a["range"],
        serde_json::json!({"start": 0.0, "end": 2.0, "frames": 48})
    );
    assert_eq!(
        a["moving"]["spheres"], 1,
        "the ball; the mirror sphere is still"
    );
    assert_eq!(v["spheres"], 1);
    assert_eq!(
        (a["camera_moves"].as_bool(), a["moving_lights"].as_u64()),
        (Some(true), Some(1))
    );
    let still = own_scenes().join("spheres.nff");
    let o = gpurt(&["info", still.to_str().unwrap(), "--json"], &d);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["animation"].is_null());
}

/// Each frame's tree made four ways (`GPURT_FRAME_TREE`): the whole scene's built anew,
/// the moving part's built anew, refitted however worn, or chosen by the wear. The trees
/// differ, the images do not, on the CPU and on the GPU; `--stats` says which were made.
#[test]
fn refitted_rebuilt_and_whole_trees_give_the_same_frames() {
    let d = workdir("sequence-trees");
    let scene = own_scenes().join("orbit.aff");
    let scene = scene.to_str().unwrap();
    let mut backends = vec!["cpu"];
    if crate::common::gpu_context().is_some() {
        backends.push("gpu");
    }
    for backend in backends {
        // The GPU renders fewer frames: lavapipe compiles and traces slowly.
        let range = if backend == "cpu" { "all" } else { "20..27" };
        let mut first: Option<Vec<(String, Vec<u8>)>> = None;
        for mode in ["whole", "rebuild", "refit", "auto"] {
            let dir = format!("{backend}-{mode}");
            let o = Command::new(env!("CARGO_BIN_EXE_gpurt"))
                .args([scene, "--frames", range, "-o", &format!("{dir}/f-%02d.png")])
                .args(["--width", "40", "--height", "30", "--backend", backend])
                .args(["--stats"])
                .current_dir(&d)
                .env("GPURT_CACHE_DIR", "")
                .env("GPURT_FRAME_TREE", mode)
                .output()
                .unwrap();
            let err = stderr(&o);
            assert!(o.status.success(), "{backend} {mode}: {err}");
            let trees = err.lines().find(|l| l.starts_with("trees")).unwrap_or("");
            let expected = match mode {
                "whole" => "whole",
                "rebuild" => "rebuilt",
                _ => "refitted",
            };
            assert!(trees.contains(expected), "{backend} {mode}: {trees}");
            let images = frames(&d.join(&dir));
            match &first {
                None => first = Some(images),
                Some(f) => assert!(
                    f == &images,
                    "{backend}: the frames with {mode} trees differ from the whole scene's"
                ),
            }
        }
    }
}
