//! `gpurt info`, `gpurt diff`, `gpurt bench` and `gpurt tune`: the documented JSON, exit
//! codes and heat maps, the shading model bench times, the tuning renders take, and a
//! reader that goes away ending the command quietly.

use std::process::Command;

use crate::common::inputs::SCENE;
use crate::common::{gpu_context, gpurt, stderr, workdir};

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

/// scenes/cornell.nff, a Cornell box whose OBJ's `.mtl` gives its ceiling light `Ke 17 12
/// 4`: `info` lists that emitter as the scene's one light (the bare OBJ too, which then
/// gets no light of the framing's), and a render is lit by it alone, from its front: the
/// light seen white, the floor lit, the ceiling above the light with the ambient term only.
#[test]
fn the_cornell_box_is_lit_by_its_ceiling_emitter_alone() {
    let d = workdir("cornell");
    let scenes = crate::common::own_scenes();
    for file in ["cornell.nff", "cornell.obj"] {
        let path = scenes.join(file).display().to_string();
        let o = gpurt(&["info", &path, "--json"], &d);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
        let lights = v["lights"].as_array().expect("lights array");
        assert_eq!(lights.len(), 1, "{file}: {v}");
        let e = &lights[0];
        assert_eq!(
            (&e["kind"], &e["triangles"], &e["color"]),
            (
                &"emitter".into(),
                &2.into(),
                &serde_json::json!([17.0, 12.0, 4.0])
            ),
            "{file}: {v}"
        );
        let area = e["area"].as_f64().unwrap();
        assert!((area - 0.47 * 0.38).abs() < 1e-4, "{area}");
        assert_eq!(
            v["materials"][e["material"].as_u64().unwrap() as usize]["emission"],
            e["color"]
        );
    }
    let scene = scenes.join("cornell.nff").display().to_string();
    let o = gpurt(
        &[
            &scene,
            "-o",
            "c.png",
            "--backend",
            "cpu",
            "--width",
            "64",
            "--height",
            "64",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(d.join("c.png"))
        .expect("c.png written")
        .to_rgb8();
    let red = |x, y| img.get_pixel(x, y).0[0];
    // The light, under the ceiling in rows 8 to 10: its radiance, above 1, is white.
    assert_eq!(img.get_pixel(32, 9).0, [255, 255, 255]);
    // The ceiling in front of it: ambient 0.1 x Kd 0.73 alone (18.6), the light behind it.
    for x in 24..40 {
        assert_eq!(red(x, 2), 19, "ceiling at ({x}, 2)");
    }
    // The floor left of the blocks, lit from above.
    assert!(red(16, 60) > 40, "floor {}", red(16, 60));
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

#[test]
fn lenient_reads_foreign_nff_for_info_and_renders_and_is_off_by_default() {
    use crate::common::inputs::VIEW;
    use crate::parse::materials::FOREIGN;
    let d = workdir("lenient-cli");
    std::fs::write(d.join("x.nff"), format!("{VIEW}{FOREIGN}")).unwrap();
    // Off by default: the first foreign keyword is an error, exit 2, no image.
    let o = gpurt(&["x.nff", "-o", "x.png", "--backend", "cpu"], &d);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("x.nff:6:1: expected an entity keyword, found 'Q'"),
        "{}",
        stderr(&o)
    );
    assert!(!d.join("x.png").exists());
    // `info --lenient` counts what is read and lists every skip.
    let o = gpurt(&["info", "x.nff", "--json", "--lenient"], &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    assert_eq!(v["spheres"], 2, "{v}");
    let warnings: Vec<&str> = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    let keywords: Vec<String> = warnings
        .iter()
        .map(|w| w.split('\'').nth(1).unwrap_or("").to_string())
        .collect();
    assert_eq!(keywords, ["Q", "fp", "obj", "Q"], "{warnings:?}");
    assert!(
        warnings[2].starts_with("x.nff:11:1: unknown keyword 'obj' skipped"),
        "{warnings:?}"
    );
    // A render, and a batch, with it: the image, and the warnings on stderr.
    for args in [
        &["x.nff", "-o", "x.png"][..],
        &["x.nff", "--out-dir", "out"][..],
    ] {
        let o = gpurt(
            &[
                args,
                &[
                    "--backend",
                    "cpu",
                    "--width",
                    "32",
                    "--height",
                    "24",
                    "--lenient",
                ],
            ]
            .concat(),
            &d,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(
            stderr(&o).matches("gpurt: warning: x.nff:").count(),
            4,
            "{}",
            stderr(&o)
        );
    }
    assert!(d.join("x.png").exists() && d.join("out/x.png").exists());
}

/// `gpurt bench` under Blinn-Phong: both backends time the model asked for, say which,
/// and trace the same rays (a mismatch would be a warning).
#[test]
fn bench_times_the_shading_model_it_is_given() {
    let d = workdir("bench-shading");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let args = [
        "bench",
        "ball.nff",
        "--sizes",
        "24x16",
        "--frames",
        "1",
        "--backend",
        "both",
        "--shading",
        "blinn-phong",
    ];
    let o = gpurt(&args, &d);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("shading     blinn-phong"), "{err}");
    assert!(!err.contains("warning"), "{err}");
    // Beside the adapter, which of its features bear on speed.
    if gpu_context().is_some() {
        let features = err.lines().find_map(|l| l.strip_prefix("features    "));
        let said: Vec<_> = features.map_or(vec![], |l| {
            l.split(", ").filter_map(|f| f.rsplit_once(' ')).collect()
        });
        let names: Vec<_> = said.iter().map(|&(name, _)| name).collect();
        assert_eq!(names, ["timestamps", "subgroups", "ray queries"], "{err}");
        assert!(said.iter().all(|&(_, v)| v == "yes" || v == "no"), "{err}");
    }
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        table.lines().filter(|l| l.starts_with("| ball ")).count(),
        1,
        "{table}"
    );
    // Every row has a cell for each column, the shading of the eye rays' hits among them.
    let cells = |l: &str| l.matches('|').count();
    let header = table.lines().next().unwrap_or_default();
    assert!(
        header.contains("| shading ms | shadow Mrays/s |"),
        "{table}"
    );
    assert!(table.lines().all(|l| cells(l) == cells(header)), "{table}");
}

/// `gpurt tune`: every candidate is timed on every scene and compared with the defaults'
/// image, the one chosen is kept in the cache directory, and renders on the adapter take
/// what is kept there (`--stats` says so): with the same image, unless the environment
/// overrides it; a kept file for another version of gpurt is passed over, and a broken
/// one refused at its line and column with nothing written.
#[test]
fn tune_keeps_a_strategy_that_renders_take() {
    if gpu_context().is_none() {
        return;
    }
    let d = workdir("tune");
    std::fs::write(d.join("ball.nff"), SCENE).unwrap();
    let mirrors = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/mirrors.nff");
    let run = |args: &[&str], env: &[(&str, &str)]| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_gpurt"));
        c.args(args)
            .current_dir(&d)
            .env("GPURT_CACHE_DIR", d.join("cache"));
        for (k, v) in env {
            c.env(k, v);
        }
        c.output().expect("gpurt runs")
    };
    let tune = [
        "tune", "ball.nff", mirrors, "--size", "24x16", "--frames", "1",
    ];
    let o = run(&tune, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    for scene in ["ball.nff", "mirrors.nff"] {
        let rows = table
            .lines()
            .filter(|l| l.starts_with(&format!("| {scene} |")));
        assert_eq!(rows.count(), 8, "{table}");
    }
    // Every candidate renders what the defaults render, so none is ruled out.
    assert!(!table.contains("differ"), "{table}");
    let chosen = table
        .lines()
        .find_map(|l| l.strip_prefix("chosen: "))
        .unwrap_or_else(|| panic!("{table}"));
    let [kernels, walk, fetch] = [0, 1, 2].map(|i| {
        let word = chosen.split([',', ' ']).filter(|w| !w.is_empty()).nth(i);
        word.unwrap().to_string()
    });
    let kept: Vec<_> = std::fs::read_dir(d.join("cache"))
        .unwrap()
        .flatten()
        .collect();
    assert_eq!(kept.len(), 1, "one file for the one adapter");
    let file = kept[0].path();
    let text = std::fs::read_to_string(&file).unwrap();
    for line in [
        format!("kernels = {kernels}"),
        format!("walk = {walk}"),
        format!("fetch = {fetch}"),
    ] {
        assert!(text.contains(&line), "{line} in\n{text}");
    }

    // A render takes what is kept: here a strategy off the defaults, for the same image.
    let kept = text
        .lines()
        .map(|l| match l.split_once(" = ").map(|(k, _)| k) {
            Some("kernels") => "kernels = pooled",
            Some("walk") => "walk = qwide",
            Some("fetch") => "fetch = buffers",
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&file, &kept).unwrap();
    let render = |out: &str, env: &[(&str, &str)]| {
        let o = run(
            &[
                mirrors,
                "-o",
                out,
                "--backend",
                "gpu",
                "--stats",
                "--width",
                "48",
                "--height",
                "32",
            ],
            env,
        );
        (o.status.code(), stderr(&o))
    };
    let strategy = |err: &str| {
        let line = err.lines().find(|l| l.starts_with("strategy "));
        line.unwrap_or_else(|| panic!("{err}")).to_string()
    };
    let (code, err) = render("tuned.png", &[]);
    assert_eq!(code, Some(0), "{err}");
    let s = strategy(&err);
    assert!(
        s.contains(
            "walk qwide, kernels pooled, scene data from buffers (tuned on 2 scenes at 24x16"
        ),
        "{s}"
    );
    let (code, err) = render("defaults.png", &[("GPURT_CACHE_DIR", "")]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        strategy(&err).contains("(the defaults; `gpurt tune` measures this adapter)"),
        "{err}"
    );
    let o = gpurt(&["diff", "tuned.png", "defaults.png"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    // The environment still overrides it.
    let (_, err) = render(
        "env.png",
        &[("GPURT_KERNELS", "main"), ("GPURT_TRAVERSAL", "wide")],
    );
    assert!(
        strategy(&err).contains("walk wide, kernels main, scene data from buffers (tuned"),
        "{err}"
    );

    // Another version's file is passed over.
    let older = kept.replace("gpurt = ", "gpurt = 0.0.0-");
    std::fs::write(&file, &older).unwrap();
    let (code, err) = render("older.png", &[]);
    assert_eq!(code, Some(0), "{err}");
    assert!(strategy(&err).contains("(the defaults;"), "{err}");

    // A broken one stops the render, naming its line and column, before any image.
    let broken = kept.replace("walk = qwide", "walk = quad");
    std::fs::write(&file, &broken).unwrap();
    let line = broken.lines().position(|l| l.starts_with("walk")).unwrap() + 1;
    let (code, err) = render("broken.png", &[]);
    assert_eq!(code, Some(2), "{err}");
    let at = format!("{}:{line}:8: expected one of", file.display());
    assert!(err.contains(&at), "{at} in {err}");
    assert!(!d.join("broken.png").exists());
    // So is one longer than any tuning file, read no further than that.
    std::fs::write(&file, format!("{kept}\n{}", "#".repeat(70 << 10))).unwrap();
    let (code, err) = render("long.png", &[]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("longer than a tuning file can be"), "{err}");
    assert!(!d.join("long.png").exists());

    // A scene that cannot be read is an error alone: no table, nothing kept.
    std::fs::write(d.join("bad.nff"), "v\nfrom 0 0 1\nbogus\n").unwrap();
    std::fs::remove_file(&file).unwrap();
    let o = run(&["tune", "bad.nff", "--size", "8x8", "--frames", "1"], &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("bad.nff:3:1: "), "{}", stderr(&o));
    assert!(o.stdout.is_empty() && !file.exists());
}
