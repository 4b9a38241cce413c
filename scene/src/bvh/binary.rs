//! The binary binned-SAH build (Wald 2007, "On fast construction of SAH-based bounding volume
//! hierarchies"): each node bins its primitives' centroids into `bin_count` equal bins per axis and
//! evaluates the surface area heuristic at the bin boundaries. Subtrees are built in parallel with
//! `rayon::join`; the big top-level nodes bin and partition their primitives in parallel as well.
//!
//! Every subtree of `n` primitives at offset `s` owns the slots `2s .. 2(s + n) - 1` of a temporary node
//! arena (a binary tree over `n` leaves has at most `2n - 1` nodes), so parallel subtrees write disjoint
//! slices without locks or per-node allocation. Subtrees small enough to be built sequentially pack
//! their nodes at the front of their slots ([`build_node`]), so the arena's untouched pages (it is
//! allocated zeroed) cost no memory.
//!
//! Depth is bounded: when a node's depth plus `ceil(log2 n)` reaches [`MAX_DEPTH`], its subtree is split at
//! object medians, which halves the primitive count per level. Leaf depth thus never exceeds `MAX_DEPTH`.
use std::sync::atomic::{AtomicUsize, Ordering};

use fovea_core::scene::BvhNode;
use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::blocks::blocks_for;
use super::MAX_DEPTH;

/// Most bins per axis; `bin_count` is clamped to `2..=MAX_BINS`.
pub(super) const MAX_BINS: usize = 32;
/// Subtrees with more primitives than this build their two children in parallel.
pub(super) const PARALLEL_SUBTREE: usize = 4096;
/// Nodes with at least this many primitives bin and partition in parallel.
const PARALLEL_NODE: usize = 65_536;
/// Primitives per task of parallel binning and partitioning.
const CHUNK: usize = 16_384;

/// An axis-aligned box; empty boxes have `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Aabb {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
}

impl Aabb {
    pub(super) const EMPTY: Self = Self {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline]
    fn grow(&mut self, other: &Aabb) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    #[inline]
    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Half the surface area (the SAH only needs ratios); zero for empty boxes.
    #[inline]
    pub(super) fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive reference: the triangle's bounds and its input index, in 32 bytes rather than 48: the
/// index rides in the `w` lane of the lower corner, which a `Vec3A` would leave as padding, so binning
/// and partitioning move a third less memory (Embree's `PrimRef` does the same).
///
/// The index is stored as the bits of a *normal* float (bit 30 flipped, so the exponent field is 128 to
/// 191 for every index below 2²⁹): the `w` lane takes part in the SIMD arithmetic on the bounds, and
/// denormal or NaN operands there could be slow.
#[derive(Clone, Copy, Debug)]
pub(super) struct PrimRef {
    min_and_index: Vec4,
    max: Vec3A,
}

/// Flips bit 30 of an index below 2²⁹ into normal-float bits and back.
const INDEX_TAG: u32 = 1 << 30;

impl PrimRef {
    /// Largest index a `PrimRef` holds (exclusive).
    pub(super) const MAX_INDEX: u32 = 1 << 29;

    #[inline]
    pub(super) fn new(bounds: Aabb, index: u32) -> Self {
        debug_assert!(index < Self::MAX_INDEX);
        Self {
            min_and_index: bounds.min.extend(f32::from_bits(index ^ INDEX_TAG)),
            max: bounds.max,
        }
    }

    #[inline]
    pub(super) fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3A::from_vec4(self.min_and_index),
            max: self.max,
        }
    }

    /// The triangle's input index.
    #[inline]
    pub(super) fn index(&self) -> u32 {
        self.min_and_index.w.to_bits() ^ INDEX_TAG
    }

    /// Twice the centroid of the bounds (the factor cancels everywhere it is used).
    #[inline]
    fn centroid2(&self) -> Vec3A {
        Vec3A::from_vec4(self.min_and_index) + self.max
    }
}

/// Bounds of a set of primitives and of their (doubled) centroids.
#[derive(Clone, Copy, Debug)]
pub(super) struct Side {
    pub(super) bounds: Aabb,
    pub(super) centroids: Aabb,
}

impl Side {
    const EMPTY: Self = Self {
        bounds: Aabb::EMPTY,
        centroids: Aabb::EMPTY,
    };

