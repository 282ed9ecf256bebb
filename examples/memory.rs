//! Heap memory at each stage of getting a scene ready, per primitive: reading the file
//! straight into the renderers' records (as `run::read` does), packing it (BVH build,
//! the records put in leaf order) and rendering a small CPU frame.
//! Counts every allocation through a wrapping global allocator, so the figures are the
//! program's own heap, without the binary, thread stacks or allocator slack that the
//! process's peak resident memory (`--stats`) also holds.
//!
//!     cargo run --release --example memory -- SCENE
//!
//! With a size and an output image, it follows a whole command-line render on the CPU at
//! one sample per pixel instead, stage by stage, and gives the peaks in bytes a pixel:
//!
//!     cargo run --release --example memory -- SCENE 16384x16384 out.png

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};
use std::time::Instant;

struct Counting;

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(bytes: usize) {
    let now = CURRENT.fetch_add(bytes, Relaxed) + bytes;
    PEAK.fetch_max(now, Relaxed);
}

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        CURRENT.fetch_sub(layout.size(), Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            if new_size > layout.size() {
                grew(new_size - layout.size());
            } else {
                CURRENT.fetch_sub(layout.size() - new_size, Relaxed);
            }
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn main() -> gpurt::Result<()> {
    let path = std::env::args()
        .nth(1)
        .expect("usage: memory SCENE (an .nff, .stl or .obj file, optionally .gz)");
    let path = Path::new(&path);
    let mib = |b: usize| b as f64 / (1 << 20) as f64;
    let mut stages = Vec::new();
    let mut stage = |name: &str, start: Instant| {
        stages.push((
            name.to_string(),
            start.elapsed(),
            PEAK.swap(CURRENT.load(Relaxed), Relaxed),
            CURRENT.load(Relaxed),
        ));
    };

    if let (Some(size), Some(out)) = (std::env::args().nth(2), std::env::args().nth(3)) {
        return image_stages(path, &size, Path::new(&out));
    }
    let t = Instant::now();
    let scene = gpurt::scene::load_flat(path)?;
    stage("read + parse into records", t);
    let prims = scene.counts().iter().sum::<usize>().max(1);
    let c = &scene.scene.camera;
    let samples = u64::from(c.width) * u64::from(c.height);
    let t = Instant::now();
    let buffers = gpurt::pack::pack_flat(scene, samples)?;
    stage("pack (BVH build, leaf order)", t);
    let opts = gpurt::frame::RenderOptions {
        width: 64,
        height: 64,
        spp: 1,
        ..gpurt::frame::RenderOptions::for_camera(&buffers.camera)
    };
    let globals = gpurt::frame::globals(&buffers, &opts);
    let t = Instant::now();
    gpurt::cpu::render(&buffers, &globals, &|_| {}, &AtomicBool::new(false))?;
    stage("render 64x64 on the CPU", t);

    println!("{}: {prims} bounded primitives", path.display());
    println!("| stage | time s | peak MiB | peak B/prim | after MiB | after B/prim |");
    println!("|---|---:|---:|---:|---:|---:|");
    for (name, time, peak, after) in &stages {
        println!(
            "| {name} | {:.3} | {:.1} | {:.0} | {:.1} | {:.0} |",
            time.as_secs_f64(),
            mib(*peak),
            *peak as f64 / prims as f64,
            mib(*after),
            *after as f64 / prims as f64
        );
    }
    Ok(())
}

/// A render of `path` at `size` (WxH), one sample per pixel on the CPU, saved to `out`, as
/// `gpurt SCENE --backend cpu` does it: the heap's peak in each stage, in bytes a pixel.
fn image_stages(path: &Path, size: &str, out: &Path) -> gpurt::Result<()> {
    use gpurt::session::CpuRenderer;
    let (w, h) = size.split_once('x').expect("a size WxH");
    let (w, h): (u32, u32) = (w.parse().expect("width"), h.parse().expect("height"));
    let pixels = f64::from(w) * f64::from(h);
    let mut rows = Vec::new();
    let mut stage = |name: &str, t: Instant| {
        let peak = PEAK.swap(CURRENT.load(Relaxed), Relaxed);
        rows.push((name.to_string(), t.elapsed(), peak, CURRENT.load(Relaxed)));
    };
    let t = Instant::now();
    let read = gpurt::run::read(path, None, &Default::default())?;
    let prepared = gpurt::run::pack(read, u64::from(w) * u64::from(h))?;
    stage("read, parse, pack", t);
    let opts = gpurt::frame::RenderOptions {
        width: w,
        height: h,
        spp: 1,
        ..gpurt::frame::RenderOptions::for_camera(&prepared.buffers.camera)
    };
    let globals = gpurt::frame::globals(&prepared.buffers, &opts);
    let mut renderer = CpuRenderer::new(std::sync::Arc::new(prepared.buffers));
    let t = Instant::now();
    let never = AtomicBool::new(false);
    let rendered = gpurt::run::render_frame(&mut renderer, &globals, &|_| {}, &never)?;
    stage("render (accumulator, tiles, film)", t);
    let t = Instant::now();
    rendered.film.save_aov(out, opts.aov)?;
    stage("save (8-bit conversion, encoder)", t);
    drop(rendered);
    println!(
        "{}: {w}x{h}, 1 spp, CPU, into {}",
        path.display(),
        out.display()
    );
    println!("| stage | time s | peak MiB | peak B/px | after MiB | after B/px |");
    println!("|---|---:|---:|---:|---:|---:|");
    for (name, time, peak, after) in &rows {
        let mib = |b: usize| b as f64 / (1 << 20) as f64;
        println!(
            "| {name} | {:.2} | {:.1} | {:.2} | {:.1} | {:.2} |",
            time.as_secs_f64(),
            mib(*peak),
            *peak as f64 / pixels,
            mib(*after),
            *after as f64 / pixels
        );
    }
    Ok(())
}
