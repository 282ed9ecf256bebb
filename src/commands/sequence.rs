//! An animated scene rendered frame by frame (`gpurt SCENE.aff --frames A..B -o
//! out/frame-%04d.png`): the scene parsed once, each frame's moving parts placed and
//! their tree refitted or built anew (`pack::frames`), every frame on one renderer (one
//! device, its pipelines compiled once), each image written atomically as soon as it is
//! traced. Which frames, and the file each goes to, are settled before anything renders,
//! so that a bad range or a pattern that would write one file twice fails at once.

use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::commands::run::{self, Read};
use crate::frame::{self, Overrides, RenderOptions};
use crate::gpu::GpuContext;
use crate::pack::frames::FrameTree;
use crate::scene::Camera;
use crate::scene::animation::TimeRange;
use crate::session::GpuSession;
use crate::util::error::{Error, Result};

/// The frames asked for: all of the animation's, or an inclusive range of them (counted
/// from 0, as BART counts them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frames {
    All,
    Range(u32, u32),
}

impl Frames {
    /// `all`, `N`, or `A..B` (both ends included).
    pub fn parse(s: &str) -> std::result::Result<Frames, String> {
        let number = |t: &str| {
            t.trim()
                .parse::<u32>()
                .map_err(|_| format!("'{t}' is not a frame number (0, 1, 2, ...)"))
        };
        if s == "all" {
            return Ok(Frames::All);
        }
        match s.split_once("..") {
            Some((a, b)) => {
                let (a, b) = (number(a)?, number(b.strip_prefix('=').unwrap_or(b))?);
                if b < a {
                    return Err(format!("the range {s} ends before it starts"));
                }
                Ok(Frames::Range(a, b))
            }
            None => number(s).map(|n| Frames::Range(n, n)),
        }
    }

    /// The frame numbers, checked against the animation's `range`.
    pub fn resolve(self, range: &TimeRange) -> std::result::Result<RangeInclusive<u32>, String> {
        let last = range.frames - 1;
        match self {
            Frames::All => Ok(0..=last),
            Frames::Range(a, b) if b <= last => Ok(a..=b),
            Frames::Range(a, b) => Err(format!(
                "frames {a}..{b} are outside the animation, whose {} frames are 0..{last} ('a {} {} {}')",
                range.frames, range.start, range.end, range.frames
            )),
        }
    }
}

/// An output path with one printf-style frame number in its name (`%d`, or `%04d` for
/// four digits with leading zeros); `%%` is a `%`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    before: String,
    width: usize,
    after: String,
}

impl Pattern {
    /// The pattern in `path`, `None` when it has no frame number (it names one file).
    pub fn parse(path: &Path) -> std::result::Result<Option<Pattern>, String> {
        let s = path.to_string_lossy();
        let mut found: Option<Pattern> = None;
        let mut literal = String::new();
        let mut chars = s.chars().peekable();
        while let Some(c) = chars.next() {
            if c != '%' {
                literal.push(c);
                continue;
            }
            if chars.peek() == Some(&'%') {
                chars.next();
                literal.push('%');
                continue;
            }
            let mut digits = String::new();
            while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
                digits.push(*d);
                chars.next();
            }
            if chars.next() != Some('d') {
                return Err(format!(
                    "'{s}': a '%' starts a frame number (%d or %04d), or is written %%"
                ));
            }
            if found.is_some() {
                return Err(format!("'{s}' has two frame numbers; give one"));
            }
            let width = if digits.is_empty() {
                0
            } else if digits.starts_with('0') {
                digits.parse::<usize>().map_err(|e| e.to_string())?.min(10)
            } else {
                return Err(format!(
                    "'{s}': a frame number's width pads with zeros: %0{digits}d"
                ));
            };
            found = Some(Pattern {
                before: std::mem::take(&mut literal),
                width,
                after: String::new(),
            });
        }
        Ok(found.map(|p| Pattern {
            after: literal,
            ..p
        }))
    }

    /// The path of frame `frame`.
    pub fn path(&self, frame: u32) -> PathBuf {
        let w = self.width;
        PathBuf::from(format!("{}{frame:0w$}{}", self.before, self.after))
    }
}

/// Each frame asked for and the file it goes to; an error where the frames are more
/// than one and `output` has no frame number (every frame would write one file).
pub fn outputs(frames: RangeInclusive<u32>, output: &Path) -> Result<Vec<(u32, PathBuf)>> {
    let pattern = Pattern::parse(output).map_err(Error::Render)?;
    let count = frames.end() - frames.start() + 1;
    match pattern {
        Some(p) => Ok(frames.map(|f| (f, p.path(f))).collect()),
        None if count == 1 => Ok(vec![(*frames.start(), output.to_path_buf())]),
        None => Err(Error::Render(format!(
            "{count} frames would all be written to {}: put a frame number in its name (frame-%04d.png)",
            output.display()
        ))),
    }
}

