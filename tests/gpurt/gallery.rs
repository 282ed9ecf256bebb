//! The README's gallery matches what its commands render today: every image of
//! `docs/gallery/list.txt` is rendered on the CPU and compared with the PNG in
//! `docs/gallery/` under the GPU-vs-CPU thresholds. `docs/gallery/regenerate.sh` writes
//! the images; this test never does, and a missing image fails it. The comparison checks
//! itself on every image: the stored image moved by two pixels (or, every other image,
//! brightened by two levels) must fail it.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use gpurt::compare::{self, Thresholds};
use gpurt::film;
use gpurt::frame::{self, RenderOptions};
use gpurt::pack;
use gpurt::scene;
use image::RgbImage;

use crate::common::shared_scenes;

/// The gallery's comparison: the GPU-vs-CPU thresholds, no noise floor.
fn verdict(stored: &RgbImage, rendered: &RgbImage) -> Result<(), String> {
    let stats = compare::diff(stored, rendered, Thresholds::GPU_VS_CPU.tolerance_255)
        .map_err(|e| e.to_string())?;
    Thresholds::GPU_VS_CPU
        .check(&stats)
        .map_err(|why| format!("{why} ({stats})"))
}

/// Wrong versions of `image` the comparison must reject: moved two pixels to the right
/// (the left columns repeated), and every channel two levels brighter.
fn perturbed(image: &RgbImage) -> [(&'static str, RgbImage); 2] {
    let moved = RgbImage::from_fn(image.width(), image.height(), |x, y| {
        *image.get_pixel(x.saturating_sub(2), y)
    });
    let mut brighter = image.clone();
    for p in brighter.pixels_mut() {
        p.0 = p.0.map(|c| c.saturating_add(2));
    }
    [
        ("moved by two pixels", moved),
        ("two levels brighter", brighter),
    ]
}

#[test]
fn gallery_matches_its_commands() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let list = std::fs::read_to_string(root.join("docs/gallery/list.txt")).expect("list");
    let needs_shared = list.contains("../shared/");
    if needs_shared && shared_scenes().is_none() {
        return;
    }
    let mut failures = Vec::new();
    let mut checked = 0;
    for line in list
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let words: Vec<&str> = line.split_whitespace().collect();
        let (name, scene_path) = (words[0], root.join(words[1]));
        let scene = scene::load(&scene_path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut opts = RenderOptions::for_camera(&scene.camera);
        for pair in words[2..].chunks(2) {
            let value: u32 = pair[1].parse().expect("a number");
            match pair[0] {
                "--width" => opts.width = value,
                "--height" => opts.height = value,
                "--spp" => opts.spp = value,
                other => panic!("{name}: list.txt option {other} is not understood here"),
            }
        }
        let buffers = pack::pack(scene.clone()).expect("packs");
        let globals = frame::globals(&buffers, &opts);
        let never = AtomicBool::new(false);
        let (film, _) = gpurt::cpu::render(&buffers, &globals, &|_| {}, &never).expect("renders");
        let rendered = film.for_display(opts.aov).to_rgb8();
        let png = root.join(format!("docs/gallery/{name}.png"));
        let stored = match film::load_rgb8(Path::new(&png)) {
            Ok(img) => img,
            Err(e) => {
                failures.push(format!("{name}: {e} (run docs/gallery/regenerate.sh)"));
                continue;
            }
        };
        if let Err(why) = verdict(&stored, &rendered) {
            failures.push(format!("{name}: {why}; run docs/gallery/regenerate.sh"));
        }
        // One perturbation an image, the two in turn, to keep the check cheap.
        let (what, wrong) = &perturbed(&stored)[checked % 2];
        if verdict(wrong, &rendered).is_ok() {
            failures.push(format!("{name}: the stored image {what} still passes"));
        }
        checked += 1;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked >= 9, "the gallery lists {checked} images");
}
