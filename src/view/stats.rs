//! What `gpurt view --stats` measures while the window runs and prints on exit: the time
//! to the first frame and the first traced image, frame times, and how fast the last view
//! converged. Kept apart from the window so that it knows nothing of winit or wgpu.

use std::time::{Duration, Instant};

use super::controls::Mode;
use super::progressive::Pass;

/// What `--stats` prints on exit: how soon the first pictures came, how long frames take
/// to draw, and how fast the last view converged.
pub struct Stats {
    launch: Instant,
    adapter: String,
    tracing_on: String,
    first_frame: Option<Duration>,
    first_image: Option<(Duration, u32)>,
    draw_times: Vec<Duration>,
    first_present: Option<Instant>,
    last_present: Option<Instant>,
    /// The newest pass shown and how long its view had been traced by then.
    last_pass: Option<(u32, u64, Duration, Duration)>,
}

impl Stats {
    pub fn new(launch: Instant) -> Self {
        Stats {
            launch,
            adapter: String::new(),
            tracing_on: String::new(),
            first_frame: None,
            first_image: None,
            draw_times: Vec::new(),
            first_present: None,
            last_present: None,
            last_pass: None,
        }
    }

    /// A frame shown, which took `took` to draw, with the traced image when `traced`.
    pub fn frame(&mut self, took: Duration, traced: bool, latest: Option<&Pass>) {
        let now = Instant::now();
        self.first_frame.get_or_insert(now - self.launch);
        if traced && let Some(p) = latest {
            self.first_image
                .get_or_insert((now - self.launch, p.samples));
        }
        self.first_present.get_or_insert(now);
        self.last_present = Some(now);
        self.draw_times.push(took);
    }

    /// A pass of the view shown came, the view having started at `view_start`.
    pub fn pass(&mut self, pass: &Pass, view_start: Instant) {
        self.last_pass = Some((
            pass.samples,
            pass.rays,
            pass.trace_time,
            view_start.elapsed(),
        ));
    }

    /// The adapter that draws the window and the one (or the CPU) that traces.
    pub fn devices(&mut self, adapter: String, tracing_on: String) {
        self.adapter = adapter;
        self.tracing_on = tracing_on;
    }

    /// Prints the statistics to stderr, for a window of `width` by `height` in `mode`.
    pub fn print(&self, (width, height): (u32, u32), mode: Mode) {
        eprintln!("viewer      {width}x{height}, {} mode", mode.name());
        eprintln!("display     {}", self.adapter);
        eprintln!("tracing     {}", self.tracing_on);
        if let Some(t) = self.first_frame {
            eprintln!("first frame {:.3} s after launch", t.as_secs_f64());
        }
        if let Some((t, spp)) = self.first_image {
            eprintln!(
                "first image {:.3} s after launch ({spp} spp)",
                t.as_secs_f64()
            );
        }
        let mut times = self.draw_times.clone();
        times.sort();
        if let (Some(first), Some(last)) = (self.first_present, self.last_present)
            && times.len() > 1
        {
            let span = (last - first).as_secs_f64().max(1e-9);
            eprintln!(
                "frames      {} shown, {:.1} per second; drawing one takes {:.2} ms (median)",
                times.len(),
                (times.len() - 1) as f64 / span,
                times[times.len() / 2].as_secs_f64() * 1e3
            );
        }
        if let Some((spp, rays, trace, wall)) = self.last_pass {
            eprintln!(
                "last view   {spp} spp in {:.3} s: {:.2} spp/s, {:.2} Mrays/s ({:.2} tracing alone)",
                wall.as_secs_f64(),
                f64::from(spp) / wall.as_secs_f64().max(1e-9),
                rays as f64 / wall.as_secs_f64().max(1e-9) / 1e6,
                rays as f64 / trace.as_secs_f64().max(1e-9) / 1e6
            );
        }
    }
}
