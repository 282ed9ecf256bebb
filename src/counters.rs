//! What a frame's rays cost, counted when asked (`--stats`, `gpurt bench`): the rays
//! traced and the BVH nodes their walks fetched, by kind of ray, with the bytes a node
//! fetch reads on the walk that fetched it. The GPU counts per pixel
//! (`GpuPixelCounts`, the `COUNTERS` specialisation) and the host adds the pixels up; the
//! CPU counts the same things on its own walk (`cpu::RayCounts`).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::gpu_types::{
    GpuCwideNode, GpuNode, GpuPixelCounts, GpuQwideNode, GpuWideNode, POOL_SIDE, TRAVERSAL_CWIDE,
    TRAVERSAL_QWIDE, TRAVERSAL_WIDE, WORKGROUP_INVOCATIONS, WORKGROUP_SIDE,
};

/// The kinds of ray counted apart: eye rays, shadow rays, and reflected and refracted rays.
pub const KINDS: [&str; 3] = ["eye", "shadow", "secondary"];

/// The pixels, across and down, that one 32-lane warp of a GPU traces: a workgroup's 64
/// invocations cover 8x8 pixels in 4x2 blocks (`main` in shaders/pixel.wgsl), so its
/// invocations 0 to 31 trace the top 8x4 pixels and 32 to 63 the bottom ones. Tiles and
/// bands start on multiples of 8 pixels, so a frame's warps tile it from its corner.
pub const WARP_PIXELS: [usize; 2] = [8, 4];

/// Lanes of a warp (`WARP_PIXELS`): NVIDIA's warp.
const WARP_LANES: u64 = 32;

/// Rays and node fetches of a frame (or part of one), by kind (`KINDS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub rays: [u64; 3],
    pub nodes: [u64; 3],
    /// Bytes one node fetch reads: the size of the node the walk reads.
    pub node_bytes: u64,
    /// Over the GPU's warps (`WARP_PIXELS`), kind by kind: the node fetches of the warp's
    /// pixels, and 32 times those of its pixel that fetched the most. A warp walks for as
    /// long as its busiest lane does, so their ratio bounds the share of its lanes that
    /// have a node to fetch (`lanes_busy`). Counted from the GPU's pixels only.
    pub warp_nodes: [u64; 3],
    pub warp_room: [u64; 3],
    /// Over the same warps, rays of every kind together: 32 times the node fetches of
    /// the warp's busiest lane, one pixel a lane as `main` traces them (`warp_room_all`),
    /// and with each `POOL_SIDE` square's pixels handed out to a workgroup's lanes as
    /// `pooled` hands them out (`pool_room`, `pooled_lanes`). A model: a warp's lanes
    /// taken to walk in step, its time that of its lane that fetches the most.
    pub warp_room_all: u64,
    pub pool_room: u64,
}

/// Where pixel `p` of a pooled workgroup's square of `side` pixels lies in it, as
/// `pool_pixel` in shaders/pixel.wgsl lays it out: 8x8 blocks in row order, each in 4x2
/// runs of lanes.
fn pool_offset(p: usize, side: usize) -> (usize, usize) {
    let blocks = side / WORKGROUP_SIDE as usize;
    let (sub, q) = (p / 64, p % 64);
    let (run, lane) = (q / 8, q % 8);
    (
        (sub % blocks) * 8 + (run % 2) * 4 + lane % 4,
        (sub / blocks) * 8 + (run / 2) * 2 + lane / 4,
    )
}

/// Node fetches of each lane of a `pooled` workgroup handed `costs` (its square's
/// pixels' fetches, in the pool's order; `None` for a pixel it does not trace): each lane
/// its own pixel first, then each next pixel to the lane that is free first (the lowest
/// numbered of those free at once), as lanes take them from the counter.
fn pooled_lanes(costs: impl Iterator<Item = Option<u64>>) -> [u64; 64] {
    const LANES: usize = WORKGROUP_INVOCATIONS as usize;
    let mut lanes = [0u64; LANES];
    let mut free = BinaryHeap::new();
    for (p, cost) in costs.enumerate() {
        let Some(cost) = cost else { continue };
        let lane = if p < LANES {
            p
        } else {
            if free.is_empty() {
                free.extend((0..LANES).map(|l| Reverse((lanes[l], l))));
            }
            let Reverse((_, l)) = free.pop().expect("64 lanes");
            free.push(Reverse((lanes[l] + cost, l)));
            l
        };
        lanes[lane] += cost;
    }
    lanes
}

