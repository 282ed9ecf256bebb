//! The packet walks of the eight-wide tree: closest hit and occlusion, written once over
//! `Lanes` and compiled for each instruction set (`x86.rs`, `mod.rs`).
//!
//! The packet goes down the tree together, a stack entry holding per lane where the ray
//! enters the child (infinity for lanes that do not reach it): a popped entry's lanes are
//! those whose entry is still within their nearest hit, as the single-ray walk culls a
//! popped child. At a node the interval test (`frustum.rs`) culls the children no ray of
//! the packet can reach, then each child left is tested against every active lane with
//! `intersect::overlaps`' arithmetic in the single-ray walk's order (`child_slab`), and the
//! children reached are pushed farthest first by the packet's entry bound, so that the
//! nearest is taken next. (The single-ray walk's `Slabs::test` takes the widening into the
//! inverse direction instead, which gains a packet nothing and costs it the wider rays:
//! the two differ by a few ulps at the widening's edge, where both overlap every box that
//! holds a hit.) Where few lanes are left at a node (`alone`), each walks its subtree by
//! itself (`single.rs`) and the packet goes on without them.
//!
//! A lane therefore enters a leaf exactly when its own slab test lets it in, against its
//! own nearest hit, and tests the leaf's primitives with the same arithmetic: it finds the
//! nearest hit the single-ray walk finds, and the primitive, but where two surfaces lie at
//! exactly the same distance (`Found::tied`); a shadow lane finds the same crossings, the
//! set of leaves it enters not depending on the order.

use std::cell::Cell;
use std::mem::MaybeUninit;

use super::frustum::Frustum;
use super::lanes::Lanes;
use super::leaf::{self, Best};
use super::rays::{Found, Occluded, Rays, Rows};
use super::single::{self, LaneHit};
use crate::bvh::wide::{EMPTY, Link, Tree, WIDTH, WideNode};
use crate::cpu::fast::wide::lane;
use crate::cpu::intersect::lanes_of;
use crate::cpu::types::Bindings;
use crate::gpu_types::{SLAB_WIDEN, TRAVERSAL_STACK};

/// Lanes of a node at or below which each walks the node's subtree alone: a quarter of the
/// packet (two of eight, four of sixteen, one of four).
fn alone<L: Lanes>() -> u32 {
    (L::N / 4) as u32
}

/// The same for the occlusion walk, whose lanes stop at any opaque crossing: at most two
/// lanes (of sixteen, eight; one of four). Three or four of sixteen shadow lanes walk on
/// together faster than alone (AVX-512: gears-4, balls-4, mount-7 4 to 6% more shadow rays
/// a second, teapot-6 the same; whole renders the same); with eight lanes a quarter is two.
fn alone_occluded<L: Lanes>() -> u32 {
    (L::N / 4).min(2) as u32
}

/// A child waiting on the stack, and the lanes that reach it: for the closest-hit walk,
/// where each enters its box (infinity for those that do not), to be culled again by the
/// nearest hit found meanwhile; for the occlusion walk, whose intervals never shrink, just
/// the lanes (a bit each), which keeps its stack a tenth of the size.
#[derive(Clone, Copy)]
struct Entry<R> {
    link: Link,
    reach: R,
}

/// Entries a walk can hold: as `wide.rs`'s stack.
const STACK: usize = TRAVERSAL_STACK * (WIDTH - 1) + 1;

/// `intersect::overlaps` of child `c` of `n` for every lane, in `Slabs::test`'s order:
/// where each enters it, clamped to `tmin`, and the lanes that overlap it within
/// `[tmin, tmax]`.
#[inline(always)]
pub(super) fn child_slab<L: Lanes>(
    l: L,
    r: &Rays<L>,
    n: &WideNode,
    c: usize,
    tmax: L::F,
) -> (L::F, L::M) {
    let mut near = [r.tmin; 3];
    let mut far = [tmax; 3];
    for a in 0..3 {
        let t_lo = l.mul(l.sub(l.splat(lane(&n.lo[a], c)), r.o[a]), r.inv[a]);
        let t_hi = l.mul(l.sub(l.splat(lane(&n.hi[a], c)), r.o[a]), r.inv[a]);
        near[a] = l.select(r.neg[a], t_hi, t_lo);
        far[a] = l.select(r.neg[a], t_lo, t_hi);
    }
    // The single walk's order: x, y, z, then the interval.
    let near = l.max(l.max(l.max(near[0], near[1]), near[2]), r.tmin);
    let far = l.min(l.min(l.min(far[0], far[1]), far[2]), tmax);
    (near, l.le(near, l.mul(far, l.splat(SLAB_WIDEN))))
}

/// The stack, not zeroed (as `wide.rs`'s): only entries below `sp` are read. Its entries
/// are in the thread's `Room`, which it holds until it is dropped.
struct Stack<'a, R> {
    entries: &'a mut [MaybeUninit<Entry<R>>; STACK],
    sp: usize,
}

/// Bytes of a `Room`: `STACK` entries of the largest kind, AVX-512's closest-hit walk's
/// (a 64-byte `reach`, aligned to 64: 128 bytes an entry).
const ROOM: usize = STACK * 128;

