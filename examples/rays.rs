//! The CPU renderer's traversal timed on plain rays, and those rays written out for
//! `benches/embree/rays.c`, so that Embree traces exactly the same ones:
//!
//!     cargo run --release --example rays -- SCENE [SIZE] [OUT.rays]
//!
//! The rays are those of a SIZE x SIZE render (default 512) at one sample per pixel: the
//! primary rays through the pixel centres, and one shadow ray from each primary hit to
//! each point light above the surface, from the same offset origin and to the same
//! distance as the renderer's (`cpu::shade::light_sample`). Both kinds are traced on all
//! rayon threads in chunks of 64 rays, best of five runs: primary rays by `closest_hit`,
//! shadow rays by `transmission`, which the renderer uses (it goes on through surfaces
//! that transmit light, where an occlusion test would stop).
//!
//! The file (little-endian): "GPRTRAYS", then counted arrays, each a u32 count and its
//! f32 records: triangles (v0, v1, v2: 9 floats), spheres (centre, radius: 4), cones
//! (p0, r0, p1, r1: 8), primary rays (origin, direction, tnear, and our hit distance,
//! infinity for a miss: 8), shadow rays (origin, direction, tfar, and whether ours found
//! the light blocked, 0 or 1: 8).

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use glam::Vec3;
use gpurt::cpu::main::camera_ray;
use gpurt::cpu::shade::offset_origin;
use gpurt::cpu::traverse::{closest_hit, transmission};
use gpurt::cpu::types::{Bindings, Ray};
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::*;
use rayon::prelude::*;

/// Rays per task: rayon's unit of work, and Embree's in the C harness.
const CHUNK: usize = 64;

