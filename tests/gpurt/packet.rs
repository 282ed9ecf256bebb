//! Packets of rays (`cpu::packet`) against the single-ray walk they stand in for, with
//! every instruction set this processor runs (each forced in turn): the same closest hit
//! to the bit (distance, primitive, barycentrics) and the same light through each shadow
//! ray, on incoherent random rays and on coherent ones (camera rays in blocks, their
//! shadow rays to every light, their mirror rays) of every shared scene and of ours; and
//! the renderer's images and ray counts with packets and without, across sizes, samples,
//! depths, lights and AOVs. Each comparison is shown to fail on a perturbed input.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use glam::Vec3;
use gpurt::cpu::fast::wide_ray::{closest_hit, transmission};
use gpurt::cpu::packet::{Isa, Kernels, MAX_LANES, Packet};
use gpurt::cpu::pixel::camera_ray;
use gpurt::cpu::shade::{light_ray, offset_origin, reflect_dir, surface};
use gpurt::cpu::types::{Bindings, Hit, Ray, RayCounts};
use gpurt::film::Accumulator;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::*;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene;

use crate::common::{XorShift, files_with, own_scenes, shared_scenes};

/// The kernels of every instruction set this processor runs: SSE and the portable ones
/// everywhere on x86-64, AVX2 and AVX-512 where present. Where the processor itself
/// reports an instruction set (asked here, apart from the kernels' own check), its kernels
/// must be among them: a machine with AVX2 or AVX-512 tests those kernels, never skips them.
fn all_kernels() -> Vec<Kernels> {
    let found: Vec<Kernels> = Isa::ALL.into_iter().filter_map(Kernels::new).collect();
    let has = |isa: Isa| found.iter().any(|k| k.isa() == isa);
    assert!(has(Isa::Portable));
    #[cfg(target_arch = "x86_64")]
    {
        assert!(has(Isa::Sse));
        use std::arch::is_x86_feature_detected as has_feature;
        let v3 = has_feature!("avx2")
            && has_feature!("fma")
            && has_feature!("bmi1")
            && has_feature!("bmi2")
            && has_feature!("lzcnt")
            && has_feature!("popcnt");
        assert!(!v3 || has(Isa::Avx2), "AVX2 present, its kernels missing");
        let avx512 = v3 && has_feature!("avx512f");
        assert!(
            !avx512 || has(Isa::Avx512),
            "AVX-512 present, its kernels missing"
        );
    }
    found
}

fn scenes() -> Vec<PathBuf> {
    let mut all = files_with(&own_scenes(), &[".nff", ".ply", ".gltf", ".glb"]);
    if let Some(dir) = shared_scenes() {
        all.extend(files_with(&dir, &[".nff", ".nff.gz"]));
    }
    all
}

fn load(path: &Path) -> SceneBuffers {
    let scene = scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    pack::pack(scene).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The NFF text `src` written to `NAME.nff` in a directory of its own, and loaded.
fn load_nff(name: &str, src: &str) -> SceneBuffers {
    let path = crate::common::temp_dir(&format!("packet-{name}")).join(format!("{name}.nff"));
    std::fs::write(&path, src).unwrap();
    load(&path)
}

/// Why two hits differ, if they do: every field but `cost` (the wide walks count none).
fn hit_differs(packet: &Hit, alone: &Hit) -> Option<String> {
    let bits = |h: &Hit| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits());
    (bits(packet) != bits(alone)).then(|| format!("packet {packet:?}, alone {alone:?}"))
}

fn light_differs(packet: Vec3, alone: Vec3) -> Option<String> {
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    (bits(packet) != bits(alone)).then(|| format!("packet {packet}, alone {alone}"))
}

#[test]
fn the_comparisons_catch_a_last_bit() {
    let h = Hit {
        t: 2.5,
        prim: 7,
        u: 0.25,
        v: 0.5,
        cost: 0,
        nodes: 0,
    };
    assert_eq!(hit_differs(&h, &Hit { cost: 9, ..h }), None);
    for other in [
        Hit {
            t: f32::from_bits(h.t.to_bits() + 1),
            ..h
        },
        Hit { prim: 8, ..h },
        Hit {
            u: f32::from_bits(h.u.to_bits() + 1),
            ..h
        },
        Hit {
            v: f32::from_bits(h.v.to_bits() - 1),
            ..h
        },
    ] {
        assert!(hit_differs(&other, &h).is_some(), "{other:?}");
    }
    let l = Vec3::new(0.5, 0.25, 1.0);
    assert!(light_differs(l, l).is_none());
    assert!(
        light_differs(
            Vec3::new(0.5, f32::from_bits(0.25f32.to_bits() + 1), 1.0),
            l
        )
        .is_some()
    );
    assert!(light_differs(Vec3::new(0.5, 0.25, -0.0), Vec3::new(0.5, 0.25, 0.0)).is_some());
}