impl Counters {
    /// No counts yet, on a walk whose nodes are `node_bytes` long.
    pub fn new(node_bytes: u64) -> Self {
        Counters {
            node_bytes,
            ..Default::default()
        }
    }

    /// Adds one pixel's counts from the GPU.
    pub fn add_pixel(&mut self, p: &GpuPixelCounts) {
        let rays = [p.eye_rays, p.shadow_rays, p.secondary_rays];
        let nodes = [p.eye_nodes, p.shadow_nodes, p.secondary_nodes];
        for k in 0..3 {
            self.rays[k] += u64::from(rays[k]);
            self.nodes[k] += u64::from(nodes[k]);
        }
    }

    /// Adds a band of the GPU's pixels, `width` to a row, whose first row is a multiple
    /// of 8, but for those whose index is in `skip` (sorted; they are counted elsewhere):
    /// each pixel, and each warp of them (`warp_nodes`).
    pub fn add_band(&mut self, px: &[GpuPixelCounts], width: usize, skip: &[usize]) {
        let [across, down] = WARP_PIXELS;
        let width = width.max(1);
        debug_assert_eq!(px.len() % width, 0, "a band is whole rows");
        let rows = px.len() / width;
        for y0 in (0..rows).step_by(down) {
            for x0 in (0..width).step_by(across) {
                let (mut sum, mut most, mut most_all) = ([0u64; 3], [0u64; 3], 0);
                for y in y0..(y0 + down).min(rows) {
                    for i in (x0..(x0 + across).min(width)).map(|x| y * width + x) {
                        if skip.binary_search(&i).is_ok() {
                            continue;
                        }
                        let p = &px[i];
                        self.add_pixel(p);
                        let nodes = [p.eye_nodes, p.shadow_nodes, p.secondary_nodes];
                        for k in 0..3 {
                            sum[k] += u64::from(nodes[k]);
                            most[k] = most[k].max(u64::from(nodes[k]));
                        }
                        most_all = most_all.max(pixel_nodes(p));
                    }
                }
                for k in 0..3 {
                    self.warp_nodes[k] += sum[k];
                    self.warp_room[k] += WARP_LANES * most[k];
                }
                self.warp_room_all += WARP_LANES * most_all;
            }
        }
        // The same pixels in `pooled`'s squares, from the band's corner.
        let side = POOL_SIDE as usize;
        for y0 in (0..rows).step_by(side) {
            for x0 in (0..width).step_by(side) {
                let costs = (0..side * side).map(|p| {
                    let (x, y) = pool_offset(p, side);
                    let (x, y) = (x0 + x, y0 + y);
                    let i = y * width + x;
                    (x < width && y < rows && skip.binary_search(&i).is_err())
                        .then(|| pixel_nodes(&px[i]))
                });
                let lanes = pooled_lanes(costs);
                let warps = lanes.chunks(WARP_LANES as usize);
                self.pool_room +=
                    WARP_LANES * warps.map(|w| w.iter().max().unwrap_or(&0)).sum::<u64>();
            }
        }
    }

    /// Adds counts of the same walk.
    pub fn add(&mut self, o: &Counters) {
        for k in 0..3 {
            self.rays[k] += o.rays[k];
            self.nodes[k] += o.nodes[k];
            self.warp_nodes[k] += o.warp_nodes[k];
            self.warp_room[k] += o.warp_room[k];
        }
        self.warp_room_all += o.warp_room_all;
        self.pool_room += o.pool_room;
    }

    /// At most what share of a warp's lanes have a node to fetch while it walks rays of
    /// kind `k`, were its lanes to walk in step (`warp_nodes`; `None` where nothing was
    /// counted by warps: the CPU's counts, or no node fetched).
    pub fn lanes_busy(&self, k: usize) -> Option<f64> {
        (self.warp_room[k] > 0).then(|| self.warp_nodes[k] as f64 / self.warp_room[k] as f64)
    }

    /// At most what share of a warp's lanes have a node to fetch over a frame's rays of
    /// every kind, one pixel a lane (`main`) and with pixels pooled (`pooled`), were its
    /// lanes to walk in step (`warp_room_all`, `pool_room`; `None` where nothing was
    /// counted by warps).
    pub fn lanes_busy_all(&self) -> Option<(f64, f64)> {
        let nodes: u64 = self.warp_nodes.iter().sum();
        (self.warp_room_all > 0 && self.pool_room > 0).then(|| {
            (
                nodes as f64 / self.warp_room_all as f64,
                nodes as f64 / self.pool_room as f64,
            )
        })
    }

