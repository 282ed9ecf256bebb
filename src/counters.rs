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

/// Rays and node fetches of a frame (or part of one), by kind (`KINDS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub rays: [u64; 3],
    pub nodes: [u64; 3],
    /// Bytes one node fetch reads: the size of the node the walk reads.
    pub node_bytes: u64,
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

    /// Adds counts of the same walk.
    pub fn add(&mut self, o: &Counters) {
        for k in 0..3 {
            self.rays[k] += o.rays[k];
            self.nodes[k] += o.nodes[k];
        }
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
                format!(
                    "{:<11} {} rays, {:.1} nodes/ray, {:.0} node bytes/ray ({} B a node)",
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
    }
}