/// Rays grouped as packets of `lanes`, each with its interval.
type Group = Vec<(Ray, f32, f32)>;

/// Traces `groups` both ways with `kernels`; returns the rays the packets answered.
fn check_closest(b: &Bindings, kernels: &Kernels, groups: &[Group], what: &str) -> (usize, usize) {
    let mut p = Packet::default();
    let mut hits = [Hit {
        t: 0.0,
        prim: 0,
        u: 0.0,
        v: 0.0,
        cost: 0,
        nodes: 0,
    }; MAX_LANES];
    let (mut packed, mut all) = (0, 0);
    for (g, group) in groups.iter().enumerate() {
        p.clear();
        for (k, (ray, tmin, tmax)) in group.iter().enumerate() {
            p.set(k, ray, *tmin, *tmax);
        }
        packed += kernels.closest_hits(b, &p, &mut hits).count_ones() as usize;
        all += group.len();
        for (k, (ray, tmin, tmax)) in group.iter().enumerate() {
            if let Some(why) = hit_differs(&hits[k], &closest_hit(b, ray, *tmin, *tmax)) {
                panic!(
                    "{what}, {}: packet {g} lane {k}, {ray:?}: {why}",
                    kernels.isa().name()
                );
            }
        }
    }
    (packed, all)
}

/// Traces the shadow rays of `groups` as packets with `kernels` and alone, each way with the
/// blocker of the last ray carried over (`hint`, as the renderer carries one a light; here
/// from ray to ray whatever the light), against the walk alone without one. Returns the
/// rays the packets answered.
fn check_shadows(b: &Bindings, kernels: &Kernels, groups: &[Group], what: &str) -> usize {
    let mut p = Packet::default();
    let mut light = [Vec3::ZERO; MAX_LANES];
    let mut packed = 0;
    let (mut hint, mut alone_hint) = (None, None);
    for (g, group) in groups.iter().enumerate() {
        p.clear();
        for (k, (ray, _, tmax)) in group.iter().enumerate() {
            p.set(k, ray, 0.0, *tmax);
        }
        packed += kernels
            .transmissions(b, &p, &mut light, &mut [0; MAX_LANES], &mut hint)
            .count_ones() as usize;
        for (k, (ray, _, tmax)) in group.iter().enumerate() {
            let alone = transmission(b, ray, *tmax, &mut 0, &mut None);
            let hinted = transmission(b, ray, *tmax, &mut 0, &mut alone_hint);
            if let Some(why) = light_differs(light[k], alone)
                .or_else(|| light_differs(hinted, alone).map(|why| format!("hinted: {why}")))
            {
                panic!(
                    "{what}, {}: shadow packet {g} lane {k}, {ray:?}: {why}",
                    kernels.isa().name()
                );
            }
        }
    }
    packed
}

/// Random rays: from outside aimed at a random primitive's box, and from inside in a random
/// direction; a third with a bounded interval. Consecutive ones share a packet: packets
/// whose lanes go every way.
fn random_groups(buffers: &SceneBuffers, lanes: usize, seed: u64) -> Vec<Group> {
    let mut rng = XorShift(seed | 1);
    let (lo, hi) = (buffers.bounds.min, buffers.bounds.max);
    let size = buffers.bounds.extent().max(Vec3::splat(1e-3));
    let rays: Vec<(Ray, f32, f32)> = (0..600)
        .map(|i| {
            let (origin, target) = if i % 2 == 0 && !buffers.prims.is_empty() {
                let p = &buffers.prims[(rng.next_u64() % buffers.prims.len() as u64) as usize];
                (rng.point_in(lo - size, hi + size), p.p0)
            } else {
                let o = rng.point_in(lo, hi);
                (o, o + rng.direction())
            };
            let tmax = if i % 3 == 0 {
                rng.range(0.0, size.length())
            } else {
                NO_HIT
            };
            (
                Ray {
                    origin,
                    dir: (target - origin).normalize_or(Vec3::X),
                },
                0.0,
                tmax,
            )
        })
        .collect();
    rays.chunks(lanes).map(<[_]>::to_vec).collect()
}