/// Room for a walk's stack, one a thread, which each packet walk on it takes in turn (they
/// never nest). In the walk's frame, the stack made the frame 57 KB with AVX-512 (28 KB
/// with AVX2), which the compiler's stack probes (which keep a frame from jumping the
/// guard page) touched a page at a time at every call: teapot-6's primary packets took
/// 9% longer (`examples/rays`, one thread).
#[repr(C, align(64))]
struct Room([MaybeUninit<u8>; ROOM]);

/// This thread's `Room` (made on its first walk, freed with the thread), and whether a
/// stack holds it.
struct Rooms {
    room: Cell<*mut Room>,
    taken: Cell<bool>,
}

impl Drop for Rooms {
    fn drop(&mut self) {
        let room = self.room.get();
        if !room.is_null() {
            // SAFETY: made by `Box::into_raw` in `Stack::new`, and freed only here.
            drop(unsafe { Box::from_raw(room) });
        }
    }
}

thread_local! {
    static ROOMS: Rooms = const {
        Rooms {
            room: Cell::new(std::ptr::null_mut()),
            taken: Cell::new(false),
        }
    };
}

impl<R: Copy> Stack<'_, R> {
    /// An empty stack in this thread's room.
    #[inline(always)]
    fn new() -> Self {
        const {
            assert!(size_of::<[Entry<R>; STACK]>() <= ROOM && align_of::<Entry<R>>() <= 64);
        }
        let room = ROOMS.with(|rooms| {
            assert!(!rooms.taken.replace(true), "a packet walk inside another");
            if rooms.room.get().is_null() {
                // SAFETY: a `Room` is bytes that need no initialising.
                let room = unsafe { Box::<Room>::new_uninit().assume_init() };
                rooms.room.set(Box::into_raw(room));
            }
            rooms.room.get()
        });
        // SAFETY: the room outlives every walk on its thread (it is freed with the
        // thread), is aligned to 64 and holds the entries (checked above), which need no
        // initialising; `taken` makes this the room's one borrow until the stack drops.
        let entries = unsafe { &mut *room.cast() };
        Stack { entries, sp: 0 }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<Entry<R>> {
        (self.sp > 0).then(|| {
            self.sp -= 1;
            // SAFETY: entries below the old `sp` have been written.
            unsafe { self.entries[self.sp].assume_init() }
        })
    }

    /// Pushes `e`, keeping the run pushed since `base` sorted by `keys` (kept beside the
    /// run), farthest at the bottom.
    #[inline(always)]
    fn push_sorted(&mut self, base: usize, keys: &mut [f32; WIDTH], e: Entry<R>, key: f32) {
        let mut j = self.sp;
        while j > base && keys[j - 1 - base] < key {
            self.entries[j] = self.entries[j - 1];
            keys[j - base] = keys[j - 1 - base];
            j -= 1;
        }
        self.entries[j] = MaybeUninit::new(e);
        keys[j - base] = key;
        self.sp += 1;
    }

    #[inline(always)]
    fn push(&mut self, e: Entry<R>) {
        self.entries[self.sp] = MaybeUninit::new(e);
        self.sp += 1;
    }
}

impl<R> Drop for Stack<'_, R> {
    fn drop(&mut self) {
        ROOMS.with(|rooms| rooms.taken.set(false));
    }
}