    /// Every ray counted.
    pub fn total_rays(&self) -> u64 {
        self.rays.iter().sum()
    }

    /// Nodes fetched per ray of kind `k` (0 where no ray of that kind was traced).
    pub fn nodes_per_ray(&self, k: usize) -> f64 {
        self.nodes[k] as f64 / self.rays[k].max(1) as f64
    }

    /// Node bytes fetched per ray of kind `k`.
    pub fn bytes_per_ray(&self, k: usize) -> f64 {
        self.nodes_per_ray(k) * self.node_bytes as f64
    }

    /// One line per kind that has rays, for `--stats`, each headed by `who` (the
    /// backend) and the kind: rays, nodes and node bytes per ray.
    pub fn report(&self, who: &str) -> Vec<String> {
        let all = self.lanes_busy_all().map(|(main, pooled)| {
            format!(
                "{:<11} at most {:.0}% of a warp's lanes busy, {:.0}% with {POOL_SIDE}x{POOL_SIDE} \
                 pixels a workgroup shared out (GPURT_KERNELS=pooled)",
                format!("{who} all"),
                100.0 * main,
                100.0 * pooled
            )
        });
        (0..3)
            .filter(|&k| self.rays[k] > 0)
            .map(|k| {
                let busy = self.lanes_busy(k).map_or(String::new(), |b| {
                    format!(", at most {:.0}% of a warp's lanes busy", 100.0 * b)
                });
                format!(
                    "{:<11} {} rays, {:.1} nodes/ray, {:.0} node bytes/ray ({} B a node){busy}",
                    format!("{who} {}", KINDS[k]),
                    self.rays[k],
                    self.nodes_per_ray(k),
                    self.bytes_per_ray(k),
                    self.node_bytes
                )
            })
            .chain(all)
            .collect()
    }
}

/// A GPU pixel's node fetches, every kind of ray together.
fn pixel_nodes(p: &GpuPixelCounts) -> u64 {
    [p.eye_nodes, p.shadow_nodes, p.secondary_nodes]
        .map(u64::from)
        .iter()
        .sum()
}

