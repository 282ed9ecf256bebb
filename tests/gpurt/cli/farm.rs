//! Work shared out: a batch of scenes in one process, its shards as separate processes,
//! and image shards (by rows or by samples) merged into the single-process image.

use std::process::Command;

use crate::common::inputs::SCENE;
use crate::common::{gpurt, stderr, workdir};

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
    // Named once, where the error is, with its line under it.
    assert!(err.contains("gpurt: broken.nff:3:1: "), "{err}");
    assert!(err.contains(" (skipped)\n  |\n3 | "), "{err}");
    assert_eq!(err.matches("broken.nff").count(), 1, "{err}");
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

    // A Blinn-Phong shard among Phong ones belongs to another render, and says so.
    let blinn = [
        &[glass, "--shard", "1/3", "-o", "blinn"][..],
        &frame,
        &["--shading", "blinn-phong"],
    ];
    let o = gpurt(&blinn.concat(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let manifest = std::fs::read_to_string(d.join("blinn/shard-1-of-3.json")).unwrap();
    assert!(
        manifest.contains(r#""shading": "blinn-phong""#),
        "{manifest}"
    );
    std::fs::create_dir_all(d.join("models")).unwrap();
    for (from, i) in [("parts", 0), ("blinn", 1), ("parts", 2)] {
        for ext in ["json", "rgbf32"] {
            let f = format!("shard-{i}-of-3.{ext}");
            std::fs::copy(d.join(from).join(&f), d.join("models").join(&f)).unwrap();
        }
    }
    let o = gpurt(&["merge", "models", "-o", "models.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("belongs to another render"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("blinn-phong shading"), "{}", stderr(&o));
    assert!(!d.join("models.png").exists());
    // The model alone tells them apart: a manifest edited to match in all but the model
    // is refused too.
    let phong = std::fs::read_to_string(d.join("parts/shard-1-of-3.json")).unwrap();
    let edited = phong.replacen('{', r#"{"shading": "blinn-phong","#, 1);
    std::fs::write(d.join("models/shard-1-of-3.json"), edited).unwrap();
    std::fs::copy(
        d.join("parts/shard-1-of-3.rgbf32"),
        d.join("models/shard-1-of-3.rgbf32"),
    )
    .unwrap();
    let o = gpurt(&["merge", "models", "-o", "models.png"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!d.join("models.png").exists());

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

    // A shard's pixels cut short are named with the size they should have.
    std::fs::create_dir_all(d.join("short")).unwrap();
    for i in 0..3 {
        for ext in ["json", "rgbf32"] {
            let f = format!("shard-{i}-of-3.{ext}");
            std::fs::copy(d.join("parts").join(&f), d.join("short").join(&f)).unwrap();
        }
    }
    let cut = d.join("short/shard-2-of-3.rgbf32");
    let len = std::fs::metadata(&cut).unwrap().len();
    let file = std::fs::OpenOptions::new().write(true).open(&cut).unwrap();
    file.set_len(len - 12).unwrap();
    let o = gpurt(&["merge", "short", "-o", "short.png"], &d);
    assert_eq!(o.status.code(), Some(2));
    let expected = format!("shard-2-of-3.rgbf32: {} bytes, expected {len}", len - 12);
    assert!(stderr(&o).contains(&expected), "{}", stderr(&o));
    assert!(!d.join("short.png").exists());

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