    #[inline]
    fn add(&mut self, p: &PrimRef) {
        self.bounds.grow(&p.bounds());
        self.centroids.grow_point(p.centroid2());
    }

    #[inline]
    fn merge(mut self, other: &Side) -> Self {
        self.bounds.grow(&other.bounds);
        self.centroids.grow(&other.centroids);
        self
    }

    pub(super) fn of(prims: &[PrimRef]) -> Self {
        if prims.len() >= PARALLEL_NODE {
            return prims
                .par_chunks(CHUNK)
                .map(Side::of)
                .reduce(|| Side::EMPTY, |a, b| a.merge(&b));
        }
        let mut s = Side::EMPTY;
        for p in prims {
            s.add(p);
        }
        s
    }
}

/// Maps centroids to bins along all three axes.
#[derive(Clone, Copy)]
struct Binning {
    origin: Vec3A,
    scale: Vec3A,
    bins: usize,
}

impl Binning {
    fn new(centroids: &Aabb, bins: usize) -> Self {
        let extent = centroids.max - centroids.min;
        // Slightly below `bins / extent` so the largest centroid lands in the last bin, not past it.
        let k = bins as f32 * (1.0 - 1e-6);
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(k) / extent,
            Vec3A::ZERO,
        );
        Self {
            origin: centroids.min,
            scale,
            bins,
        }
    }

    /// Bin indices of `p` along x, y and z. The bin coordinate is clamped to `[0, bins - 1]` as a vector
    /// first (NaN maps to 0), so each lane's conversion is a plain truncation.
    #[inline]
    fn bins_of(&self, p: &PrimRef) -> [usize; 3] {
        let last = (self.bins - 1) as f32;
        let f = ((p.centroid2() - self.origin) * self.scale)
            .max(Vec3A::ZERO)
            .min(Vec3A::splat(last));
        [
            f.x as i32 as usize,
            f.y as i32 as usize,
            f.z as i32 as usize,
        ]
    }

    /// Whether `p` falls in a bin below `split` along `axis`: the same decision as `bins_of(p)[axis] <
    /// split` for `1 <= split < bins` (`floor(f) < k` if and only if `f < k` for a whole `k`; NaN, bin 0,
    /// goes left), with one float comparison instead of a conversion.
    #[inline]
    fn is_below(&self, p: &PrimRef, axis: usize, split: usize) -> bool {
        let f = (p.centroid2()[axis] - self.origin[axis]) * self.scale[axis];
        !(f >= split as f32)
    }
}

/// Per-axis bin bounds and counts.
#[derive(Clone, Copy)]
pub(super) struct Bins {
    bounds: [[Aabb; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    pub(super) fn empty() -> Self {
        Self {
            bounds: [[Aabb::EMPTY; MAX_BINS]; 3],
            counts: [[0; MAX_BINS]; 3],
        }
    }

    fn merge(mut self, other: &Bins, bins: usize) -> Self {
        for axis in 0..3 {
            for b in 0..bins {
                self.bounds[axis][b].grow(&other.bounds[axis][b]);
                self.counts[axis][b] += other.counts[axis][b];
            }
        }
        self
    }

    /// Empties the first `bins` bins of each axis (the only ones a binning with `bins` bins uses).
    fn reset(&mut self, bins: usize) {
        for axis in 0..3 {
            self.bounds[axis][..bins].fill(Aabb::EMPTY);
            self.counts[axis][..bins].fill(0);
        }
    }

    /// Bins `prims` into `self` (overwriting the bins `binning` uses).
    fn fill(&mut self, prims: &[PrimRef], binning: &Binning) {
        let bins = binning.bins;
        if prims.len() >= PARALLEL_NODE {
            *self = prims
                .par_chunks(CHUNK)
                .map(|c| {
                    let mut b = Bins::empty();
                    b.fill(c, binning);
                    b
                })
                .reduce(Bins::empty, |a, b| a.merge(&b, bins));
            return;
        }
        self.reset(bins);
        for p in prims {
            for (axis, &bin) in binning.bins_of(p).iter().enumerate() {
                self.bounds[axis][bin].grow(&p.bounds());
                self.counts[axis][bin] += 1;
            }
        }
    }
}

/// The best binned split: primitives with `bin_of(axis) < split` go left; `cost` is the SAH area-count
/// sum `A_L N_L + A_R N_R` (not yet divided by the parent's area).
#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    split: usize,
    cost: f32,
}

/// Finds the cheapest split among the bin boundaries of all axes with a non-zero centroid extent.
fn best_split(bins: &Bins, binning: &Binning) -> Option<Split> {
    let n = binning.bins;
    let mut best: Option<Split> = None;
    for axis in 0..3 {
        if binning.scale[axis] == 0.0 {
            continue;
        }
        // Sweep from the right: area and count of bins i+1.. for the split after bin i.
        let mut right_area = [0.0f32; MAX_BINS];
        let mut right_count = [0u32; MAX_BINS];
        let mut acc = Aabb::EMPTY;
        let mut count = 0u32;
        for i in (1..n).rev() {
            acc.grow(&bins.bounds[axis][i]);
            count += bins.counts[axis][i];
            right_area[i - 1] = acc.half_area();
            right_count[i - 1] = count;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0u32;
        for i in 0..n - 1 {
            acc.grow(&bins.bounds[axis][i]);
            count += bins.counts[axis][i];
            if count == 0 || right_count[i] == 0 {
                continue;
            }
            // Leaves are tested four triangles at a time, so the cost counts blocks of four.
            let cost = acc.half_area() * blocks_for(count as usize) as f32
                + right_area[i] * blocks_for(right_count[i] as usize) as f32;
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    split: i + 1,
                    cost,
                });
            }
        }
    }
    best
}