/// Bytes one node fetch of the GPU's walk `traversal` reads: a binary node for the
/// single and pairs walks (pairs fetches two at a time, counted as two).
pub fn gpu_node_bytes(traversal: u32) -> u64 {
    (match traversal {
        TRAVERSAL_WIDE => size_of::<GpuWideNode>(),
        TRAVERSAL_CWIDE => size_of::<GpuCwideNode>(),
        TRAVERSAL_QWIDE => size_of::<GpuQwideNode>(),
        _ => size_of::<GpuNode>(),
    }) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_add_up_by_kind_and_per_ray_figures_follow() {
        let mut c = Counters::new(80);
        let p = GpuPixelCounts {
            eye_rays: 2,
            eye_nodes: 30,
            shadow_rays: 4,
            shadow_nodes: 20,
            secondary_rays: 0,
            secondary_nodes: 0,
            _pad: [0; 2],
        };
        c.add_pixel(&p);
        c.add_pixel(&p);
        assert_eq!((c.rays, c.nodes), ([4, 8, 0], [60, 40, 0]));
        assert_eq!(c.total_rays(), 12);
        assert_eq!(c.nodes_per_ray(0), 15.0);
        assert_eq!(c.bytes_per_ray(1), 400.0);
        assert_eq!(c.nodes_per_ray(2), 0.0);
        let lines = c.report("gpu");
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(lines[0].starts_with("gpu eye "), "{lines:?}");
        assert!(lines[0].contains("15.0 nodes/ray") && lines[0].contains("1200 node bytes/ray"));
        assert!(
            !lines[0].contains("warp"),
            "the CPU's counts have no warps: {lines:?}"
        );
    }

    /// A band of 16x8 pixels is four warps of 8x4: one eye node everywhere, in the
    /// top-left warp one pixel of 8 secondary nodes and one skipped (counted elsewhere),
    /// in the bottom-right one a pixel of 50 eye nodes.
    #[test]
    fn a_band_is_counted_by_pixel_and_by_warp() {
        let eye = GpuPixelCounts {
            eye_rays: 1,
            eye_nodes: 1,
            ..Default::default()
        };
        let mut px = vec![eye; 16 * 8];
        px[16 + 3].secondary_rays = 1;
        px[16 + 3].secondary_nodes = 8;
        px[5 * 16 + 12].eye_nodes = 50; // in warp (1, 1)
        let mut c = Counters::new(112);
        c.add_band(&px, 16, &[3 * 16 + 4]); // in warp (0, 0)
        assert_eq!(c.rays, [127, 0, 1]);
        assert_eq!(c.nodes, [127 + 49, 0, 8]);
        // Warp (0, 0) has 31 pixels of one eye node: 31 of room 32. The others 32 of 32,
        // but the one whose pixel fetched 50: 81 of room 32 x 50.
        assert_eq!(c.warp_nodes, [31 + 32 + 32 + 81, 0, 8]);
        assert_eq!(c.warp_room, [32 * 3 + 32 * 50, 0, 32 * 8]);
        assert_eq!(c.lanes_busy(2), Some(1.0 / 32.0));
        assert_eq!(c.lanes_busy(1), None);
        let lines = c.report("gpu");
        assert!(
            lines[1].ends_with("at most 3% of a warp's lanes busy"),
            "{lines:?}"
        );
        let mut twice = c;
        twice.add(&c);
        assert_eq!(twice.warp_room, c.warp_room.map(|r| 2 * r));
    }

    /// A pooled square's pixels: each once, the first 32 (a warp's first pixels) the
    /// 8x4 of `WARP_PIXELS`, the first 64 one 8x8 block.
    #[test]
    fn a_pooled_square_is_laid_out_as_the_shader_lays_it_out() {
        for side in [8, 16, 24] {
            let mut seen = vec![0; side * side];
            for p in 0..side * side {
                let (x, y) = pool_offset(p, side);
                seen[y * side + x] += 1;
                if p < 32 {
                    assert!(x < WARP_PIXELS[0] && y < WARP_PIXELS[1], "{p}: {x}, {y}");
                } else if p < 64 {
                    assert!(x < 8 && (4..8).contains(&y), "{p}: {x}, {y}");
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "side {side}");
        }
        assert_eq!(pool_offset(8, 16), (4, 0));
        assert_eq!(pool_offset(64, 16), (8, 0));
        assert_eq!(pool_offset(128, 16), (0, 8));
    }

    /// A band of 16x16 pixels of one node each but one of 100 (at the corner) and one of
    /// 40 (the last pixel handed out). `main`: eight warps, the corner's room 32 x 100,
    /// the last's 32 x 40, the others 32 each. `pooled`: lane 0 keeps the corner's pixel;
    /// lanes 1 to 63 take the square's other pixels as they come free, so the last (the
    /// 255th) goes to lane 3 after three more rounds: lanes 1 and 2 end at 5, lane 3 at
    /// 44, lanes 4 to 63 at 4. The first warp's room is 32 x 100 (lane 3's 44 within
    /// it), the second's 32 x 4.
    #[test]
    fn a_pooled_square_hands_its_pixels_to_the_lanes_free_first() {
        let one = GpuPixelCounts {
            eye_rays: 1,
            eye_nodes: 1,
            ..Default::default()
        };
        let mut px = vec![one; 16 * 16];
        px[0].eye_nodes = 100;
        let (x, y) = pool_offset(255, 16);
        px[y * 16 + x].shadow_rays = 1;
        px[y * 16 + x].shadow_nodes = 39;
        let mut c = Counters::new(112);
        c.add_band(&px, 16, &[]);
        let nodes = 254 + 100 + 40;
        assert_eq!(c.warp_nodes.iter().sum::<u64>(), nodes);
        assert_eq!(c.warp_room_all, 32 * (100 + 40 + 6));
        assert_eq!(c.pool_room, 32 * (100 + 4));
        let (main, pooled) = c.lanes_busy_all().expect("counted by warps");
        assert_eq!(main, nodes as f64 / (32.0 * 146.0));
        assert_eq!(pooled, nodes as f64 / (32.0 * 104.0));
        let lines = c.report("gpu");
        assert!(
            lines.last().unwrap().starts_with("gpu all")
                && lines
                    .last()
                    .unwrap()
                    .contains("8% of a warp's lanes busy, 12% with 16x16"),
            "{lines:?}"
        );
    }
}