/// A small render's coherent rays, block by block as the renderer packs them: camera
/// rays (two jittered samples a pixel), the shadow rays from their hits to every light (area
/// lights' samples too), and mirror rays off every hit (curved surfaces too).
fn coherent_groups(b: &Bindings, lanes: usize) -> [Vec<Group>; 3] {
    let g = b.globals;
    let (bw, bh) = match lanes {
        16 => (4, 4),
        8 => (4, 2),
        _ => (2, 2),
    };
    let (mut eye, mut shadow, mut mirror) = (Vec::new(), Vec::new(), Vec::new());
    for s in 0..2 {
        for by in (0..g.height).step_by(bh) {
            for bx in (0..g.width).step_by(bw) {
                let mut group = Group::new();
                for y in by..(by + bh as u32).min(g.height) {
                    for x in bx..(bx + bw as u32).min(g.width) {
                        let mut rng = (y * g.width + x) ^ s << 20;
                        let j = (s as f32 * 0.37, s as f32 * 0.61);
                        let ray = camera_ray(g, x as f32 + j.0, y as f32 + j.1, &mut rng);
                        group.push((ray, g.hither, NO_HIT));
                    }
                }
                let surfaces: Vec<_> = group
                    .iter()
                    .map(|(ray, tmin, tmax)| {
                        let hit = closest_hit(b, ray, *tmin, *tmax);
                        (hit.prim != NO_PRIM).then(|| (*ray, surface(b, ray, &hit)))
                    })
                    .collect();
                for light in b.lights {
                    let mut rng = 12345;
                    let group: Group = surfaces
                        .iter()
                        .flatten()
                        .filter_map(|(ray, s)| {
                            let m = &b.materials[s.material as usize];
                            let r = reflect_dir(ray.dir, s.ns);
                            light_ray(b, s, m, ray.dir, r, light, 0, &mut rng)
                        })
                        .map(|lr| (lr.ray, 0.0, lr.dist))
                        .collect();
                    shadow.push(group);
                }
                let bounce: Group = surfaces
                    .iter()
                    .flatten()
                    .map(|(ray, s)| {
                        let dir = reflect_dir(ray.dir, s.ns);
                        (
                            Ray {
                                origin: offset_origin(s, dir, g.epsilon),
                                dir,
                            },
                            0.0,
                            NO_HIT,
                        )
                    })
                    .collect();
                mirror.push(bounce);
                eye.push(group);
            }
        }
    }
    [eye, shadow, mirror]
}

/// The frame whose coherent rays the per-ray comparisons trace: 24x18 from the scene's
/// camera.
fn small_frame(buffers: &SceneBuffers) -> GpuGlobals {
    let opts = RenderOptions {
        width: 24,
        height: 18,
        ..RenderOptions::for_camera(&buffers.camera)
    };
    frame::globals(buffers, &opts)
}

/// Every scene, every kernel: the packets' answers are the single-ray walk's, and the
/// packets answer nearly all coherent rays themselves (not handing them to the single walk).
#[test]
fn packets_find_the_single_ray_walks_hits_and_shadows_on_every_scene() {
    let kernels = all_kernels();
    let (mut packed, mut all, mut shadow_packed, mut shadows) = (0, 0, 0, 0);
    let paths = scenes();
    // Without the shared scenes (which `shared_scenes` skips visibly outside CI), our own.
    let least = if shared_scenes().is_some() { 20 } else { 5 };
    assert!(paths.len() >= least, "only {} scenes", paths.len());
    for path in &paths {
        let buffers = load(path);
        let globals = small_frame(&buffers);
        let b = Bindings::new(&buffers, &globals);
        let what = path.display().to_string();
        for k in &kernels {
            for group in random_groups(&buffers, k.lanes(), 7)
                .iter()
                .chain(random_groups(&buffers, k.lanes(), 8).iter())
            {
                check_closest(&b, k, std::slice::from_ref(group), &what);
                check_shadows(&b, k, std::slice::from_ref(group), &what);
            }
            let [eye, shadow, mirror] = coherent_groups(&b, k.lanes());
            let (p, a) = check_closest(&b, k, &eye, &what);
            (packed, all) = (packed + p, all + a);
            check_closest(&b, k, &mirror, &what);
            shadow_packed += check_shadows(&b, k, &shadow, &what);
            shadows += shadow.iter().map(Vec::len).sum::<usize>();
        }
    }
    assert!(
        packed as f64 > 0.97 * all as f64,
        "packets answered {packed} of {all} camera rays"
    );
    assert!(
        shadow_packed as f64 > 0.8 * shadows as f64,
        "{shadow_packed} of {shadows} shadow rays"
    );
}