/// Partitions `prims` in place into `[left | right]`; returns the left count and both sides' bounds.
fn partition_serial(
    prims: &mut [PrimRef],
    goes_left: &(impl Fn(&PrimRef) -> bool + Sync),
) -> (usize, Side, Side) {
    let mut left = Side::EMPTY;
    let mut right = Side::EMPTY;
    let mut i = 0;
    let mut j = prims.len();
    while i < j {
        if goes_left(&prims[i]) {
            left.add(&prims[i]);
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
            right.add(&prims[j]);
        }
    }
    (i, left, right)
}

/// [`partition_serial`] for big nodes: chunks partition in parallel, then the right-side elements below the
/// split point swap places with the left-side elements above it, segment by segment, in parallel.
fn partition(
    prims: &mut [PrimRef],
    goes_left: &(impl Fn(&PrimRef) -> bool + Sync),
) -> (usize, Side, Side) {
    if prims.len() < PARALLEL_NODE {
        return partition_serial(prims, goes_left);
    }
    let parts: Vec<(usize, usize, Side, Side)> = prims
        .par_chunks_mut(CHUNK)
        .map(|c| {
            let (m, l, r) = partition_serial(c, goes_left);
            (c.len(), m, l, r)
        })
        .collect();
    let mut left = Side::EMPTY;
    let mut right = Side::EMPTY;
    let mut mid = 0;
    for p in &parts {
        mid += p.1;
        left = left.merge(&p.2);
        right = right.merge(&p.3);
    }

    // Misplaced ranges: right elements in [0, mid) and left elements in [mid, n), both ascending.
    let mut wrong_right = Vec::new();
    let mut wrong_left = Vec::new();
    let mut offset = 0;
    for &(len, m, _, _) in &parts {
        let (l0, l1) = (offset, offset + m);
        let (r0, r1) = (offset + m, offset + len);
        if r0 < mid {
            wrong_right.push((r0, r1.min(mid)));
        }
        if l1 > mid {
            wrong_left.push((l0.max(mid), l1));
        }
        offset += len;
    }
    // Pair them into equal-length segments (a, b, len).
    let mut segments = Vec::new();
    let (mut ia, mut ib) = (0, 0);
    let (mut a, mut b) = (
        wrong_right.first().map_or(0, |r| r.0),
        wrong_left.first().map_or(0, |r| r.0),
    );
    while ia < wrong_right.len() && ib < wrong_left.len() {
        let len = (wrong_right[ia].1 - a).min(wrong_left[ib].1 - b);
        segments.push((a, b, len));
        a += len;
        b += len;
        if a == wrong_right[ia].1 {
            ia += 1;
            if ia < wrong_right.len() {
                a = wrong_right[ia].0;
            }
        }
        if b == wrong_left[ib].1 {
            ib += 1;
            if ib < wrong_left.len() {
                b = wrong_left[ib].0;
            }
        }
    }
    // Carve both halves into the segments' slices and swap them in parallel.
    let (low, high) = prims.split_at_mut(mid);
    let mut low_pieces = Vec::with_capacity(segments.len());
    let mut high_pieces = Vec::with_capacity(segments.len());
    let (mut low_rest, mut low_at) = (low, 0);
    let (mut high_rest, mut high_at) = (high, mid);
    for &(a, b, len) in &segments {
        let (_, tail) = std::mem::take(&mut low_rest).split_at_mut(a - low_at);
        let (piece, tail) = tail.split_at_mut(len);
        low_pieces.push(piece);
        low_rest = tail;
        low_at = a + len;
        let (_, tail) = std::mem::take(&mut high_rest).split_at_mut(b - high_at);
        let (piece, tail) = tail.split_at_mut(len);
        high_pieces.push(piece);
        high_rest = tail;
        high_at = b + len;
    }
    low_pieces
        .into_par_iter()
        .zip(high_pieces)
        .for_each(|(x, y)| x.swap_with_slice(y));
    (mid, left, right)
}

