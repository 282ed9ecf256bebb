//! What a frame's rays cost, counted when asked (`--stats`, `gpurt bench`): the rays
//! traced and the BVH nodes their walks fetched, by kind of ray, with the bytes a node
//! fetch reads on the walk that fetched it. The GPU counts per pixel
//! (`GpuPixelCounts`, the `COUNTERS` specialisation) and the host adds the pixels up; the
//! CPU counts the same things on its own walk (`cpu::RayCounts`).

use crate::gpu_types::{
    GpuCwideNode, GpuNode, GpuPixelCounts, GpuWideNode, TRAVERSAL_CWIDE, TRAVERSAL_WIDE,
};

/// The kinds of ray counted apart: eye rays, shadow rays, and reflected and refracted rays.
pub const KINDS: [&str; 3] = ["eye", "shadow", "secondary"];

/// The pixels, across and down, that one 32-lane warp of a GPU traces: a workgroup's 64
/// invocations cover 8x8 pixels in 4x2 blocks (`main` in shaders/main.wgsl), so its
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
                let (mut sum, mut most) = ([0u64; 3], [0u64; 3]);
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
                    }
                }
                for k in 0..3 {
                    self.warp_nodes[k] += sum[k];
                    self.warp_room[k] += WARP_LANES * most[k];
                }
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
    }

    /// At most what share of a warp's lanes have a node to fetch while it walks rays of
    /// kind `k`, were its lanes to walk in step (`warp_nodes`; `None` where nothing was
    /// counted by warps: the CPU's counts, or no node fetched).
    pub fn lanes_busy(&self, k: usize) -> Option<f64> {
        (self.warp_room[k] > 0).then(|| self.warp_nodes[k] as f64 / self.warp_room[k] as f64)
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
            .collect()
    }
}

/// Bytes one node fetch of the GPU's walk `traversal` reads: a binary node for the
/// single and pairs walks (pairs fetches two at a time, counted as two).
pub fn gpu_node_bytes(traversal: u32) -> u64 {
    (match traversal {
        TRAVERSAL_WIDE => size_of::<GpuWideNode>(),
        TRAVERSAL_CWIDE => size_of::<GpuCwideNode>(),
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
}
