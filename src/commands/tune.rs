//! `gpurt tune`: which walk of the BVH, kernels and way of reading the scene trace the
//! given scenes fastest on this adapter, kept for every later render on it
//! (`gpu::tuning`). The defaults (`gpu::defaults`) were measured on lavapipe and on the
//! H100 and H200; another adapter, or another workload, may be faster another way, and
//! this measures it on the user's own hardware and scenes.
//!
//! Every candidate traces every scene once to be compared with the defaults' image
//! (under the GPU-vs-CPU limits, which the candidates meet against the CPU in the
//! suite), and is then timed in rounds that take every candidate in turn
//! (`time_in_rounds`). A candidate whose image differs on any scene is never chosen.
//! The fastest over all the scenes (the geometric mean of its frame times over the
//! defaults') is kept where it is at least `MARGIN` faster than the defaults; otherwise
//! the defaults are kept, so that timing noise does not move a render off what was
//! measured with care.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use web_time::Instant;

use crate::commands::bench::warm_up;
use crate::commands::run;
use crate::compare::{self, Thresholds};
use crate::frame::{self, Overrides, RenderOptions};
use crate::gpu::shaders::Fetch;
use crate::gpu::{self, GpuRenderer, Kernels, Strategy};
use crate::gpu_types::{GpuGlobals, TRAVERSAL_NAMES, TRAVERSAL_QWIDE, TRAVERSAL_WIDE};
use crate::pack::SceneBuffers;
use crate::scene::ReadOptions;
use crate::util::error::{Error, Result};
use crate::{out, outln};

/// How much faster (as a fraction of the defaults' time) the fastest candidate must be to
/// be kept instead of the defaults, so that one no faster but for timing noise is not.
pub const MARGIN: f64 = 0.03;

/// What to measure.
pub struct TuneConfig {
    pub scenes: Vec<PathBuf>,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub depth: u32,
    /// Timed rounds per scene, each a frame of every candidate (`time_in_rounds`); a
    /// candidate's ratio on the scene is the median over the rounds.
    pub frames: u32,
    pub adapter: Option<String>,
    pub read: ReadOptions,
}

/// The strategies tried: the defaults first, then every other way of the two kernels
/// (`main`, `pooled`), the two four-wide walks (`wide`, `qwide`) and the two fetches.
/// Left out, as slower on every adapter measured by large factors: the wavefront kernels
/// (1.3 to 1.7 times the one kernel's time on lavapipe, 2.8 to 41 times on an H200) and
/// the single, pairs and compressed eight-wide walks (docs/gpu.md); `GPURT_KERNELS` and
/// `GPURT_TRAVERSAL` still reach them.
pub fn candidates(defaults: Strategy) -> Vec<Strategy> {
    let mut all = vec![defaults];
    for kernels in [Kernels::Main, Kernels::Pooled] {
        for traversal in [TRAVERSAL_WIDE, TRAVERSAL_QWIDE] {
            for fetch in [Fetch::Textures, Fetch::Buffers] {
                let s = Strategy {
                    traversal,
                    kernels,
                    fetch,
                };
                if !all.contains(&s) {
                    all.push(s);
                }
            }
        }
    }
    all
}

/// One candidate's figures over the scenes.
#[derive(Clone, Debug, Default)]
pub struct Measured {
    /// Its frame time over the defaults' on each scene so far.
    pub ratios: Vec<f64>,
    /// Whether its image agreed with the defaults' on every scene.
    pub agrees: bool,
}

impl Measured {
    /// The geometric mean of its time over the defaults'.
    pub fn score(&self) -> f64 {
        let logs: f64 = self.ratios.iter().map(|r| r.ln()).sum();
        (logs / self.ratios.len().max(1) as f64).exp()
    }
}

/// The candidate to keep: the fastest of those whose images agreed, where it is at least
/// `MARGIN` faster than the defaults (`measured[0]`), else the defaults.
pub fn choose(measured: &[Measured]) -> usize {
    let best = (1..measured.len())
        .filter(|&i| measured[i].agrees)
        .min_by(|&a, &b| measured[a].score().total_cmp(&measured[b].score()));
    match best {
        Some(i) if measured[i].score() <= 1.0 - MARGIN => i,
        _ => 0,
    }
}

/// `strategy`'s kernels, walk and fetch, `between` each: a table's cells or a list.
fn named(s: &Strategy, between: &str) -> String {
    let walk = TRAVERSAL_NAMES[s.traversal as usize];
    [s.kernels.name(), walk, s.fetch.name()].join(between)
}

