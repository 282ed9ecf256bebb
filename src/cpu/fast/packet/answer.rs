//! What the packet API answers for each ray, as `closest_hit` and `transmission` answer
//! it: the walks' results (`walk.rs`) turned into hits and light, the node fetches shared
//! among the lanes, and the lanes the packet cannot answer traced again alone. Generic
//! over `Lanes`, as the walks are, so that each instruction set's entry (`x86_walks.rs`)
//! compiles this bookkeeping with its own instructions too: compiled for the baseline, a
//! bit count is a dozen instructions and the answers' loops a tenth of a shadow packet.

use glam::Vec3;

use super::lanes::{Lanes, MAX_LANES};
use super::rays::{Found, Rows};
use super::walk;
use crate::cpu::fast::wide_ray::{closest_hit, transmission};
use crate::cpu::intersect::lanes_of;
use crate::cpu::traverse::transmit_planes;
use crate::cpu::types::{Bindings, Hit};

/// Fewer lanes than this in a packet, and its rays are traced one at a time.
const MIN_LANES: u32 = 2;

/// `closest_hit(b, ray, tmin, tmax)` of every ray of `rows`, into `hits` (lane by lane;
/// `cost` 0, as the wide walk counts none; `nodes`, the packet's node fetches shared among
/// the lanes it traced, `share`, plus a lane's own walk if it took one). Returns the lanes
/// the packet answered; the others went alone: all of them where `b` has no wide tree or
/// the packet is nearly empty, rays from or towards infinity, and lanes that met two
/// surfaces at one distance.
#[inline(always)]
pub fn closest_hits<L: Lanes>(l: L, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
    let mut found = Found::default();
    let packed = match b.wide {
        Some(wide) if rows.lanes.count_ones() >= MIN_LANES => {
            walk::closest(l, b, wide, rows, rows.lanes, &mut found);
            found.traced & !found.tied
        }
        _ => 0,
    };
    let nodes = share(found.nodes, found.traced);
    // Field by field: a `Hit` built whole on the stack and copied stalls on store
    // forwarding, a tenth of a packet's time.
    for k in lanes_of(packed) {
        let h = &mut hits[k];
        (h.t, h.prim, h.u, h.v, h.cost, h.nodes) = (
            found.t[k],
            found.prim[k],
            found.u[k],
            found.v[k],
            0,
            nodes[k],
        );
    }
    for k in lanes_of(rows.lanes & !packed) {
        hits[k] = closest_hit(b, &rows.ray(k), rows.tmin[k], rows.tmax[k]);
        hits[k].nodes += nodes[k];
    }
    packed
}

/// `transmission(b, ray, tmax, _, hint)` of every ray of `rows` (whose `tmin` must be 0),
/// into `light`, and the node fetches of each lane into `nodes` (as `closest_hits` counts
/// them): `hint`, the primitive that blocked the last packet to the same light, is tested
/// against every lane before the walk, and is set to the last that blocks one of these.
/// Returns the lanes the occlusion packet answered: blocked, crossing nothing, or crossing
/// surfaces of one material that transmits light; the planes are each lane's own, and
/// lanes crossing two such materials go alone, as do all where the packet cannot (see
/// `closest_hits`).
#[inline(always)]
pub fn transmissions<L: Lanes>(
    l: L,
    b: &Bindings,
    rows: &Rows,
    light: &mut [Vec3; MAX_LANES],
    nodes: &mut [u32; MAX_LANES],
    hint: &mut Option<u32>,
) -> u32 {
    // The planes first, lane by lane (most scenes have none: all lanes open).
    let mut open = if b.planes.is_empty() { rows.lanes } else { 0 };
    light.fill(Vec3::ONE);
    for k in lanes_of(rows.lanes & !open) {
        match transmit_planes(b, &rows.ray(k), rows.tmax[k]) {
            Some(t) => {
                light[k] = t;
                open |= 1 << k;
            }
            None => light[k] = Vec3::ZERO,
        }
    }
    let (found, packed) = match b.wide {
        Some(wide) if open.count_ones() >= MIN_LANES => {
            let found = walk::occluded(l, b, wide, rows, open, *hint);
            if found.blocker.is_some() {
                *hint = found.blocker;
            }
            let packed = found.traced & !found.mixed;
            (found, packed)
        }
        _ => Default::default(),
    };
    *nodes = share(found.nodes, found.traced);
    for k in lanes_of(found.blocked & packed) {
        light[k] = Vec3::ZERO;
    }
    for k in lanes_of(found.transmits & !found.blocked & packed) {
        // `transmission`'s product: the same factor each time, so in any order.
        let m = &b.materials[found.material[k] as usize];
        for _ in 0..found.crossings[k] {
            light[k] *= m.t * m.color;
        }
    }
    for k in lanes_of(open & !packed) {
        light[k] = transmission(b, &rows.ray(k), rows.tmax[k], &mut nodes[k], hint);
    }
    packed
}

/// A packet's `nodes` fetches shared among its `lanes` (a bit each), so that they add up
/// to the packet's: a node fetched once for the packet serves each of its rays, and the
/// count per ray is the memory traffic a ray cost (`counters`). The first lanes take the
/// remainder; lanes outside `lanes` take none.
#[inline(always)]
fn share(nodes: u32, lanes: u32) -> [u32; MAX_LANES] {
    let mut out = [0; MAX_LANES];
    let n = lanes.count_ones();
    if let Some(each) = nodes.checked_div(n) {
        for (i, k) in lanes_of(lanes).enumerate() {
            out[k] = each + u32::from((i as u32) < nodes % n);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A packet's fetches are all counted, once, and shared within one a lane.
    #[test]
    fn a_packets_node_fetches_are_shared_and_add_up() {
        for (nodes, lanes) in [(0, 0b1011), (7, 0), (7, 0b1), (10, 0b1011), (37, 0xffff)] {
            let s = share(nodes, lanes);
            let total: u32 = s.iter().sum();
            assert_eq!(
                total,
                if lanes == 0 { 0 } else { nodes },
                "{nodes} over {lanes:b}"
            );
            let mine: Vec<u32> = lanes_of(lanes).map(|k| s[k]).collect();
            if let (Some(lo), Some(hi)) = (mine.iter().min(), mine.iter().max()) {
                assert!(hi - lo <= 1, "{mine:?}");
            }
            for (k, &n) in s.iter().enumerate() {
                assert!(
                    lanes & 1 << k != 0 || n == 0,
                    "lane {k} is not in the packet"
                );
            }
        }
    }
}