/// A scene of every kind of primitive among infinite planes: a floor, a tilted wall and a
/// glass plane that cuts through the rest (so random rays start on both sides of it), with
/// boxes, spheres, triangles and cones, some of them glass, under two lights.
fn planes_and_boxes() -> String {
    let mut src = String::from(
        "v\nfrom 0 -14 6\nat 0 0 1\nup 0 0 1\nangle 45\nhither 0.01\nresolution 8 8\n\
         b 0.1 0.1 0.1\nl 4 -6 12\nl -6 2 9 0.5 0.5 0.5\n\
         f 0.8 0.8 0.7 0.8 0.2 10 0 1\npl 0 0 0  1 0 0  0 1 0\n\
         f 0.5 0.6 0.9 0.7 0.3 20 0 1\npl 6 0 0  6 1 0  7 0 3\n\
         f 0.9 0.9 1 0 0.1 30 0.8 1.4\npl 0 0 1.5  0 1 1.6  1 0 1.4\n",
    );
    let mut rng = XorShift(11);
    for i in 0..80 {
        let c = rng.point_in(Vec3::new(-5.0, -4.0, 0.2), Vec3::new(5.0, 4.0, 3.5));
        let r = rng.range(0.15, 0.6);
        if i % 9 == 0 {
            src += "f 1 0.95 0.9 0 0.1 40 0.7 1.5\n";
        } else if i % 9 == 1 {
            src += "f 0.8 0.3 0.2 0.7 0.3 15 0 1\n";
        }
        src += &match i % 4 {
            0 => format!(
                "aabb {} {} {} {} {} {}\n",
                c.x - r,
                c.x + r,
                c.y - r * 0.7,
                c.y + r * 0.7,
                c.z - r * 0.4,
                c.z + r
            ),
            1 => format!("s {} {} {} {r}\n", c.x, c.y, c.z),
            2 => format!(
                "p 3\n{} {} {}\n{} {} {}\n{} {} {}\n",
                c.x - r,
                c.y,
                c.z,
                c.x + r,
                c.y - r,
                c.z + r * 0.5,
                c.x,
                c.y + r,
                c.z - r * 0.3
            ),
            _ => format!(
                "c\n{} {} {} {r}\n{} {} {} {}\n",
                c.x,
                c.y,
                c.z - r,
                c.x + r * 0.2,
                c.y,
                c.z + r,
                r * 0.3
            ),
        };
    }
    src
}

/// The random and coherent rays of a scene with infinite planes, boxes and glass (which no
/// bundled or shared scene has together) get the single-ray walk's answers from every
/// kernel, and the random rays do meet the planes and the boxes.
#[test]
fn packets_find_the_single_ray_walks_hits_among_planes_and_boxes() {
    let buffers = load_nff("planes", &planes_and_boxes());
    assert_eq!(buffers.planes.len(), 3);
    let globals = small_frame(&buffers);
    let b = Bindings::new(&buffers, &globals);
    let (mut planes, mut boxes) = (0, 0);
    for k in &all_kernels() {
        for seed in [3, 4, 5] {
            let groups = random_groups(&buffers, k.lanes(), seed);
            check_closest(&b, k, &groups, "planes and boxes");
            check_shadows(&b, k, &groups, "planes and boxes");
            for (ray, tmin, tmax) in groups.iter().flatten() {
                let h = closest_hit(&b, ray, *tmin, *tmax);
                if h.t < *tmax && h.prim & PLANE_FLAG != 0 {
                    planes += 1;
                } else if h.t < *tmax && buffers.prims[h.prim as usize].kind() == PRIM_BOX {
                    boxes += 1;
                }
            }
        }
        let [eye, shadow, mirror] = coherent_groups(&b, k.lanes());
        check_closest(&b, k, &eye, "planes and boxes");
        check_closest(&b, k, &mirror, "planes and boxes");
        check_shadows(&b, k, &shadow, "planes and boxes");
    }
    println!("random rays met planes {planes} and boxes {boxes} times");
    assert!(
        planes > 100 && boxes > 100,
        "random rays met planes {planes} and boxes {boxes} times"
    );
}