/// One frame rendered, and what it cost.
#[derive(Clone, Debug)]
pub struct FrameReport {
    pub frame: u32,
    pub time: f64,
    /// Placing the moving parts and building and packing the tree.
    pub build: Duration,
    /// Tracing (on the GPU with the upload and the readback), and writing the image.
    pub trace: Duration,
    pub write: Duration,
    pub rays: u64,
    /// How the frame's tree was made.
    pub tree: FrameTree,
}

/// Renders `frames` (each with the file it goes to) of the animated scene `read`, on
/// `gpu`'s device or on the CPU, with `overrides` over the scene's camera and options;
/// `done` is called after each frame is written. An interruption (`cancel`) ends the
/// sequence with `Error::Interrupted`, the frames already written staying.
pub fn render(
    read: &Read,
    frames: &[(u32, PathBuf)],
    overrides: &Overrides,
    gpu: Option<GpuContext>,
    done: &dyn Fn(&FrameReport),
    cancel: &AtomicBool,
) -> Result<Vec<FrameReport>> {
    let range = read
        .animation()
        .and_then(|a| a.range)
        .ok_or_else(|| Error::Render("the scene has no animation time range ('a')".into()))?;
    let options = |camera: &Camera| RenderOptions::for_camera(camera).with_overrides(overrides);
    let samples = options(read.camera()).samples();
    let setup = Instant::now();
    let mut packer = read
        .frames(samples, frames.len() as u64)?
        .ok_or_else(|| Error::Render("nothing moves in the scene".into()))?;
    // The still part's tree, built once, is the first frame's to pay for.
    let mut setup = Some(setup.elapsed());
    // One session for the whole sequence: its pipelines outlive each frame's scene.
    let mut session: Option<GpuSession> = None;
    let mut reports = Vec::with_capacity(frames.len());
    for (frame, out) in frames {
        let time = range.time(*frame);
        let start = Instant::now();
        let (mut buffers, tree) = packer.pack(time)?;
        let options = options(&buffers.camera);
        if gpu.is_none() {
            buffers.for_cpu_alone(options.aov);
        }
        let buffers = Arc::new(buffers);
        let globals = frame::globals(&buffers, &options);
        let build = start.elapsed() + setup.take().unwrap_or_default();
        let mut cpu = None;
        let renderer = run::next_renderer(gpu.as_ref(), &mut session, &mut cpu, buffers)?;
        let rendered = run::render_frame(renderer, &globals, &|_| {}, cancel)?;
        let written = Instant::now();
        rendered.film.save_aov(out, options.aov)?;
        let report = FrameReport {
            frame: *frame,
            time,
            build,
            trace: rendered.trace,
            write: written.elapsed(),
            rays: rendered.rays,
            tree,
        };
        done(&report);
        reports.push(report);
    }
    Ok(reports)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_are_read_and_checked_against_the_animation() {
        assert_eq!(Frames::parse("all"), Ok(Frames::All));
        assert_eq!(Frames::parse("3"), Ok(Frames::Range(3, 3)));
        assert_eq!(Frames::parse("2..5"), Ok(Frames::Range(2, 5)));
        assert_eq!(Frames::parse("2..=5"), Ok(Frames::Range(2, 5)));
        assert!(Frames::parse("5..2").unwrap_err().contains("ends before"));
        assert!(Frames::parse("-1..2").is_err());
        let range = TimeRange {
            start: 0.0,
            end: 2.0,
            frames: 48,
        };
        assert_eq!(Frames::All.resolve(&range), Ok(0..=47));
        let e = Frames::Range(40, 48).resolve(&range).unwrap_err();
        assert!(
            e.contains("outside the animation") && e.contains("0..47"),
            "{e}"
        );
    }

    #[test]
    fn patterns_number_each_frame_and_refuse_one_file_for_many() {
        let p = Pattern::parse(Path::new("out/f-%04d.png"))
            .unwrap()
            .unwrap();
        assert_eq!(p.path(7), PathBuf::from("out/f-0007.png"));
        let p = Pattern::parse(Path::new("100%%-%d.png")).unwrap().unwrap();
        assert_eq!(p.path(12), PathBuf::from("100%-12.png"));
        assert_eq!(Pattern::parse(Path::new("still.png")), Ok(None));
        assert!(Pattern::parse(Path::new("%d-%d.png")).is_err());
        assert!(Pattern::parse(Path::new("%4d.png")).is_err());
        assert!(Pattern::parse(Path::new("%s.png")).is_err());
        let e = outputs(0..=3, Path::new("still.png"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("4 frames would all be written to still.png"),
            "{e}"
        );
        assert_eq!(outputs(5..=5, Path::new("still.png")).unwrap().len(), 1);
    }
}
