//! Binned surface-area heuristic over references (`Ref`: a primitive, or the part of one
//! that a spatial split left on one side), as the high-quality build (`spatial`) weighs
//! splits: bins along an axis (`Bins`), the cheapest plane between them (`sweep`), and
//! the splits by centroid (`object_split`, `partition_objects`, `median`); the spatial
//! split's own binning, which cuts triangles, stays with the builder.

use obvhs::aabb::Aabb;

/// Bins an axis, for a split by centroids and a spatial split of a large node.
pub(super) const BINS: usize = 32;

/// Bins an axis for a spatial split of a node of few references (`spatial::FEW_REFS`):
/// its triangles span more of its bins, and each is cut at every plane it crosses.
pub(super) const FEW_BINS: usize = 16;

/// A primitive, or its part inside `b`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ref {
    pub(super) b: Aabb,
    pub(super) prim: u32,
}

/// `count` equal bins along `axis` from `lo` over `extent`: over the centroids for an
/// object split, over the node's box for a spatial one.
#[derive(Clone, Copy, Debug)]
pub(super) struct Bins {
    pub(super) axis: usize,
    pub(super) lo: f32,
    pub(super) extent: f32,
    pub(super) count: usize,
}

impl Bins {
    /// `count` bins over `b` on each axis where it has an extent.
    pub(super) fn over(b: &Aabb, count: usize) -> impl Iterator<Item = Bins> + '_ {
        (0..3)
            .map(move |axis| Bins {
                axis,
                lo: b.min[axis],
                extent: b.max[axis] - b.min[axis],
                count,
            })
            .filter(|bins| bins.extent > 0.0)
    }

    /// The bin of coordinate `x` (the last holds `lo + extent` itself).
    pub(super) fn index(&self, x: f32) -> usize {
        (((x - self.lo) * (self.count as f32 / self.extent)) as usize).min(self.count - 1)
    }

    /// Where bin `k` starts.
    pub(super) fn plane(&self, k: usize) -> f32 {
        self.lo + self.extent * k as f32 / self.count as f32
    }
}

/// A split of a node's references and what the SAH makes of it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Split {
    pub(super) bins: Bins,
    /// The first bin of the right half: for a spatial split, the plane is its start.
    pub(super) bin: usize,
    /// Surface area times references, summed over both halves.
    pub(super) cost: f32,
    pub(super) left: Aabb,
    pub(super) right: Aabb,
    pub(super) counts: (u32, u32),
}

impl Split {
    pub(super) fn plane(&self) -> f32 {
        self.bins.plane(self.bin)
    }
}

/// The box around the references' centroids.
fn centroid_bounds(refs: &[Ref]) -> Aabb {
    refs.iter().fold(Aabb::empty(), |a, r| {
        a.union(&Aabb::from_point(r.b.center()))
    })
}

/// Half the surface area of `b`; 0 for an empty box.
pub(super) fn half_area(b: &Aabb) -> f32 {
    if b.valid() { b.half_area() } else { 0.0 }
}

/// The box around the references.
pub(super) fn bounds(refs: &[Ref]) -> Aabb {
    refs.iter().fold(Aabb::empty(), |a, r| a.union(&r.b))
}

/// `refs` ordered so that the first half's centroids lie below the second's on the axis
/// where they spread widest.
pub(super) fn median(mut refs: Vec<Ref>) -> Vec<Ref> {
    let axis = centroid_bounds(&refs).largest_axis();
    let mid = refs.len() / 2;
    if mid > 0 {
        refs.select_nth_unstable_by(mid, |a, b| {
            a.b.center_axis(axis).total_cmp(&b.b.center_axis(axis))
        });
    }
    refs
}

/// The cheapest split of `refs` by centroid into two non-empty halves, binned on each
/// axis; `None` where every centroid is in one place.
pub(super) fn object_split(refs: &[Ref]) -> Option<Split> {
    let mut best: Option<Split> = None;
    for bins in Bins::over(&centroid_bounds(refs), BINS) {
        let mut boxes = [Aabb::empty(); BINS];
        let mut counts = [0u32; BINS];
        for r in refs {
            let k = bins.index(r.b.center_axis(bins.axis));
            boxes[k] = boxes[k].union(&r.b);
            counts[k] += 1;
        }
        sweep(&mut best, bins, &boxes, &counts, &counts);
    }
    best
}

/// `best` replaced by the cheapest split between the `bins` (their boxes `boxes`) where it
/// is cheaper: `entry[k]` references start in bin `k`, `exit[k]` end there.
pub(super) fn sweep(
    best: &mut Option<Split>,
    bins: Bins,
    boxes: &[Aabb; BINS],
    entry: &[u32; BINS],
    exit: &[u32; BINS],
) {
    // The bins in use: `bins.count` of the arrays' `BINS`.
    let n = bins.count;
    let mut right = [(Aabb::empty(), 0u32); BINS];
    let (mut rb, mut rc) = (Aabb::empty(), 0);
    for k in (1..n).rev() {
        rb = rb.union(&boxes[k]);
        rc += exit[k];
        right[k] = (rb, rc);
    }
    let (mut lb, mut lc) = (Aabb::empty(), 0);
    for k in 1..n {
        lb = lb.union(&boxes[k - 1]);
        lc += entry[k - 1];
        let (rb, rc) = right[k];
        if lc == 0 || rc == 0 {
            continue;
        }
        let cost = half_area(&lb) * lc as f32 + half_area(&rb) * rc as f32;
        if best.is_none_or(|b| cost < b.cost) {
            *best = Some(Split {
                bins,
                bin: k,
                cost,
                left: lb,
                right: rb,
                counts: (lc, rc),
            });
        }
    }
}

/// `refs` on each side of centroid split `s`, binned as `object_split` binned them.
pub(super) fn partition_objects(refs: Vec<Ref>, s: &Split) -> (Vec<Ref>, Vec<Ref>) {
    refs.into_iter()
        .partition(|r| s.bins.index(r.b.center_axis(s.bins.axis)) < s.bin)
}