/// An opaque ball under a light above a floor, among smaller balls (so that the tree has
/// levels to walk), and a glass ball beside it.
fn ball_under_a_light() -> String {
    let mut src = String::from(
        "v\nfrom 0 -12 6\nat 0 0 1\nup 0 0 1\nangle 45\nhither 0.01\nresolution 8 8\n\
         b 0 0 0\nl 0 0 10\nf 0.8 0.8 0.8 1 0 1 0 1\ns 0 0 5 1\n\
         p 4\n-20 -20 0\n20 -20 0\n20 20 0\n-20 20 0\n",
    );
    for i in 0..60 {
        let (x, y) = ((i % 10) as f32 - 4.5, (i / 10) as f32 * 1.5 + 3.0);
        src += &format!("s {x} {y} 0.5 0.2\n");
    }
    src + "f 0.9 0.9 1 0 0 1 0.8 1.5\ns 4 0 3 0.8\n"
}

/// The blocker of the last shadow ray to a light (`hint`) is tested first: a ray it blocks
/// walks no tree, alone or in a packet, and gets the same darkness; a ray it does not block
/// walks as before and gets the same light; a glass ball is never taken for a blocker.
#[test]
fn a_shadow_ray_blocked_where_the_last_one_was_walks_no_tree() {
    let buffers = load_nff("ball", &ball_under_a_light());
    let globals = small_frame(&buffers);
    let b = Bindings::new(&buffers, &globals);
    let light = Vec3::new(0.0, 0.0, 10.0);
    let shadow = |from: Vec3| {
        let to = light - from;
        let ray = Ray {
            origin: from,
            dir: to.normalize(),
        };
        (ray, to.length())
    };
    // Under the ball: blocked.
    let (under, dist) = shadow(Vec3::new(0.1, -0.2, 0.01));
    let (mut hint, mut walked) = (None, 0);
    assert_eq!(
        transmission(&b, &under, dist, &mut walked, &mut hint),
        Vec3::ZERO
    );
    let blocker = hint.expect("the ball blocked it");
    assert_eq!(buffers.prims[blocker as usize].kind(), PRIM_SPHERE);
    assert!(walked > 0);
    let mut again = 0;
    assert_eq!(
        transmission(&b, &under, dist, &mut again, &mut hint),
        Vec3::ZERO
    );
    assert_eq!(
        (again, hint),
        (0, Some(blocker)),
        "walked with the blocker known"
    );
    // Beside it, in the open and through the glass ball: the light the walk gives.
    for from in [Vec3::new(-8.0, 0.0, 0.01), Vec3::new(4.5, 0.0, 0.01)] {
        let (ray, dist) = shadow(from);
        let mut nodes = 0;
        let lit = transmission(&b, &ray, dist, &mut nodes, &mut hint);
        assert_ne!(lit, Vec3::ZERO, "from {from}");
        assert!(light_differs(lit, transmission(&b, &ray, dist, &mut 0, &mut None)).is_none());
        assert!(nodes > 0);
        assert_eq!(hint, Some(blocker), "from {from}");
    }
    // A packet of rays under the ball, with the blocker known: no node fetched.
    for k in &all_kernels() {
        let mut p = Packet::default();
        for lane in 0..k.lanes() {
            let (ray, dist) = shadow(Vec3::new(0.05 * lane as f32, 0.1, 0.01));
            p.set(lane, &ray, 0.0, dist);
        }
        let (mut lights, mut nodes) = ([Vec3::ONE; MAX_LANES], [0; MAX_LANES]);
        let mut packet_hint = None;
        k.transmissions(&b, &p, &mut lights, &mut nodes, &mut packet_hint);
        assert_eq!(packet_hint, Some(blocker), "{}", k.isa().name());
        assert!(nodes.iter().sum::<u32>() > 0);
        k.transmissions(&b, &p, &mut lights, &mut nodes, &mut packet_hint);
        assert_eq!(nodes, [0; MAX_LANES], "{}", k.isa().name());
        assert!(lights[..k.lanes()].iter().all(|&l| l == Vec3::ZERO));
    }
}

/// A glass panel of one material between a light and the floor, a glass sphere of that
/// material under it, and with `two`, a glass sphere of another.
fn glass(two: bool) -> String {
    let other = if two {
        "f 0.4 0.9 0.5 0 0 1 0.6 1.3\ns 1.2 0 3 0.8\n"
    } else {
        ""
    };
    format!(
        "v\nfrom 0 -8 4\nat 0 0 2\nup 0 0 1\nangle 40\nhither 0.01\nresolution 8 8\n\
         b 0 0 0\nl 0 0 10\n\
         f 0.9 0.8 0.7 0 0 1 0.8 1.5\np 4\n-2 -2 5\n2 -2 5\n2 2 5\n-2 2 5\ns -1 0 3 0.8\n{other}"
    )
}