/// `ceil(log2(n))` for `n >= 1`.
#[inline]
fn ceil_log2(n: usize) -> u32 {
    usize::BITS - (n - 1).leading_zeros()
}

/// Validated build settings.
pub(super) struct Context {
    pub(super) bins: usize,
    pub(super) max_leaf: usize,
    pub(super) coincident_leaf: usize,
    pub(super) traversal_cost: f32,
    pub(super) intersection_cost: f32,
    /// Leaves made so far.
    pub(super) leaves: AtomicUsize,
}

/// Splits at the object median along the axis of largest centroid extent; returns the left count and both
/// sides' bounds.
fn median_split(prims: &mut [PrimRef], centroids: &Aabb) -> (usize, Side, Side) {
    let mid = prims.len() / 2;
    let extent = centroids.max - centroids.min;
    if extent.max_element() > 0.0 {
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        prims.select_nth_unstable_by(mid, |a, b| {
            a.centroid2()[axis].total_cmp(&b.centroid2()[axis])
        });
    }
    let (l, r) = prims.split_at(mid);
    let (left, right) = rayon::join(|| Side::of(l), || Side::of(r));
    (mid, left, right)
}

/// Builds the subtree over `prims` (at offset `first` of the leaf order) into `arena`, whose slot 0 is the
/// subtree's root and whose length is at least `2 * prims.len() - 1` (the most nodes a binary tree over
/// that many leaves has), and returns how many slots from the start it spans.
///
/// An interior node's left child is the next slot, and `left_or_first` holds the offset of its right
/// child. Subtrees built in parallel put the right child after the left child's whole reservation
/// (`2 * left_count`), since both are written at once; sequential ones put it right after the left
/// subtree's last node, so each sequential subtree is contiguous and the untouched rest of its
/// reservation (more than half of it, with leaves of about three triangles) is never paged in.
pub(super) fn build_node(
    ctx: &Context,
    prims: &mut [PrimRef],
    arena: &mut [BvhNode],
    first: u32,
    side: Side,
    depth: u32,
    bins: &mut Bins,
) -> usize {
    let n = prims.len();
    debug_assert!(arena.len() >= 2 * n - 1);
    let leaf = BvhNode {
        bounds_min: side.bounds.min.to_array(),
        left_or_first: first,
        bounds_max: side.bounds.max.to_array(),
        triangle_count: n as u32,
    };
    if n == 1 {
        arena[0] = leaf;
        ctx.leaves.fetch_add(1, Ordering::Relaxed);
        return 1;
    }

    let coincident = side.centroids.max.cmple(side.centroids.min).all();
    let split = if depth + ceil_log2(n) >= MAX_DEPTH {
        // Depth guard: object medians from here on.
        (n > ctx.max_leaf).then(|| median_split(prims, &side.centroids))
    } else if coincident {
        // No centroid split can separate these primitives.
        (n > ctx.coincident_leaf).then(|| median_split(prims, &side.centroids))
    } else {
        // Small nodes use fewer bins: cheaper, and a few primitives need no more.
        let binning = Binning::new(&side.centroids, ctx.bins.min(n));
        bins.fill(prims, &binning);
        match best_split(bins, &binning) {
            Some(best) => {
                let area = side.bounds.half_area();
                let split_cost = if area > 0.0 {
                    ctx.traversal_cost + ctx.intersection_cost * best.cost / area
                } else {
                    ctx.traversal_cost + ctx.intersection_cost * blocks_for(n) as f32
                };
                let leaf_cost = ctx.intersection_cost * blocks_for(n) as f32;
                if n <= ctx.max_leaf && leaf_cost <= split_cost {
                    None
                } else {
                    Some(partition(prims, &|p: &PrimRef| {
                        binning.is_below(p, best.axis, best.split)
                    }))
                }
            }
            None if n <= ctx.max_leaf => None,
            None => Some(median_split(prims, &side.centroids)),
        }
    };

    let Some((mid, left, right)) = split else {
        arena[0] = leaf;
        ctx.leaves.fetch_add(1, Ordering::Relaxed);
        return 1;
    };
    debug_assert!(mid > 0 && mid < n);
    let (left_prims, right_prims) = prims.split_at_mut(mid);
    let right_first = first + mid as u32;
    let (root, below) = arena.split_first_mut().expect("the arena holds the root");
    let (right_offset, span) = if n > PARALLEL_SUBTREE {
        let (left_arena, right_arena) = below.split_at_mut(2 * mid - 1);
        let (_, right_span) = rayon::join(
            || build_node(ctx, left_prims, left_arena, first, left, depth + 1, bins),
            || {
                let mut right_bins = Bins::empty();
                build_node(
                    ctx,
                    right_prims,
                    right_arena,
                    right_first,
                    right,
                    depth + 1,
                    &mut right_bins,
                )
            },
        );
        (2 * mid, 2 * mid + right_span)
    } else {
        let left_span = build_node(ctx, left_prims, below, first, left, depth + 1, bins);
        let right_span = build_node(
            ctx,
            right_prims,
            &mut below[left_span..],
            right_first,
            right,
            depth + 1,
            bins,
        );
        (1 + left_span, 1 + left_span + right_span)
    };
    *root = BvhNode {
        bounds_min: side.bounds.min.to_array(),
        left_or_first: right_offset as u32,
        bounds_max: side.bounds.max.to_array(),
        triangle_count: 0,
    };
    span
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prim_ref_keeps_bounds_and_index_in_32_bytes() {
        assert_eq!(std::mem::size_of::<PrimRef>(), 32);
        let bounds = Aabb {
            min: Vec3A::new(-1.0, 2.0, -3.0),
            max: Vec3A::new(4.0, 5.0, 6.0),
        };
        for index in [0, 1, 12_345, (1 << 23) - 1, 1 << 23, PrimRef::MAX_INDEX - 1] {
            let p = PrimRef::new(bounds, index);
            assert_eq!(p.index(), index);
            assert_eq!(p.bounds().min, bounds.min);
            assert_eq!(p.bounds().max, bounds.max);
            assert_eq!(p.centroid2(), bounds.min + bounds.max);
            // The index lane is a normal float, never a denormal or NaN.
            assert!(p.min_and_index.w.is_normal(), "{index}");
        }
    }

    #[test]
    fn partition_test_agrees_with_binning() {
        let centroids = Aabb {
            min: Vec3A::new(-2.0, 0.0, 1.0),
            max: Vec3A::new(6.0, 0.0, 1.0 + 1e-3),
        };
        let mut state = 1u32;
        for bins in [2usize, 3, 7, 32] {
            // Binning works on doubled centroids, as the builder's `Side::centroids` are.
            let doubled = Aabb {
                min: centroids.min * 2.0,
                max: centroids.max * 2.0,
            };
            let binning = Binning::new(&doubled, bins);
            for i in 0..20_000u32 {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                // Points inside the centroid box, on its faces and exactly on bin boundaries.
                let u = if i % 4 == 0 {
                    (state % (bins as u32 + 1)) as f32 / bins as f32
                } else {
                    (state >> 8) as f32 / (1u32 << 24) as f32
                };
                let c = centroids.min + (centroids.max - centroids.min) * u;
                let p = PrimRef::new(Aabb { min: c, max: c }, i);
                let bin = binning.bins_of(&p);
                for (axis, &b) in bin.iter().enumerate() {
                    for split in 1..bins {
                        assert_eq!(
                            binning.is_below(&p, axis, split),
                            b < split,
                            "bins {bins} axis {axis} split {split} u {u}"
                        );
                    }
                }
            }
        }
    }
}
