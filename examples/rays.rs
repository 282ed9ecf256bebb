//! The CPU renderer's traversal timed on plain rays, alone and in packets, and those rays
//! written out for `benches/embree/rays.c`, so that Embree traces exactly the same ones:
//!
//!     cargo run --release --example rays -- SCENE [SIZE] [OUT.rays]
//!
//! The rays are those of a SIZE x SIZE render (default 512, a multiple of 4) at one sample
//! per pixel, taken in blocks of 4x4 pixels (the order of the file too): the primary rays
//! through the pixel centres; one shadow ray from each primary hit to each point light
//! above the surface, from the same offset origin and to the same distance as the
//! renderer's (`cpu::shade::light_ray`); and one mirror ray from each hit, off its shading
//! normal (`reflect_dir`), as the renderer reflects them, curved surfaces and all: the
//! incoherent rays that keep the single-ray walk.
//!
//! Each kind is traced on all rayon threads in chunks of 64 rays, best of five runs:
//! primary rays by `closest_hit` one at a time and by `Kernels::closest_hits` in packets
//! (16 lanes: a 4x4 block, 8: half of one, 4: a row of one), shadow rays by `transmission`
//! and by `Kernels::transmissions` (the renderer's: it goes on through surfaces that
//! transmit light, where an occlusion test stops), mirror rays by `closest_hit`. The packet
//! answers must be the single-ray ones to the bit: the program fails otherwise.
//! `GPURT_SIMD` picks the packet kernels (`cpu::packet::Kernels::from_env`); `CLOCK=cpu`
//! times processor time instead of wall-clock; `PACKETS_ONLY=1` times the packets alone
//! (the others print 0).
//!
//! The file (little-endian): "GPRTRAYS", then counted arrays, each a u32 count and its
//! f32 records: triangles (v0, v1, v2: 9 floats; a box's faces as two each), spheres (centre, radius: 4), cones
//! (p0, r0, p1, r1: 8), primary rays (origin, direction, tnear, and our hit distance,
//! infinity for a miss: 8), shadow rays in groups of 16 slots, a group per block and
//! light (origin, direction, tfar, and whether ours found the light blocked, 0 or 1: 8; an
//! empty slot has tfar -1), mirror rays (as primary rays, tnear 0); then what a crossing
//! of each triangle, sphere and cone lets through (r, g, b: 3, zero for an opaque one;
//! three arrays in the order of the primitives' own), and the light each shadow ray let
//! through on our side (r, g, b: 3, zero where blocked; one a slot).

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use glam::Vec3;
use gpurt::cpu::fast::wide_ray::{closest_hit, transmission};
use gpurt::cpu::packet::{Kernels, MAX_LANES, Packet};
use gpurt::cpu::pixel::camera_ray;
use gpurt::cpu::shade::{light_ray, offset_origin, reflect_dir, surface};
use gpurt::cpu::types::{Bindings, Hit, Ray};
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::*;
use gpurt::scene::place::box_triangles;
use rayon::prelude::*;

/// Rays per task: rayon's unit of work, and Embree's in the C harness.
const CHUNK: usize = 64;
/// Pixels of a block, a 4x4 square: a packet of 16 rays, two of 8, four of 4.
const BLOCK: usize = 16;

/// Best time of five runs of `f`: wall-clock time, or with `CLOCK=cpu` the processor time
/// of the whole process, which other programs sharing the machine inflate far less.
fn best_of_five(mut f: impl FnMut()) -> Duration {
    let cpu = std::env::var("CLOCK").is_ok_and(|c| c == "cpu");
    let now = || {
        if cpu {
            process_time()
        } else {
            Instant::now().duration_since(*START.get_or_init(Instant::now))
        }
    };
    (0..5)
        .map(|_| {
            let start = now();
            f();
            now() - start
        })
        .min()
        .expect("five runs")
}

static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();

/// Processor time this process has used, all threads (Linux; wall-clock elsewhere).
#[cfg(target_os = "linux")]
fn process_time() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec to write to.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