/// Shadow rays through glass: where every surface a ray crosses is of one material, the
/// packet answers it itself (the same factor each time, so the order of the product, which
/// the single-ray walk alone knows, cannot change a bit of it); where a ray crosses two
/// materials, the single-ray walk does. Either way the light is `transmission`'s to the
/// bit, and some rays pass through the sphere as well as the panel.
#[test]
fn shadow_packets_answer_rays_through_glass_of_one_material() {
    let light = Vec3::new(0.0, 0.0, 10.0);
    let n = 32;
    let rays: Vec<(Ray, f32, f32)> = (0..n * n)
        .map(|i| {
            let at = |i: u32| -3.0 + 6.0 * (i as f32 + 0.5) / n as f32;
            let origin = Vec3::new(at(i % n), at(i / n), 0.0);
            let to = light - origin;
            let ray = Ray {
                origin,
                dir: to.normalize(),
            };
            (ray, 0.0, to.length())
        })
        .collect();
    for two in [false, true] {
        let name = format!("glass-{two}");
        let buffers = load_nff(&name, &glass(two));
        let globals = frame::globals(&buffers, &RenderOptions::for_camera(&buffers.camera));
        let b = Bindings::new(&buffers, &globals);
        let mut lights: Vec<[u32; 3]> = rays
            .iter()
            .map(|(ray, _, tmax)| {
                transmission(&b, ray, *tmax, &mut 0, &mut None)
                    .to_array()
                    .map(f32::to_bits)
            })
            .collect();
        lights.sort_unstable();
        lights.dedup();
        assert!(lights.len() >= 2 + usize::from(two), "{two}: {lights:?}");
        assert!(
            !lights.contains(&[1.0f32.to_bits(); 3]),
            "every ray crosses the panel"
        );
        for k in &all_kernels() {
            let groups: Vec<Group> = rays.chunks(k.lanes()).map(<[_]>::to_vec).collect();
            let packed = check_shadows(&b, k, &groups, &name);
            let what = format!("{two}, {}: {packed} of {}", k.isa().name(), rays.len());
            if two {
                assert!(packed < rays.len(), "{what}");
            } else {
                assert_eq!(packed, rays.len(), "{what}");
            }
        }
    }
}

/// A render's image and its ray counts.
fn render(
    b: &SceneBuffers,
    opts: &RenderOptions,
    kernels: Option<&Kernels>,
) -> (Vec<[u32; 3]>, RayCounts) {
    let g = frame::globals(b, opts);
    let mut accum = Accumulator::new(g.width, g.height);
    let never = AtomicBool::new(false);
    let counts = gpurt::cpu::render_rows_with(
        b,
        &g,
        kernels,
        0..g.height,
        0..g.spp,
        &mut accum,
        &|_| {},
        &never,
    )
    .expect("renders");
    let film = accum.into_film();
    (
        film.pixels.iter().map(|p| p.map(f32::to_bits)).collect(),
        counts,
    )
}

/// Lights, mirrors and glass beside one another: twelve point lights, a directional one,
/// an area light, a mirror plane, a flat mirror triangle, a glass sphere, a cone.
const MANY_LIGHTS: &str = "v\nfrom 0 -6 2.5\nat 0 0 0.5\nup 0 0 1\nangle 50\nhither 0.01\nresolution 8 8\n\
b 0.1 0.1 0.2\n\
l 3 3 6\nl -3 3 6\nl 3 -3 6\nl -3 -3 6\nl 0 0 8\nl 5 0 2\nl -5 0 2\nl 0 5 2\nl 0 -5 7\nl 1 1 9\nl -1 2 4\nl 2 -1 5\n\
dl 1 -1 2\nal -1 -1 5 2 0 0 0 2 0 0.5 0.5 0.5 2 2\n\
f 0.9 0.9 0.9 0.3 0.7 20 0 1\n\
pl 0 0 0 1 0 0 0 1 0\n\
f 0.8 0.3 0.2 0.5 0.3 30 0 1\ns 0 0 1 1\n\
f 0.9 0.9 0.9 0 0.1 50 0.9 1.5\ns 1.5 -1 0.7 0.6\n\
f 0.2 0.8 0.3 0.8 0.1 10 0 1\np 3\n-3 2 0\n3 2 0\n0 3 3\n\
f 0.3 0.3 0.9 0.7 0.2 10 0 1\nc\n-2 -1 0 0.4\n-2 -1 2 0.1\n";

