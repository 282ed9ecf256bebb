//! Many scenes in one process (`gpurt SCENE... --out-dir DIR`): one device for all of
//! them, each kind of pipeline compiled once, each image named after its scene, and a
//! scene that fails reported and skipped while the others go on.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::film::Format;
use crate::frame::{self, RenderOptions};
use crate::gpu::GpuContext;
use crate::run;
use crate::scene::Camera;
use crate::session::{CpuRenderer, GpuSession, Renderer};

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

/// This process's share of a batch run as a job array: scenes `index`, `index + count`,
/// `index + 2 count`, ... of the list every task is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Parses `I/N`, or `/N` with `I` from `SLURM_ARRAY_TASK_ID` (a Slurm job array) or
    /// `JOB_COMPLETION_INDEX` (a Kubernetes Indexed Job).
    pub fn parse(s: &str) -> std::result::Result<Shard, String> {
        Self::parse_with(s, |k| std::env::var(k).ok())
    }

    fn parse_with(
        s: &str,
        env: impl Fn(&str) -> Option<String>,
    ) -> std::result::Result<Shard, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("'{s}': expected I/N (or /N inside a job array)"))?;
        let count: u32 = match n.trim().parse() {
            Ok(n) if n >= 1 => n,
            _ => return Err(format!("'{s}': N must be a whole number, 1 or more")),
        };
        let (index, from) = if i.trim().is_empty() {
            let var = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"]
                .into_iter()
                .find_map(|k| env(k).map(|v| (v, k)));
            let (v, k) = var.ok_or_else(|| {
                format!(
                    "'{s}' takes its index from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX, \
                     and neither is set"
                )
            })?;
            let from = format!("{k}={}", v.trim());
            (v, from)
        } else {
            (i.to_string(), format!("'{s}'"))
        };
        match index.trim().parse::<u32>() {
            Ok(index) if index < count => Ok(Shard { index, count }),
            _ => Err(format!(
                "{from}: the shard index must be 0 to {} (with N = {count}; a Slurm array \
                 for N shards is --array=0-{})",
                count - 1,
                count - 1
            )),
        }
    }

    /// This shard's items.
    pub fn take<'a, T>(&self, items: &'a [T]) -> Vec<&'a T> {
        items
            .iter()
            .skip(self.index as usize)
            .step_by(self.count as usize)
            .collect()
    }
}

/// How every scene of a batch is rendered; the size and camera default to each scene's.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: u32,
    pub max_depth: u32,
    pub ambient: Option<Vec3>,
    pub aov: u32,
    pub seed: u32,
    /// A `v` block that replaces every scene's camera.
    pub view: Option<PathBuf>,
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
    let options = |camera: &Camera| {
        let defaults = RenderOptions::for_camera(camera);
        RenderOptions {
            width: opts.width.unwrap_or(defaults.width),
            height: opts.height.unwrap_or(defaults.height),
            spp: opts.spp,
            max_depth: opts.max_depth,
            ambient: opts.ambient,
            aov: opts.aov,
            seed: opts.seed,
        }
    };
    let prepared = run::prepare(scene, opts.view.as_deref(), |c| options(c).samples())?;
    let buffers = Arc::new(prepared.buffers);
    let frame = frame::globals(&buffers, &options(&buffers.camera));
    let mut cpu;
    let renderer: &mut dyn Renderer = match (gpu, session.as_mut()) {
        (Some(_), Some(s)) => {
            s.set_scene(buffers);
            s
        }
        (Some(ctx), None) => session.insert(GpuSession::new(ctx.clone(), buffers)?),
        (None, _) => {
            cpu = CpuRenderer::new(buffers);
            &mut cpu
        }
    };
    let rendered = run::render_frame(renderer, &frame, &|_| {}, cancel)?;
    rendered.film.save_aov(out, opts.aov)?;
    Ok((rendered.rays, prepared.warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_a_batch_and_take_their_index_from_the_job_array() {
        let none = |_: &str| None;
        let s = Shard::parse_with("1/3", none).unwrap();
        assert_eq!(s.take(&[0, 1, 2, 3, 4, 5, 6]), [&1, &4]);
        // Every item lands in exactly one shard.
        let mut all: Vec<i32> = (0..3)
            .flat_map(|i| Shard { index: i, count: 3 }.take(&[0, 1, 2, 3, 4, 5, 6]))
            .copied()
            .collect();
        all.sort();
        assert_eq!(all, [0, 1, 2, 3, 4, 5, 6]);
        let slurm = |k: &str| (k == "SLURM_ARRAY_TASK_ID").then(|| "2".to_string());
        assert_eq!(
            Shard::parse_with("/4", slurm).unwrap(),
            Shard { index: 2, count: 4 }
        );
        let k8s = |k: &str| (k == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(
            Shard::parse_with("/2", k8s).unwrap(),
            Shard { index: 0, count: 2 }
        );
        for (bad, want) in [
            ("3/3", "the shard index must be 0 to 2"),
            ("x/3", "the shard index must be 0 to 2"),
            ("1/0", "N must be a whole number"),
            ("2", "expected I/N"),
            ("/3", "neither is set"),
        ] {
            let e = Shard::parse_with(bad, none).unwrap_err();
            assert!(e.contains(want), "{bad}: {e}");
        }
        let e = Shard::parse_with("/2", |_| Some("5".into())).unwrap_err();
        assert!(e.contains("SLURM_ARRAY_TASK_ID=5"), "{e}");
    }

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
