//! Renders a scene progressively through the library: `cargo run --release --example
//! render -- scenes/spheres.nff out.png`. Uses the GPU when there is an adapter, else the
//! CPU; traces 16 samples per pixel in four steps of 4, saving the image after each.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use gpurt::film::Accumulator;
use gpurt::frame::{self, RenderOptions};
use gpurt::pack;
use gpurt::session::{CpuRenderer, GpuSession, Renderer};

fn main() -> gpurt::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene_path = PathBuf::from(args.next().unwrap_or("scenes/spheres.nff".into()));
    let out = PathBuf::from(args.next().unwrap_or("out.png".into()));

    // Read and pack the scene; packing consumes the tree, and the camera, background
    // and ambient travel on in the packed buffers.
    let buffers = Arc::new(pack::pack(gpurt::scene::load(&scene_path)?)?);
    let opts = RenderOptions {
        spp: 16,
        ..RenderOptions::for_camera(&buffers.camera)
    };
    let frame = frame::globals(&buffers, &opts);

    let mut renderer: Box<dyn Renderer> = match gpurt::gpu::open(None) {
        Ok(ctx) => Box::new(GpuSession::new(ctx, buffers)?),
        Err(_) => Box::new(CpuRenderer::new(buffers)),
    };
    println!("rendering on {}", renderer.describe());

    let mut accum = Accumulator::new(frame.width, frame.height);
    let never = AtomicBool::new(false);
    for step in 0..4 {
        let samples = step * 4..step * 4 + 4;
        let rays = renderer.render(&frame, samples.clone(), &mut accum, &|_| {}, &never)?;
        accum.film().save(&out)?;
        println!("samples {samples:?}: {rays} rays, saved {}", out.display());
    }
    Ok(())
}