#[test]
fn renders_with_packets_are_the_single_ray_renders_to_the_bit() {
    let dir = crate::common::temp_dir("packet-lights");
    let many = dir.join("many-lights.nff");
    std::fs::write(&many, MANY_LIGHTS).expect("writes");
    let mut paths: Vec<PathBuf> = files_with(&own_scenes(), &[".nff", ".ply", ".gltf", ".glb"]);
    paths.push(many);
    if let Some(shared) = shared_scenes() {
        for s in [
            "balls-1", "gears-1", "mount-3", "rings-1", "teapot-2", "tetra-3", "tree-1",
        ] {
            paths.push(shared.join(format!("spd/{s}.nff")));
        }
    }
    let kernels = all_kernels();
    let mut packed = RayCounts::default();
    for (i, path) in paths.iter().enumerate() {
        let buffers = load(path);
        // Sizes that leave partial blocks and tiles; samples, depths and AOVs beyond the
        // defaults, by turns.
        let base = RenderOptions::for_camera(&buffers.camera);
        let opts = RenderOptions {
            width: [37, 21, 50][i % 3],
            height: [29, 17, 18][i % 3],
            spp: [3, 1, 5][i % 3],
            max_depth: [8, 2, 12, 1][i % 4],
            aov: if i % 5 == 4 { AOV_DEPTH } else { base.aov },
            ..base
        };
        let (want, want_counts) = render(&buffers, &opts, None);
        assert_eq!(
            want_counts.eye_packed
                + want_counts.shadow_packed
                + want_counts.reflected_packed
                + want_counts.refracted_packed,
            0
        );
        for k in &kernels {
            let (got, counts) = render(&buffers, &opts, Some(k));
            let what = format!("{}, {}", path.display(), k.isa().name());
            let first = got.iter().zip(&want).position(|(a, b)| a != b);
            assert_eq!(first, None, "{what}: first differing pixel");
            let kinds = |c: &RayCounts| (c.eye, c.shadow, c.reflected, c.refracted);
            assert_eq!(kinds(&counts), kinds(&want_counts), "{what}: rays by kind");
            packed.add(&counts);
        }
        if i == 0 {
            // The comparison's own teeth: another seed moves the jittered samples.
            let seeded = RenderOptions { seed: 1, ..opts };
            let (off, _) = render(&buffers, &seeded, kernels.first());
            assert!(
                off.iter().zip(&want).any(|(a, b)| a != b),
                "{}",
                path.display()
            );
        }
    }
    assert!(
        packed.eye_packed > 0
            && packed.shadow_packed > 0
            && packed.reflected_packed > 0
            && packed.refracted_packed > 0,
        "{packed:?}"
    );
}

/// The mirror and refracted rays off every surface, curved or flat, go in packets, and so
/// do their shadow rays to point lights: on spheres.nff (a mirror sphere and a glass one
/// on a floor of quads, two point lights) at depth 2, where every ray is a camera ray, its
/// shadow rays, its mirror or refracted ray or that ray's shadow rays; and at depth 3 the
/// refracted rays' refracted rays.
#[test]
fn mirror_and_refracted_rays_and_their_shadow_rays_go_in_packets() {
    let buffers = load(&own_scenes().join("spheres.nff"));
    let kernels = Kernels::new(Isa::best()).expect("the best kernels");
    let opts = |max_depth| RenderOptions {
        width: 64,
        height: 48,
        spp: 2,
        max_depth,
        ..RenderOptions::for_camera(&buffers.camera)
    };
    let (_, one) = render(&buffers, &opts(1), Some(&kernels));
    let (want, alone) = render(&buffers, &opts(2), None);
    let (got, two) = render(&buffers, &opts(2), Some(&kernels));
    assert_eq!(got, want, "the images");
    let kinds = |c: &RayCounts| (c.eye, c.shadow, c.reflected, c.refracted);
    assert_eq!(kinds(&two), kinds(&alone), "rays by kind");
    assert!(
        one.reflected == 0 && one.shadow - one.shadow_packed <= one.shadow / 50,
        "{one:?}"
    );
    assert!(two.reflected > 0 && two.refracted > 0, "{two:?}");
    // Lanes go on alone where a packet thins out (`packet::single`): most, not all.
    assert!(two.reflected_packed * 10 >= two.reflected * 9, "{two:?}");
    assert!(two.refracted_packed * 10 >= two.refracted * 9, "{two:?}");
    // Walked alone: a few lone lanes. With the refracted rays' shadow rays walked alone
    // too, 6% of them; without the mirror rays' shadow packets, about twice that.
    assert!(two.shadow - two.shadow_packed <= two.shadow / 50, "{two:?}");
    // At depth 3 the rays that leave the glass sphere go in packets too: with only those
    // that enter it, half of the refracted rays did.
    let (want, alone) = render(&buffers, &opts(3), None);
    let (got, three) = render(&buffers, &opts(3), Some(&kernels));
    assert_eq!(got, want, "the images at depth 3");
    assert_eq!(kinds(&three), kinds(&alone), "rays by kind at depth 3");
    assert!(three.refracted > two.refracted, "{three:?}");
    assert!(
        three.refracted_packed * 10 >= three.refracted * 9,
        "{three:?}"
    );
}