/// The nearest hit of each lane of `rows` (planes first, then the tree), into `found`.
#[inline(always)]
pub fn closest<L: Lanes>(
    l: L,
    b: &Bindings,
    wide: &Tree,
    rows: &Rows,
    lanes: u32,
    found: &mut Found,
) {
    let r = Rays::new(l, rows);
    let lanes = lanes & r.finite;
    found.traced = lanes;
    let mut best = Best::new(l, rows);
    best.planes(l, b, &r, lanes);
    if b.globals.n_nodes > 0 {
        closest_tree(l, b, wide, rows, lanes, &r, &mut best, found);
    }
    best.store(l, found);
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn closest_tree<L: Lanes>(
    l: L,
    b: &Bindings,
    wide: &Tree,
    rows: &Rows,
    packet: u32,
    r: &Rays<L>,
    best: &mut Best<L>,
    found: &mut Found,
) {
    let inf = l.splat(f32::INFINITY);
    let widen = l.splat(SLAB_WIDEN);
    let frustum = Frustum::new(l, r, packet);
    let tmin_lo = l.min_of(r.tmin, packet);
    let mut tmax_hi = l.max_of(best.t, packet);
    let mut stack = Stack::new();
    let mut next = Some(Entry {
        link: Link::ROOT,
        reach: l.select(l.mask(packet), r.tmin, inf),
    });
    while let Some(e) = next {
        let lanes = l.bits(l.le(e.reach, l.mul(best.t, widen)));
        if lanes == 0 {
        } else if e.link.count() > 0 {
            // An empty lane leads nowhere (reached only through NaN distances).
            if e.link.count() != EMPTY {
                let leaf = (e.link.first(), e.link.count());
                leaf::closest(l, b, r, rows, leaf, lanes, best);
                tmax_hi = l.max_of(best.t, packet);
            }
        } else if lanes.count_ones() <= alone::<L>() {
            best.store(l, found);
            for k in lanes_of(lanes) {
                let mut h = LaneHit {
                    t: found.t[k],
                    prim: found.prim[k],
                    u: found.u[k],
                    v: found.v[k],
                    tied: found.tied & (1 << k) != 0,
                };
                let interval = (rows.tmin[k], rows.tmax[k]);
                let (ray, inv) = (rows.ray(k), r.inv_of(k));
                single::closest_from(
                    b,
                    wide,
                    &ray,
                    inv,
                    interval,
                    e.link,
                    &mut h,
                    &mut found.nodes,
                );
                (found.t[k], found.prim[k], found.u[k], found.v[k]) = (h.t, h.prim, h.u, h.v);
                found.tied |= u32::from(h.tied) << k;
            }
            best.reload(l, found);
            tmax_hi = l.max_of(best.t, packet);
        } else {
            // SAFETY: `e` is the root (every tree has one) or came from one of the tree's
            // nodes, and leads to an inner child.
            let n = unsafe { e.link.node(wide) };
            found.nodes += 1;
            let (children, keys) = frustum.cull(n, tmin_lo, tmax_hi);
            let active = l.mask(lanes);
            let base = stack.sp;
            let mut run_keys = [0.0; WIDTH];
            for c in lanes_of(children) {
                let (near, hit) = child_slab(l, r, n, c, best.t);
                let hit = l.and(hit, active);
                if l.bits(hit) != 0 {
                    let entry = Entry {
                        link: n.link(c),
                        reach: l.select(hit, near, inf),
                    };
                    stack.push_sorted(base, &mut run_keys, entry, lane(&keys, c));
                }
            }
        }
        next = stack.pop();
    }
}

/// Which shadow rays of `rows` (intervals `(0, tmax)`) the tree blocks, and the surfaces
/// that transmit light each of the others crosses (`Occluded`).
#[inline(always)]
pub fn occluded<L: Lanes>(
    l: L,
    b: &Bindings,
    wide: &Tree,
    rows: &Rows,
    packet: u32,
    hint: Option<u32>,
) -> Occluded {
    let r = Rays::new(l, rows);
    let packet = packet & r.finite;
    let mut out = Occluded {
        traced: packet,
        ..Occluded::default()
    };
    if b.globals.n_nodes == 0 || packet == 0 {
        return out;
    }
    let mut alive = packet;
    // The primitive that blocked the last packet to the same light, first: lanes it blocks
    // walk no further. Only an opaque one, whose crossings the walk cannot meet again
    // to count twice.
    let opaque = |p: u32| b.materials[b.prims[p as usize].material() as usize].t <= 0.0;
    if let Some(p) = hint.filter(|&p| opaque(p)) {
        leaf::occlusion(l, b, &r, rows, (p, 1), packet, &mut out);
        alive = out.open(alive);
        if alive == 0 {
            return out;
        }
    }
    let tmax = l.load(&rows.tmax);
    let frustum = Frustum::new(l, &r, packet);
    let tmin_lo = l.min_of(r.tmin, packet);
    let tmax_hi = l.max_of(tmax, packet);
    let mut stack = Stack::new();
    let mut next = Some(Entry {
        link: Link::ROOT,
        reach: alive,
    });
    while let Some(e) = next {
        let lanes = e.reach & alive;
        if lanes == 0 {
        } else if e.link.count() > 0 {
            if e.link.count() != EMPTY {
                let leaf = (e.link.first(), e.link.count());
                leaf::occlusion(l, b, &r, rows, leaf, lanes, &mut out);
                alive = out.open(alive);
            }
        } else if lanes.count_ones() <= alone_occluded::<L>() {
            for k in lanes_of(lanes) {
                let (ray, inv) = (rows.ray(k), r.inv_of(k));
                single::occluded_from(b, wide, &ray, inv, rows.tmax[k], e.link, k, &mut out);
            }
            alive = out.open(alive);
        } else {
            // SAFETY: `e` is the root (every tree has one) or came from one of the tree's
            // nodes, and leads to an inner child.
            let n = unsafe { e.link.node(wide) };
            out.nodes += 1;
            let (children, _) = frustum.cull(n, tmin_lo, tmax_hi);
            let active = l.mask(lanes);
            for c in lanes_of(children) {
                // A lane's interval never shrinks here, so that the lanes reaching a child
                // are all the stack keeps: the closest-hit walk's test when the entry is
                // popped (its entry within `tmax * SLAB_WIDEN`) follows from this one.
                let (_, hit) = child_slab(l, &r, n, c, tmax);
                let hit = l.bits(l.and(hit, active));
                if hit != 0 {
                    stack.push(Entry {
                        link: n.link(c),
                        reach: hit,
                    });
                }
            }
        }
        if alive == 0 {
            break;
        }
        next = stack.pop();
    }
    out
}