#[cfg(not(target_os = "linux"))]
fn process_time() -> Duration {
    START.get_or_init(Instant::now).elapsed()
}

/// A shadow ray and its interval's end; `None` for an empty slot of a group.
type Shadow = Option<(Ray, f32)>;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let scene = PathBuf::from(args.next().unwrap_or("scenes/spheres.nff".into()));
    let size: u32 = args.next().map_or(Ok(512), |s| s.parse())?;
    let out = args.next().map(PathBuf::from);
    anyhow::ensure!(
        size > 0 && size.is_multiple_of(4),
        "SIZE must be a multiple of 4"
    );

    // The tree a render of these rays would get: one sample per pixel, or SPP (the rays
    // are those of the first sample either way; a longer render gets a better tree,
    // `bvh::Quality::for_work`).
    let spp: u64 = std::env::var("SPP").map_or(Ok(1), |s| s.parse())?;
    let read = gpurt::run::read(&scene, None, &Default::default())?;
    let buffers = gpurt::run::pack(read, u64::from(size) * u64::from(size) * spp)?.buffers;
    anyhow::ensure!(
        buffers.planes.is_empty() && buffers.camera.aperture <= 0.0,
        "{}: infinite planes and thin lenses have no Embree counterpart here",
        scene.display()
    );
    let opts = RenderOptions {
        width: size,
        height: size,
        ..RenderOptions::for_camera(&buffers.camera)
    };
    let g = frame::globals(&buffers, &opts);
    let b = Bindings::new(&buffers, &g);
    let kernels = Kernels::from_env()?.ok_or_else(|| anyhow::anyhow!("GPURT_SIMD=none"))?;
    let lanes = kernels.lanes();

    // Primary rays, block by block, row by row within a block.
    let blocks = size / 4;
    let primary: Vec<Ray> = (0..size * size)
        .map(|i| {
            let (block, k) = (i / 16, i % 16);
            let x = (block % blocks) * 4 + k % 4;
            let y = (block / blocks) * 4 + k / 4;
            camera_ray(&g, x as f32 + 0.5, y as f32 + 0.5, &mut 0)
        })
        .collect();
    let mut hits = vec![0.0f32; primary.len()];
    let single = |out: &mut [f32]| {
        primary
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| {
                for (r, t) in rays.iter().zip(out) {
                    *t = closest_hit(&b, r, g.hither, NO_HIT).t;
                }
            });
    };
    let packets = |out: &mut [f32]| {
        primary
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| {
                let mut p = Packet::default();
                let mut h = [Hit {
                    t: 0.0,
                    prim: 0,
                    u: 0.0,
                    v: 0.0,
                    cost: 0,
                    nodes: 0,
                }; MAX_LANES];
                for (rays, out) in rays.chunks(lanes).zip(out.chunks_mut(lanes)) {
                    p.clear();
                    for (k, r) in rays.iter().enumerate() {
                        p.set(k, r, g.hither, NO_HIT);
                    }
                    kernels.closest_hits(&b, &p, &mut h);
                    for (k, t) in out.iter_mut().enumerate() {
                        *t = h[k].t;
                    }
                }
            });
    };
    single(&mut hits);
    let mut packed = vec![0.0f32; primary.len()];
    packets(&mut packed);
    let differ = hits
        .iter()
        .zip(&packed)
        .filter(|(a, b)| a.to_bits() != b.to_bits())
        .count();
    anyhow::ensure!(
        differ == 0,
        "{differ} primary rays: packets and single rays differ"
    );
    // PACKETS_ONLY=1 times the packets alone (benches/packets.sh: sizes up to 4K).
    let only_packets = std::env::var("PACKETS_ONLY").is_ok_and(|v| v == "1");
    let timed = |f: &mut dyn FnMut()| {
        if only_packets {
            Duration::MAX
        } else {
            best_of_five(f)
        }
    };
    let primary_single = timed(&mut || single(&mut packed));
    let primary_packets = best_of_five(|| packets(&mut packed));

    // Shadow rays from every hit to every point light on its side (directional and area
    // lights are not in the SPD scenes), in groups of a block's, and mirror rays.
    let surfaces: Vec<_> = primary
        .iter()
        .zip(&hits)
        .map(|(ray, &t)| {
            (t != NO_HIT).then(|| surface(&b, ray, &closest_hit(&b, ray, g.hither, NO_HIT)))
        })
        .collect();
    let mut shadow: Vec<Shadow> = Vec::new();
    for (block, rays) in surfaces.chunks(BLOCK).zip(primary.chunks(BLOCK)) {
        for light in b.lights.iter().filter(|l| l.kind == LIGHT_POINT) {
            let group = block.iter().zip(rays).map(|(s, ray)| {
                let s = s.as_ref()?;
                let (m, r) = (
                    &b.materials[s.material as usize],
                    reflect_dir(ray.dir, s.ns),
                );
                let lr = light_ray(&b, s, m, ray.dir, r, light, 0, &mut 0)?;
                Some((lr.ray, lr.dist))
            });
            if group.clone().any(|r| r.is_some()) {
                shadow.extend(group);
            }
        }
    }
    let mirror: Vec<Ray> = primary
        .iter()
        .zip(&surfaces)
        .filter_map(|(ray, s)| {
            let s = s.as_ref()?;
            let dir = reflect_dir(ray.dir, s.ns);
            Some(Ray {
                origin: offset_origin(s, dir, g.epsilon),
                dir,
            })
        })
        .collect();

    let mut blocked = vec![false; shadow.len()];
    let single = |out: &mut [bool]| {
        shadow
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| {
                for (r, o) in rays.iter().zip(out) {
                    if let Some((r, tmax)) = r {
                        *o = transmission(&b, r, *tmax, &mut 0, &mut None) == Vec3::ZERO;
                    }
                }
            });
    };
    let packets = |out: &mut [bool]| {
        shadow
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| {
                let mut p = Packet::default();
                let mut light = [Vec3::ZERO; MAX_LANES];
                for (rays, out) in rays.chunks(lanes).zip(out.chunks_mut(lanes)) {
                    p.clear();
                    for (k, r) in rays.iter().enumerate() {
                        if let Some((r, tmax)) = r {
                            p.set(k, r, 0.0, *tmax);
                        }
                    }
                    kernels.transmissions(&b, &p, &mut light, &mut [0; MAX_LANES], &mut None);
                    for (k, o) in out.iter_mut().enumerate() {
                        *o = p.lanes() & 1 << k != 0 && light[k] == Vec3::ZERO;
                    }
                }
            });
    };
    single(&mut blocked);
    let mut packed = vec![false; shadow.len()];
    packets(&mut packed);
    anyhow::ensure!(
        blocked == packed,
        "shadow rays: packets and single rays differ"
    );
    let shadow_single = timed(&mut || single(&mut packed));
    let shadow_packets = best_of_five(|| packets(&mut packed));
    let shadow_rays = shadow.iter().flatten().count();

    let mut mirror_hits = vec![0.0f32; mirror.len()];
    let trace_mirror = |out: &mut [f32]| {
        mirror
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .for_each(|(rays, out)| {
                for (r, t) in rays.iter().zip(out) {
                    *t = closest_hit(&b, r, 0.0, NO_HIT).t;
                }
            });
    };
    trace_mirror(&mut mirror_hits);
    let mirror_time = timed(&mut || trace_mirror(&mut vec![0.0; mirror.len()]));

    let rate = |n: usize, t: Duration| n as f64 / t.as_secs_f64() / 1e6;
    // Name, rays, Mrays/s, as benches/embree/rays.c prints them (P: packets).
    println!(
        "gpurt primary1 {n} {:.2} primaryP {n} {:.2} shadow1 {s} {:.2} shadowP {s} {:.2} mirror1 {m} {:.2}   threads {} lanes {lanes} isa {}",
        rate(primary.len(), primary_single),
        rate(primary.len(), primary_packets),
        rate(shadow_rays, shadow_single),
        rate(shadow_rays, shadow_packets),
        rate(mirror.len(), mirror_time),
        rayon::current_num_threads(),
        kernels.isa().name(),
        n = primary.len(),
        s = shadow_rays,
        m = mirror.len(),
    );

    if let Some(out) = out {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&out)?);
        w.write_all(b"GPRTRAYS")?;
        let floats = |w: &mut dyn Write, v: &[f32]| -> std::io::Result<()> {
            v.iter().try_for_each(|f| w.write_all(&f.to_le_bytes()))
        };
        let count = |w: &mut dyn Write, n: usize| w.write_all(&(n as u32).to_le_bytes());
        let of = |kind| buffers.prims.iter().filter(move |p| p.kind() == kind);
        // The scene's triangles once each: a triangle that spatial splits put in several
        // leaves has a record in each (`SceneBuffers::copies`), which Embree, building its
        // own tree, should not have to trace.
        // Then each box's faces as two triangles each, which Embree meets where we meet
        // the box. Triangles are stored as a vertex and two edges.
        let mut seen = std::collections::HashSet::new();
        let triangles: Vec<([Vec3; 3], &GpuPrim)> = of(PRIM_TRIANGLE)
            .filter(|p| buffers.copies == 0 || seen.insert(bytemuck::bytes_of(*p)))
            .map(|p| ([p.p0, p.p0 + p.p1, p.p0 + p.p2], p))
            .chain(of(PRIM_BOX).flat_map(|p| box_triangles(p.p0, p.p1).map(move |t| (t, p))))
            .collect();
        count(&mut w, triangles.len())?;
        for (t, _) in &triangles {
            floats(&mut w, &t.map(|v| v.to_array()).concat())?;
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
        let closest = |w: &mut dyn Write, rays: &[Ray], hits: &[f32], tnear: f32| {
            count(w, rays.len())?;
            for (r, &t) in rays.iter().zip(hits) {
                let t = if t == NO_HIT { f32::INFINITY } else { t };
                floats(
                    w,
                    &[&r.origin.to_array()[..], &r.dir.to_array(), &[tnear, t]].concat(),
                )?;
            }
            std::io::Result::Ok(())
        };
        closest(&mut w, &primary, &hits, g.hither)?;
        count(&mut w, shadow.len())?;
        for (r, &blocked) in shadow.iter().zip(&blocked) {
            let (r, tmax) = r.unwrap_or((
                Ray {
                    origin: Vec3::ZERO,
                    dir: Vec3::X,
                },
                -1.0,
            ));
            let record = [
                &r.origin.to_array()[..],
                &r.dir.to_array(),
                &[tmax, f32::from(u8::from(blocked))],
            ];
            floats(&mut w, &record.concat())?;
        }
        closest(&mut w, &mirror, &mirror_hits, 0.0)?;
        // What a crossing of each primitive lets through, as `leaf::transmit_leaf`
        // multiplies it in (zero for an opaque one), kind by kind in the order above; then
        // the light each shadow ray lets through, so that Embree, letting its shadow rays
        // through the same surfaces, can be held to the same answers.
        let through = |p: &GpuPrim| {
            let m = &buffers.materials[p.material() as usize];
            if m.t > 0.0 { m.t * m.color } else { Vec3::ZERO }.to_array()
        };
        for prims in [
            triangles
                .iter()
                .map(|(_, p)| through(p))
                .collect::<Vec<_>>(),
            of(PRIM_SPHERE).map(through).collect(),
            of(PRIM_CONE).map(through).collect(),
        ] {
            count(&mut w, prims.len())?;
            floats(&mut w, prims.as_flattened())?;
        }
        count(&mut w, shadow.len())?;
        for r in &shadow {
            let light = r.map_or(Vec3::ZERO, |(r, tmax)| {
                transmission(&b, &r, tmax, &mut 0, &mut None)
            });
            floats(&mut w, &light.to_array())?;
        }
        w.flush()?;
    }
    Ok(())
}