/// Whether each of `renderers` traces the image of `buffers` the first (the defaults)
/// traces, under the GPU-vs-CPU limits: `Err` says how it differs. Compiles each
/// renderer's pipeline for the frame on the way.
fn against_defaults(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    renderers: &[GpuRenderer],
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
) -> Result<Vec<std::result::Result<(), String>>> {
    let never = AtomicBool::new(false);
    let mut reference = None;
    let mut agrees = Vec::with_capacity(renderers.len());
    for renderer in renderers {
        renderer.prepare(device, queue, buffers, globals)?;
        let scene = renderer.upload(device, queue, buffers, globals)?;
        let (film, _) = gpu::trace(device, queue, &scene, &|_| {}, &never)?;
        let image = film.for_display(globals.aov).to_rgb8();
        agrees.push(match &reference {
            None => Ok(()),
            Some(r) => {
                let stats = compare::diff(r, &image, Thresholds::GPU_VS_CPU.tolerance_255)?;
                Thresholds::GPU_VS_CPU.check(&stats)
            }
        });
        reference.get_or_insert(image);
    }
    Ok(agrees)
}

/// A frame of `buffers` timed on each of `renderers`, on the device alone, in `rounds`
/// rounds that each time one frame of every renderer in turn (the order turned by one
/// each round), so that what drifts over the run (the clocks, other work on the
/// machine) falls on every candidate alike: `times[i][round]`, in seconds. Each renderer
/// uploads the scene afresh each round, so that no more than one upload is held at once,
/// and traces one frame untimed before its timed one; the GPU is warmed up first, as
/// `gpurt bench` does (`bench::warm_up`).
fn time_in_rounds(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    renderers: &[GpuRenderer],
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    rounds: u32,
) -> Result<Vec<Vec<f64>>> {
    let n = renderers.len();
    let mut times = vec![Vec::new(); n];
    warm_up(
        device,
        queue,
        &renderers[0].upload(device, queue, buffers, globals)?,
    )?;
    for round in 0..rounds.max(1) as usize {
        for k in 0..n {
            let i = (k + round) % n;
            let scene = renderers[i].upload(device, queue, buffers, globals)?;
            gpu::trace_on_device(device, queue, &scene)?;
            let t = Instant::now();
            gpu::trace_on_device(device, queue, &scene)?;
            times[i].push(t.elapsed().as_secs_f64());
        }
    }
    Ok(times)
}

/// The median of `values` (not empty).
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// A candidate's time over the defaults' on one scene, from the rounds' times of each
/// (`time_in_rounds`): the median over the rounds of the ratio within each round, a
/// paired measure, so that a round slowed as a whole counts once rather than skewing
/// either side.
pub fn ratio(candidate: &[f64], defaults: &[f64]) -> f64 {
    median(candidate.iter().zip(defaults).map(|(c, d)| c / d).collect())
}