/// Best time of five runs of `f`.
fn best_of_five(mut f: impl FnMut()) -> Duration {
    (0..5)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed()
        })
        .min()
        .expect("five runs")
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene = PathBuf::from(args.next().unwrap_or("scenes/spheres.nff".into()));
    let size: u32 = args.next().map_or(Ok(512), |s| s.parse())?;
    let out = args.next().map(PathBuf::from);

    // The tree a render of these rays would get: one sample per pixel, or SPP (the rays
    // are those of the first sample either way; a longer render gets a better tree,
    // `bvh::Quality::for_work`).
    let spp: u64 = std::env::var("SPP").map_or(Ok(1), |s| s.parse())?;
    let buffers =
        gpurt::run::prepare(&scene, None, |_| u64::from(size) * u64::from(size) * spp)?.buffers;
    anyhow::ensure!(
        buffers.planes.is_empty()
            && buffers.prims.iter().all(|p| p.kind() != PRIM_BOX)
            && buffers.camera.aperture <= 0.0,
        "{}: infinite planes, boxes and thin lenses have no Embree counterpart here",
        scene.display()
    );
    let opts = RenderOptions {
        width: size,
        height: size,
        ..RenderOptions::for_camera(&buffers.camera)
    };
    let g = frame::globals(&buffers, &opts);
    // GPURT_CPU_WALK=binary times the GPU's walk of the binary tree instead.
    let b = match std::env::var("GPURT_CPU_WALK").as_deref() {
        Ok("binary") => Bindings::gpu_walk(&buffers, &g),
        _ => Bindings::new(&buffers, &g),
    };

    // Primary rays, scanline order, as a renderer without tiles would shoot them.
    let primary: Vec<Ray> = (0..size * size)
        .map(|i| {
            let (x, y) = ((i % size) as f32 + 0.5, (i / size) as f32 + 0.5);
            camera_ray(&g, x, y, &mut 0)
        })
        .collect();
    let trace_primary = || -> Vec<f32> {
        primary
            .par_iter()
            .with_min_len(CHUNK)
            .map(|r| closest_hit(&b, r, g.hither, NO_HIT).t)
            .collect()
    };
    let hits = trace_primary();
    let primary_time = best_of_five(|| {
        std::hint::black_box(trace_primary());
    });

    // Shadow rays from every hit to every point light on its side (directional and area
    // lights are not in the SPD scenes).
    let mut shadow: Vec<(Ray, f32)> = Vec::new();
    for (ray, &t) in primary.iter().zip(&hits) {
        if t == NO_HIT {
            continue;
        }
        let hit = closest_hit(&b, ray, g.hither, NO_HIT);
        debug_assert_ne!(hit.prim, NO_PRIM);
        let s = gpurt::cpu::shade::surface(&b, ray, &hit);
        for light in b.lights.iter().filter(|l| l.kind == LIGHT_POINT) {
            let to = light.pos - s.point;
            let l = to.normalize();
            if s.ns.dot(l) <= 0.0 {
                continue;
            }
            let origin = offset_origin(&s, l, g.epsilon);
            shadow.push((Ray { origin, dir: l }, to.length()));
        }
    }
    let trace_shadow = || -> Vec<bool> {
        shadow
            .par_iter()
            .with_min_len(CHUNK)
            .map(|(r, tmax)| transmission(&b, r, *tmax, &mut 0) == Vec3::ZERO)
            .collect()
    };
    let blocked = trace_shadow();
    let shadow_time = best_of_five(|| {
        std::hint::black_box(trace_shadow());
    });

    let rate = |n: usize, t: Duration| n as f64 / t.as_secs_f64() / 1e6;
    println!(
        "gpurt   primary {:>9} rays {:8.2} Mrays/s   shadow {:>9} rays {:8.2} Mrays/s   ({} threads)",
        primary.len(),
        rate(primary.len(), primary_time),
        shadow.len(),
        rate(shadow.len(), shadow_time),
        rayon::current_num_threads()
    );

    if let Some(out) = out {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&out)?);
        w.write_all(b"GPRTRAYS")?;
        let floats = |w: &mut dyn Write, v: &[f32]| -> std::io::Result<()> {
            v.iter().try_for_each(|f| w.write_all(&f.to_le_bytes()))
        };
        let count = |w: &mut dyn Write, n: usize| w.write_all(&(n as u32).to_le_bytes());
        let of = |kind| buffers.prims.iter().filter(move |p| p.kind() == kind);
        count(&mut w, of(PRIM_TRIANGLE).count())?;
        for p in of(PRIM_TRIANGLE) {
            // Triangles are stored as a vertex and two edges.
            let (v1, v2) = (p.p0 + p.p1, p.p0 + p.p2);
            floats(
                &mut w,
                &[p.p0.to_array(), v1.to_array(), v2.to_array()].concat(),
            )?;
        }
        count(&mut w, of(PRIM_SPHERE).count())?;
        for p in of(PRIM_SPHERE) {
            floats(&mut w, &[p.p0.x, p.p0.y, p.p0.z, p.f0])?;
        }
        count(&mut w, of(PRIM_CONE).count())?;
        for p in of(PRIM_CONE) {
            floats(
                &mut w,
                &[p.p0.x, p.p0.y, p.p0.z, p.f0, p.p1.x, p.p1.y, p.p1.z, p.f1],
            )?;
        }
        count(&mut w, primary.len())?;
        for (r, &t) in primary.iter().zip(&hits) {
            let t = if t == NO_HIT { f32::INFINITY } else { t };
            floats(
                &mut w,
                &[&r.origin.to_array()[..], &r.dir.to_array(), &[g.hither, t]].concat(),
            )?;
        }
        count(&mut w, shadow.len())?;
        for ((r, tmax), &blocked) in shadow.iter().zip(&blocked) {
            floats(
                &mut w,
                &[
                    &r.origin.to_array()[..],
                    &r.dir.to_array(),
                    &[*tmax, f32::from(u8::from(blocked))],
                ]
                .concat(),
            )?;
        }
        w.flush()?;
    }
    Ok(())
}
