//! Many scenes in one process (`gpurt SCENE... --out-dir DIR`): one device for all of
//! them, each kind of pipeline compiled once, each image named after its scene, and a
//! scene that fails reported and skipped while the others go on.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::commands::run;
use crate::film::Format;
use crate::frame::{self, Overrides, RenderOptions};
use crate::gpu::GpuContext;
use crate::scene::{Camera, ReadOptions};
use crate::session::GpuSession;
use crate::util::error::{Error, Result};

/// The name an image of `scene` gets: its file name without `.gz` and the scene's own
/// extension (`parts/gear.stl.gz` -> `gear`).
pub fn output_stem(scene: &Path) -> String {
    let name = scene
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into())
}

/// The image each scene is written to in `dir`; an error naming both scenes when two
/// would write the same file (`a/part.stl` and `b/part.obj`), before anything renders.
pub fn outputs(scenes: &[PathBuf], dir: &Path, format: Format) -> Result<Vec<PathBuf>> {
    let mut seen: HashMap<PathBuf, &Path> = HashMap::new();
    scenes
        .iter()
        .map(|scene| {
            let out = dir.join(format!("{}.{}", output_stem(scene), format.extension()));
            if let Some(first) = seen.insert(out.clone(), scene) {
                return Err(Error::Render(format!(
                    "{} and {} would both be written to {}; render them in separate batches",
                    first.display(),
                    scene.display(),
                    out.display()
                )));
            }
            Ok(out)
        })
        .collect()
}

/// How every scene of a batch is rendered: each scene's own camera and size unless
/// `overrides` sets them.
#[derive(Clone, Debug, Default)]
pub struct BatchOptions {
    pub overrides: Overrides,
    /// A `v` block that replaces every scene's camera.
    pub view: Option<PathBuf>,
    /// How every scene is read (`--lenient`).
    pub read: ReadOptions,
}

/// What a batch did.
#[derive(Debug, Default)]
pub struct Outcome {
    pub rendered: usize,
    pub rays: u64,
    /// The scenes that failed, with why, in input order.
    pub failed: Vec<(PathBuf, Error)>,
    /// The readers' warnings about the scenes rendered (each names its file and line).
    pub warnings: Vec<String>,
}

/// Renders `scenes` to `outputs` (see `outputs`), on `gpu`'s device or on the CPU.
/// `done` is called after each scene. A scene that cannot be read or rendered is
/// recorded in the outcome and skipped; an interruption (`cancel`) ends the batch with
/// `Error::Interrupted`, the images already written staying.
pub fn run(
    scenes: &[PathBuf],
    outputs: &[PathBuf],
    opts: &BatchOptions,
    gpu: Option<GpuContext>,
    done: &dyn Fn(&Path),
    cancel: &AtomicBool,
) -> Result<Outcome> {
    let mut outcome = Outcome::default();
    // One session for the whole batch: its pipelines outlive each scene.
    let mut session: Option<GpuSession> = None;
    for (scene, out) in scenes.iter().zip(outputs) {
        match render_one(scene, out, opts, gpu.as_ref(), &mut session, cancel) {
            Ok((rays, warnings)) => {
                outcome.rendered += 1;
                outcome.rays += rays;
                outcome.warnings.extend(warnings);
            }
            Err(Error::Interrupted) => return Err(Error::Interrupted),
            Err(e) => outcome.failed.push((scene.clone(), e)),
        }
        done(scene);
    }
    Ok(outcome)
}

fn render_one(
    scene: &Path,
    out: &Path,
    opts: &BatchOptions,
    gpu: Option<&GpuContext>,
    session: &mut Option<GpuSession>,
    cancel: &AtomicBool,
) -> Result<(u64, Vec<String>)> {
    let options =
        |camera: &Camera| RenderOptions::for_camera(camera).with_overrides(&opts.overrides);
    let read = run::read(scene, opts.view.as_deref(), &opts.read)?.still(None)?;
    let samples = options(read.camera()).samples();
    let prepared = run::pack(read, samples)?;
    let mut buffers = prepared.buffers;
    let options = options(&buffers.camera);
    if gpu.is_none() {
        buffers.for_cpu_alone(options.aov);
    }
    let buffers = Arc::new(buffers);
    let frame = frame::globals(&buffers, &options);
    let mut cpu = None;
    let renderer = run::next_renderer(gpu, session, &mut cpu, buffers)?;
    let rendered = run::render_frame(renderer, &frame, &|_| {}, cancel)?;
    rendered.film.save_aov(out, options.aov)?;
    Ok((rendered.rays, prepared.warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_are_named_after_their_scenes_and_collisions_are_refused() {
        let scenes = [
            PathBuf::from("a/gear.stl.gz"),
            PathBuf::from("b/teapot.nff"),
        ];
        let outs = outputs(&scenes, Path::new("out"), Format::Png).unwrap();
        assert_eq!(
            outs,
            [
                PathBuf::from("out/gear.png"),
                PathBuf::from("out/teapot.png")
            ]
        );
        let clash = [PathBuf::from("a/part.stl"), PathBuf::from("b/part.obj")];
        let e = outputs(&clash, Path::new("o"), Format::Exr)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("a/part.stl and b/part.obj would both be written to o/part.exr"),
            "{e}"
        );
    }
}