/// `gpurt SCENE --stats` on the CPU with `GPURT_SIMD` set to `simd`.
fn cli(dir: &Path, simd: &str, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_gpurt"))
        .args(args)
        .current_dir(dir)
        .env("GPURT_SIMD", simd)
        .output()
        .expect("gpurt runs")
}

/// The numbers of `--stats`' `rays` line: eye, packed, shadow, packed, reflected, packed,
/// refracted, packed.
fn ray_line(stderr: &str) -> Vec<u64> {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("rays "))
        .unwrap_or_else(|| panic!("no rays line in:\n{stderr}"));
    line.split(|c: char| !c.is_ascii_digit())
        .filter(|w| !w.is_empty())
        .map(|w| w.parse().expect("a count"))
        .collect()
}

#[test]
fn stats_count_rays_by_kind_and_those_in_packets() {
    let dir = crate::common::workdir("packet-stats");
    let scene = own_scenes().join("mirrors.nff");
    let scene = scene.to_str().expect("a UTF-8 path");
    let args = [
        scene,
        "-o",
        "out.png",
        "--width",
        "33",
        "--height",
        "21",
        "--spp",
        "2",
        "--backend",
        "cpu",
        "--stats",
    ];
    let with = cli(&dir, "", &args);
    let text = crate::common::stderr(&with);
    assert!(with.status.success(), "{text}");
    let packed = ray_line(&text);
    assert_eq!(packed.len(), 8, "{text}");
    assert_eq!(packed[0], 33 * 21 * 2, "{text}");
    // Camera rays go in packets but in a corner block of one pixel; shadow rays from
    // their hits and reflections off the flat mirrors too, the rest alone.
    assert!(
        packed[1] >= packed[0] - 2 && packed[3] > 0 && packed[5] > 0,
        "{text}"
    );
    assert!(
        text.contains(&format!(
            "packets of {} rays",
            Kernels::new(Isa::best()).expect("best").lanes()
        )),
        "{text}"
    );
    let without = cli(&dir, "none", &args);
    let text = crate::common::stderr(&without);
    let alone = ray_line(&text);
    assert!(text.contains("no packets"), "{text}");
    let kinds = |v: &[u64]| [v[0], v[2], v[4], v[6]];
    assert_eq!(kinds(&alone), kinds(&packed), "the same rays by kind");
    assert_eq!([alone[1], alone[3], alone[5], alone[7]], [0; 4], "{text}");
}

#[test]
fn a_bad_or_missing_instruction_set_is_an_error_with_no_image() {
    let dir = crate::common::workdir("packet-simd");
    let scene = own_scenes().join("spheres.nff");
    let scene = scene.to_str().expect("a UTF-8 path");
    let args = [
        scene,
        "-o",
        "out.png",
        "--width",
        "8",
        "--height",
        "8",
        "--backend",
        "cpu",
    ];
    let mut cases = vec![(
        "bogus",
        "expected none or one of avx512, avx2, sse, portable",
    )];
    if !Isa::Avx512.available() {
        cases.push(("avx512", "this processor lacks avx512"));
    }
    for (simd, message) in cases {
        let out = cli(&dir, simd, &args);
        let text = crate::common::stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{simd}: {text}");
        assert!(
            text.contains(&format!("GPURT_SIMD={simd}: {message}")),
            "{simd}: {text}"
        );
        assert!(
            !dir.join("out.png").exists(),
            "{simd}: an image was written"
        );
    }
    for simd in Isa::ALL
        .into_iter()
        .filter(|i| i.available())
        .map(Isa::name)
    {
        assert!(cli(&dir, simd, &args).status.success(), "{simd}");
    }
}