/// Measures every candidate on every scene, prints a row each and the verdict, and keeps
/// the one chosen for the adapter (where there is a cache directory).
pub fn run(config: &TuneConfig) -> Result<()> {
    if config.scenes.is_empty() {
        return Err(Error::Render("gpurt tune: no scene to measure".into()));
    }
    let ctx = gpu::open(config.adapter.as_deref())?;
    eprintln!("adapter     {}", ctx.describe());
    eprintln!("features    {}", ctx.capabilities());
    let defaults = gpu::defaults(gpu::is_software(&ctx.info));
    let candidates = candidates(defaults);
    // One renderer a candidate for every scene, so that each compiles its pipelines once.
    // Made without the adapter's info, so that neither a tuning kept before nor the
    // environment's choices (which `with_*` override) stand in for a candidate.
    let renderers = candidates
        .iter()
        .map(|s| {
            Ok(GpuRenderer::fetching(&ctx.device, None, s.fetch)?
                .with_traversal(s.traversal)
                .with_wavefront(s.kernels == Kernels::Wavefront)
                .with_pooled(s.kernels == Kernels::Pooled))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut measured = vec![
        Measured {
            agrees: true,
            ..Measured::default()
        };
        candidates.len()
    ];
    let overrides = Overrides {
        width: Some(config.width),
        height: Some(config.height),
        spp: Some(config.spp),
        max_depth: Some(config.depth),
        ..Overrides::default()
    };
    // The table's header waits for the first scene, so that a scene that cannot be read
    // first is an error alone.
    let mut header = true;
    for path in &config.scenes {
        let opts =
            |c: &crate::scene::Camera| RenderOptions::for_camera(c).with_overrides(&overrides);
        let read = run::read(path, None, &config.read)?.still(None)?;
        let samples = opts(read.camera()).samples();
        let prepared = run::pack(read, samples)?;
        let buffers = &prepared.buffers;
        let globals = frame::globals(buffers, &opts(&buffers.camera));
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let (device, queue) = (&ctx.device, &ctx.queue);
        let start = Instant::now();
        let agrees = against_defaults(device, queue, &renderers, buffers, &globals)?;
        let times = time_in_rounds(device, queue, &renderers, buffers, &globals, config.frames)?;
        eprintln!(
            "  {name}: BVH at {} quality, {} strategies compared and timed in {:.1} s",
            buffers.bvh_quality.name(),
            renderers.len(),
            start.elapsed().as_secs_f64()
        );
        if std::mem::take(&mut header) {
            outln!(
                "| scene | kernels | walk | fetch | GPU frame ms | of the defaults' time | image |"
            );
            outln!("|---|---|---|---|---:|---:|---|");
        }
        for (i, renderer) in renderers.iter().enumerate() {
            let ratio = ratio(&times[i], &times[0]);
            measured[i].ratios.push(ratio);
            measured[i].agrees &= agrees[i].is_ok();
            let walk = TRAVERSAL_NAMES[renderer.frame(buffers, &globals).traversal as usize];
            let kernels = renderer.kernels(buffers, &globals);
            let image = match &agrees[i] {
                Ok(()) => "as the defaults'".to_string(),
                Err(why) => format!("differs: {why}"),
            };
            outln!(
                "| {name} | {kernels} | {walk} | {} | {:.3} | {ratio:.3} | {image} |",
                candidates[i].fetch.name(),
                median(times[i].clone()) * 1e3
            );
        }
    }
    outln!("");
    outln!("| kernels | walk | fetch | of the defaults' time, geometric mean | images |");
    outln!("|---|---|---|---:|---|");
    for (s, m) in candidates.iter().zip(&measured) {
        let images = match m.agrees {
            true => "as the defaults'",
            false => "one differed: never chosen",
        };
        outln!("| {} | {:.3} | {images} |", named(s, " | "), m.score());
    }
    outln!("");
    let chosen = choose(&measured);
    let scenes = config.scenes.len();
    let setting = format!(
        "{scenes} scene{} at {}x{}, {} spp, depth {}",
        if scenes == 1 { "" } else { "s" },
        config.width,
        config.height,
        config.spp,
        config.depth
    );
    let verdict = match chosen {
        0 => format!(
            "{setting}: the defaults, nothing was {:.0}% faster",
            MARGIN * 100.0
        ),
        i => format!(
            "{setting}: {:.3} of the defaults' time",
            measured[i].score()
        ),
    };
    let strategy = candidates[chosen];
    out!("chosen: {} ({verdict})\n", named(&strategy, ", "));
    match gpu::tuning::save(&ctx.info, strategy, &verdict)? {
        Some(file) => eprintln!(
            "kept in {}: renders on this adapter take it",
            file.display()
        ),
        None => eprintln!("not kept: GPURT_CACHE_DIR is empty, so there is no cache directory"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(ratios: &[f64], agrees: bool) -> Measured {
        Measured {
            ratios: ratios.to_vec(),
            agrees,
        }
    }

    /// The fastest agreeing candidate is kept, by the geometric mean of its ratios, and
    /// only where it beats the defaults by the margin; one that differed never is.
    #[test]
    fn the_fastest_agreeing_candidate_is_kept_past_the_margin() {
        let defaults = m(&[1.0, 1.0], true);
        // 0.5 and 2.0: a geometric mean of 1, not faster; 0.9 and 0.9 is.
        let all = [defaults.clone(), m(&[0.5, 2.0], true), m(&[0.9, 0.9], true)];
        assert_eq!(choose(&all), 2);
        assert!((all[1].score() - 1.0).abs() < 1e-12);
        // The fastest differed: the next fastest.
        let all = [
            defaults.clone(),
            m(&[0.5, 0.5], false),
            m(&[0.9, 0.9], true),
        ];
        assert_eq!(choose(&all), 2);
        // Within the margin: the defaults stay.
        let near = 1.0 - MARGIN / 2.0;
        let all = [defaults.clone(), m(&[near, near], true)];
        assert_eq!(choose(&all), 0);
        assert_eq!(choose(std::slice::from_ref(&defaults)), 0);
    }

    /// A scene's ratio pairs each round's times: a round slow as a whole (here the
    /// second, twice as slow for both) leaves it as the other rounds say, where the
    /// medians' ratio would follow the rounds' order.
    #[test]
    fn a_scenes_ratio_pairs_the_rounds() {
        let defaults = [1.0, 2.0, 1.0];
        let candidate = [0.9, 1.8, 0.9];
        assert!((ratio(&candidate, &defaults) - 0.9).abs() < 1e-12);
        // Drift from round to round: the medians (1.5 and 1.25) would say 0.83.
        let defaults = [1.0, 1.5, 2.0];
        let candidate = [1.0, 1.25, 2.0];
        assert!((ratio(&candidate, &defaults) - 1.0).abs() < 1e-12);
    }

    /// The defaults come first, every candidate once, and on any adapter's defaults the
    /// same eight.
    #[test]
    fn the_candidates_start_with_the_defaults() {
        for software in [false, true] {
            let d = gpu::defaults(software);
            let c = candidates(d);
            assert_eq!(c[0], d);
            assert_eq!(c.len(), 8);
            for (i, s) in c.iter().enumerate() {
                assert!(!c[..i].contains(s), "{s:?} twice");
            }
        }
    }
}
