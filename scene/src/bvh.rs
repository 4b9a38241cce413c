//! BVH construction: binned SAH, built in parallel, flattened for traversal.
//!
//! The builder follows Wald 2007, "On fast construction of SAH-based bounding volume hierarchies": each
//! node bins its primitives' centroids into `bin_count` equal bins per axis and evaluates the surface area
//! heuristic at the bin boundaries. Subtrees are built in parallel with `rayon::join`; the big top-level
//! nodes bin and partition their primitives in parallel as well.
//!
//! Every subtree of `n` primitives at offset `s` owns the slots `2s .. 2(s + n) - 1` of a temporary node
//! arena (a binary tree over `n` leaves has at most `2n - 1` nodes), so parallel subtrees write disjoint
//! slices without locks or per-node allocation. A final depth-first pass writes the traversal layout:
//! root at 0, siblings adjacent.
//!
//! Depth is bounded: when a node's depth plus `ceil(log2 n)` reaches [`MAX_DEPTH`], its subtree is split at
//! object medians, which halves the primitive count per level. Leaf depth thus never exceeds `MAX_DEPTH`,
//! which is below `TRAVERSAL_STACK_SIZE`.
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use fovea_core::bvh::TRAVERSAL_STACK_SIZE;
use fovea_core::scene::{BvhNode, TrianglePositions};
use glam::Vec3A;
use rayon::prelude::*;

/// The deepest leaf depth (root = 0) [`build_bvh`] produces.
pub const MAX_DEPTH: u32 = TRAVERSAL_STACK_SIZE as u32 - 2;

/// Most bins per axis; `bin_count` is clamped to `2..=MAX_BINS`.
const MAX_BINS: usize = 32;
/// Subtrees with more primitives than this build their two children in parallel.
const PARALLEL_SUBTREE: usize = 4096;
/// Nodes with at least this many primitives bin and partition in parallel.
const PARALLEL_NODE: usize = 65_536;
/// Primitives per task of parallel binning and partitioning.
const CHUNK: usize = 16_384;

/// Builder settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhBuildOptions {
    /// Leaves hold at most this many triangles, except when all centroids of a node coincide (then up to
    /// four times this many, since no split can separate them).
    pub max_leaf_size: u32,
    /// SAH bins per axis (2 to 32).
    pub bin_count: u32,
    /// SAH cost of visiting an interior node.
    pub traversal_cost: f32,
    /// SAH cost of one ray-triangle test.
    pub intersection_cost: f32,
}

impl Default for BvhBuildOptions {
    fn default() -> Self {
        Self {
            max_leaf_size: 4,
            bin_count: 16,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
        }
    }
}

/// What a build produced and how long it took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    pub build_ms: f64,
    pub node_count: usize,
    pub leaf_count: usize,
    /// Depth of the deepest leaf; the root alone has depth 0.
    pub max_depth: u32,
    /// Bytes of the node array.
    pub memory_bytes: usize,
}

/// A built BVH in traversal layout (see [`BvhNode`]).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// `triangle_order[i]` is the input index of the triangle stored at position `i` of the leaf-ordered
    /// triangle arrays.
    pub triangle_order: Vec<u32>,
    pub stats: BvhStats,
}

/// An axis-aligned box; empty boxes have `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: Vec3A,
    max: Vec3A,
}

impl Aabb {
    const EMPTY: Self = Self {
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
    fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive reference: the triangle's bounds and its input index.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    bounds: Aabb,
    index: u32,
}

impl PrimRef {
    /// Twice the centroid of the bounds (the factor cancels everywhere it is used).
    #[inline]
    fn centroid2(&self) -> Vec3A {
        self.bounds.min + self.bounds.max
    }
}

/// Bounds of a set of primitives and of their (doubled) centroids.
#[derive(Clone, Copy, Debug)]
struct Side {
    bounds: Aabb,
    centroids: Aabb,
}

impl Side {
    const EMPTY: Self = Self {
        bounds: Aabb::EMPTY,
        centroids: Aabb::EMPTY,
    };

    #[inline]
    fn add(&mut self, p: &PrimRef) {
        self.bounds.grow(&p.bounds);
        self.centroids.grow_point(p.centroid2());
    }

    #[inline]
    fn merge(mut self, other: &Side) -> Self {
        self.bounds.grow(&other.bounds);
        self.centroids.grow(&other.centroids);
        self
    }

    fn of(prims: &[PrimRef]) -> Self {
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

    /// Bin indices of `p` along x, y and z (saturating casts map NaN to 0 and overflow to the last bin).
    #[inline]
    fn bins_of(&self, p: &PrimRef) -> [usize; 3] {
        let f = (p.centroid2() - self.origin) * self.scale;
        let last = self.bins - 1;
        [
            (f.x as usize).min(last),
            (f.y as usize).min(last),
            (f.z as usize).min(last),
        ]
    }

    #[inline]
    fn bin_of(&self, p: &PrimRef, axis: usize) -> usize {
        let f = (p.centroid2()[axis] - self.origin[axis]) * self.scale[axis];
        (f as usize).min(self.bins - 1)
    }
}

/// Per-axis bin bounds and counts.
#[derive(Clone, Copy)]
struct Bins {
    bounds: [[Aabb; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn empty() -> Self {
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
                self.bounds[axis][bin].grow(&p.bounds);
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
            let cost = acc.half_area() * count as f32 + right_area[i] * right_count[i] as f32;
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
struct Context {
    bins: usize,
    max_leaf: usize,
    coincident_leaf: usize,
    traversal_cost: f32,
    intersection_cost: f32,
    /// Leaves made so far (sizes the final node array exactly).
    leaves: AtomicUsize,
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
/// subtree's root and whose length is `2 * prims.len() - 1`. Interior nodes store their left child's
/// primitive count in `left_or_first` (the children sit at slots 1 and `2 * left_count`).
fn build_node(
    ctx: &Context,
    prims: &mut [PrimRef],
    arena: &mut [BvhNode],
    first: u32,
    side: Side,
    depth: u32,
    bins: &mut Bins,
) {
    let n = prims.len();
    debug_assert_eq!(arena.len(), 2 * n - 1);
    let leaf = BvhNode {
        bounds_min: side.bounds.min.to_array(),
        left_or_first: first,
        bounds_max: side.bounds.max.to_array(),
        triangle_count: n as u32,
    };
    if n == 1 {
        arena[0] = leaf;
        ctx.leaves.fetch_add(1, Ordering::Relaxed);
        return;
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
        let binning = Binning::new(&side.centroids, ctx.bins.min(2 * n));
        bins.fill(prims, &binning);
        match best_split(bins, &binning) {
            Some(best) => {
                let area = side.bounds.half_area();
                let split_cost = if area > 0.0 {
                    ctx.traversal_cost + ctx.intersection_cost * best.cost / area
                } else {
                    ctx.traversal_cost + ctx.intersection_cost * n as f32
                };
                let leaf_cost = ctx.intersection_cost * n as f32;
                if n <= ctx.max_leaf && leaf_cost <= split_cost {
                    None
                } else {
                    Some(partition(prims, &|p: &PrimRef| {
                        binning.bin_of(p, best.axis) < best.split
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
        return;
    };
    debug_assert!(mid > 0 && mid < n);
    arena[0] = BvhNode {
        bounds_min: side.bounds.min.to_array(),
        left_or_first: mid as u32,
        bounds_max: side.bounds.max.to_array(),
        triangle_count: 0,
    };
    let (left_prims, right_prims) = prims.split_at_mut(mid);
    let (left_arena, right_arena) = arena[1..].split_at_mut(2 * mid - 1);
    let right_first = first + mid as u32;
    if n > PARALLEL_SUBTREE {
        rayon::join(
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
                );
            },
        );
    } else {
        build_node(ctx, left_prims, left_arena, first, left, depth + 1, bins);
        build_node(
            ctx,
            right_prims,
            right_arena,
            right_first,
            right,
            depth + 1,
            bins,
        );
    }
}

/// Moves `x` down by at least two ulps (and at least 1e-30), so boxes strictly contain their triangles.
#[inline]
fn widen_down(x: f32) -> f32 {
    x - (x.abs() * (1.0 / 4_194_304.0)).max(1e-30)
}

/// Moves `x` up by at least two ulps (and at least 1e-30).
#[inline]
fn widen_up(x: f32) -> f32 {
    x + (x.abs() * (1.0 / 4_194_304.0)).max(1e-30)
}

/// Writes the arena subtree at `slot` into `out[position]` and appends its descendants depth first, each
/// sibling pair adjacent. Boxes are widened by a few ulps so that they strictly contain their triangles:
/// the traversal's slab test may then miss a box only when no triangle in it can be hit.
fn flatten(
    arena: &[BvhNode],
    slot: usize,
    out: &mut Vec<BvhNode>,
    position: usize,
    depth: u32,
    stats: &mut BvhStats,
) {
    let node = arena[slot];
    let mut flat = node;
    flat.bounds_min = node.bounds_min.map(widen_down);
    flat.bounds_max = node.bounds_max.map(widen_up);
    if node.is_leaf() {
        out[position] = flat;
        stats.leaf_count += 1;
        stats.max_depth = stats.max_depth.max(depth);
        return;
    }
    let children = out.len();
    flat.left_or_first = children as u32;
    out[position] = flat;
    out.push(BvhNode::default());
    out.push(BvhNode::default());
    let left_count = node.left_or_first as usize;
    flatten(arena, slot + 1, out, children, depth + 1, stats);
    flatten(
        arena,
        slot + 2 * left_count,
        out,
        children + 1,
        depth + 1,
        stats,
    );
}

/// Builds a BVH over `triangles` with binned SAH (see the module documentation). An empty input gives an
/// empty node array; degenerate triangles are accepted (their boxes are flat or points).
#[must_use]
pub fn build_bvh(triangles: &[TrianglePositions], options: &BvhBuildOptions) -> Bvh {
    let start = Instant::now();
    let n = triangles.len();
    if n == 0 {
        return Bvh {
            stats: BvhStats {
                build_ms: start.elapsed().as_secs_f64() * 1e3,
                ..BvhStats::default()
            },
            ..Bvh::default()
        };
    }
    assert!(
        n < (u32::MAX / 2) as usize,
        "too many triangles for 32-bit node indices"
    );
    let max_leaf = options.max_leaf_size.max(1) as usize;
    let ctx = Context {
        bins: (options.bin_count as usize).clamp(2, MAX_BINS),
        max_leaf,
        coincident_leaf: 4 * max_leaf,
        traversal_cost: options.traversal_cost.max(0.0),
        intersection_cost: options.intersection_cost.max(1e-6),
        leaves: AtomicUsize::new(0),
    };

    let mut prims: Vec<PrimRef> = triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            let a = Vec3A::from_slice(&t.v0[..3]);
            let b = Vec3A::from_slice(&t.v1[..3]);
            let c = Vec3A::from_slice(&t.v2[..3]);
            PrimRef {
                bounds: Aabb {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                },
                index: i as u32,
            }
        })
        .collect();
    let root = Side::of(&prims);
    let mut arena = vec![BvhNode::default(); 2 * n - 1];
    let mut bins = Bins::empty();
    build_node(&ctx, &mut prims, &mut arena, 0, root, 0, &mut bins);

    let mut stats = BvhStats::default();
    // A binary tree with `leaves` leaves has `2 * leaves - 1` nodes.
    let mut nodes = Vec::with_capacity(2 * ctx.leaves.load(Ordering::Relaxed) - 1);
    nodes.push(BvhNode::default());
    flatten(&arena, 0, &mut nodes, 0, 0, &mut stats);
    drop(arena);
    let triangle_order: Vec<u32> = prims.par_iter().map(|p| p.index).collect();

    stats.node_count = nodes.len();
    stats.memory_bytes = nodes.len() * std::mem::size_of::<BvhNode>();
    stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
    Bvh {
        nodes,
        triangle_order,
        stats,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fovea_core::bvh::{any_hit, closest_hit, Hit};
    use fovea_core::geometry::triangle::WatertightRay;
    use fovea_core::geometry::Ray;
    use fovea_core::math::{pack_vec3, vec3_from};
    use fovea_core::scene::{Material, SceneGlobals, SceneView, TriangleInfo};
    use glam::Vec3;

    /// SplitMix64 for reproducible test data.
    struct TestRng(u64);
    impl TestRng {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        fn uniform(&mut self) -> f32 {
            (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.uniform()
        }
        fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
            Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
        }
        fn unit_vector(&mut self) -> Vec3 {
            loop {
                let v = self.vec(-1.0, 1.0);
                let l = v.length_squared();
                if l > 1e-4 && l <= 1.0 {
                    return v / l.sqrt();
                }
            }
        }
    }

    fn tri(a: Vec3, b: Vec3, c: Vec3) -> TrianglePositions {
        TrianglePositions {
            v0: pack_vec3(a, 0.0),
            v1: pack_vec3(b, 0.0),
            v2: pack_vec3(c, 0.0),
        }
    }

    /// A random soup: triangles of assorted sizes in `[-10, 10]^3`, every 50th one degenerate.
    fn soup(n: usize, rng: &mut TestRng) -> Vec<TrianglePositions> {
        (0..n)
            .map(|i| {
                let c = rng.vec(-10.0, 10.0);
                let size = 10f32.powf(rng.range(-2.0, 0.5));
                let a = c + rng.vec(-size, size);
                let b = c + rng.vec(-size, size);
                match i % 50 {
                    0 => tri(a, a, a),
                    25 => tri(a, b, a + (b - a) * 0.25),
                    _ => tri(a, b, c + rng.vec(-size, size)),
                }
            })
            .collect()
    }

    /// The packed scene arrays a traversal needs, in BVH leaf order.
    struct Packed {
        bvh: Bvh,
        triangles: Vec<TrianglePositions>,
        info: Vec<TriangleInfo>,
        materials: Vec<Material>,
    }

    impl Packed {
        fn new(input: &[TrianglePositions]) -> Self {
            Self::with_options(input, &BvhBuildOptions::default())
        }

        fn with_options(input: &[TrianglePositions], options: &BvhBuildOptions) -> Self {
            let bvh = build_bvh(input, options);
            let triangles: Vec<_> = bvh
                .triangle_order
                .iter()
                .map(|&i| input[i as usize])
                .collect();
            let info = vec![TriangleInfo::default(); triangles.len()];
            Self {
                bvh,
                triangles,
                info,
                materials: vec![Material::default()],
            }
        }

        fn view(&self) -> SceneView<'_> {
            SceneView {
                globals: SceneGlobals::default(),
                nodes: &self.bvh.nodes,
                triangles: &self.triangles,
                triangle_info: &self.info,
                normals: &[],
                uvs: &[],
                materials: &self.materials,
                textures: &[],
                texels: &[],
                lights: &[],
                light_cdf: &[],
                triangle_light: &[],
                environment_texels: &[],
                environment_marginal_cdf: &[],
                environment_conditional_cdf: &[],
            }
        }
    }

    fn brute_force(triangles: &[TrianglePositions], ray: &Ray, t_max: f32) -> Hit {
        let w = WatertightRay::new(ray);
        let mut best = Hit::miss();
        let mut closest = t_max;
        for (i, t) in triangles.iter().enumerate() {
            let h = w.intersect(t, closest);
            if h.hit {
                closest = h.t;
                best = Hit {
                    t: h.t,
                    triangle: i as u32,
                    b1: h.b1,
                    b2: h.b2,
                };
            }
        }
        best
    }

    /// Checks the layout invariants: sibling pairs adjacent after their parent (depth first), every leaf
    /// range disjoint and together covering all triangles, every box strictly containing its triangles and
    /// children, leaf sizes bounded, and the reported depth within the stack.
    fn validate(bvh: &Bvh, input: &[TrianglePositions], max_leaf: usize) {
        let n = input.len();
        let mut seen = vec![false; n];
        for &i in &bvh.triangle_order {
            assert!(!seen[i as usize], "triangle {i} appears twice");
            seen[i as usize] = true;
        }
        assert!(seen.iter().all(|&s| s), "a triangle is missing");
        if n == 0 {
            assert!(bvh.nodes.is_empty());
            return;
        }
        assert_eq!(bvh.nodes.len(), bvh.stats.node_count);
        assert_eq!(bvh.nodes.len(), 2 * bvh.stats.leaf_count - 1);
        let mut covered = vec![false; n];
        let mut stack = vec![(0usize, 0u32)];
        let mut max_depth = 0;
        let mut next_expected_child = 1;
        let mut order = Vec::new();
        while let Some((i, depth)) = stack.pop() {
            order.push(i);
            let node = bvh.nodes[i];
            let (lo, hi) = (Vec3::from(node.bounds_min), Vec3::from(node.bounds_max));
            max_depth = max_depth.max(depth);
            if node.is_leaf() {
                let range = node.left_or_first as usize
                    ..(node.left_or_first + node.triangle_count) as usize;
                let coincident = {
                    let c = |k: usize| {
                        let t = &input[bvh.triangle_order[k] as usize];
                        let (a, b, c) = (vec3_from(t.v0), vec3_from(t.v1), vec3_from(t.v2));
                        a.min(b).min(c) + a.max(b).max(c)
                    };
                    range.clone().all(|k| c(k) == c(range.start))
                };
                assert!(range.len() <= max_leaf || (coincident && range.len() <= 4 * max_leaf));
                for k in range {
                    assert!(!covered[k]);
                    covered[k] = true;
                    let t = &input[bvh.triangle_order[k] as usize];
                    for v in [t.v0, t.v1, t.v2] {
                        let v = vec3_from(v);
                        assert!(
                            v.cmpgt(lo).all() && v.cmplt(hi).all(),
                            "{v:?} not strictly in {lo:?}..{hi:?}"
                        );
                    }
                }
            } else {
                let c = node.left_or_first as usize;
                assert_eq!(
                    c, next_expected_child,
                    "children must follow in depth-first order"
                );
                next_expected_child += 2;
                for child in [c, c + 1] {
                    let b = bvh.nodes[child];
                    assert!(
                        Vec3::from(b.bounds_min).cmpge(lo).all()
                            && Vec3::from(b.bounds_max).cmple(hi).all()
                    );
                }
                // Depth first: the left subtree is completed before the right one.
                stack.push((c + 1, depth + 1));
                stack.push((c, depth + 1));
            }
        }
        assert!(covered.iter().all(|&c| c));
        assert_eq!(order.len(), bvh.nodes.len());
        assert_eq!(max_depth, bvh.stats.max_depth);
        assert!((bvh.stats.max_depth as usize) < TRAVERSAL_STACK_SIZE);
        assert!(bvh.stats.max_depth <= MAX_DEPTH);
    }

    /// Random rays: origins inside and outside the soup, random and axis-aligned directions, infinite and
    /// finite segments.
    fn random_ray(rng: &mut TestRng, triangles: &[TrianglePositions]) -> (Ray, f32) {
        let origin = rng.vec(-15.0, 15.0);
        let dir = match rng.next_u64() % 8 {
            0 => [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z]
                [(rng.next_u64() % 6) as usize],
            1 => (rng.vec(-10.0, 10.0) - origin).normalize(),
            2..=4 => {
                // Aimed at a random point of a random triangle.
                let t = &triangles[(rng.next_u64() % triangles.len() as u64) as usize];
                let (b1, b2) = (rng.uniform() * 0.5, rng.uniform() * 0.5);
                let p =
                    vec3_from(t.v0) * (1.0 - b1 - b2) + vec3_from(t.v1) * b1 + vec3_from(t.v2) * b2;
                (p - origin).normalize_or(Vec3::X)
            }
            _ => rng.unit_vector(),
        };
        let t_max = if rng.uniform() < 0.5 {
            f32::INFINITY
        } else {
            rng.range(0.0, 30.0)
        };
        (Ray::new(origin, dir), t_max)
    }

    fn assert_matches_brute_force(packed: &Packed, rng: &mut TestRng, rays: usize) -> usize {
        let scene = packed.view();
        let mut hits = 0;
        for _ in 0..rays {
            let (ray, t_max) = random_ray(rng, &packed.triangles);
            let expected = brute_force(&packed.triangles, &ray, t_max);
            let got = closest_hit(&scene, &ray, t_max);
            assert_eq!(got.is_hit(), expected.is_hit(), "{ray:?} {t_max}");
            if expected.is_hit() {
                hits += 1;
                assert_eq!(got.t, expected.t, "{ray:?}");
                if got.triangle != expected.triangle {
                    // A tie: the other triangle must be hit at the very same distance.
                    let other = WatertightRay::new(&ray)
                        .intersect(&packed.triangles[got.triangle as usize], f32::INFINITY);
                    assert!(other.hit && other.t == expected.t);
                }
            }
            assert_eq!(any_hit(&scene, &ray, t_max), expected.is_hit());
        }
        hits
    }

    #[test]
    fn traversal_equals_brute_force_on_random_soups() {
        let mut rng = TestRng(1);
        let mut total_hits = 0;
        for &n in &[1usize, 2, 3, 5, 8, 17, 64, 300, 1000, 5000] {
            let input = soup(n, &mut rng);
            let packed = Packed::new(&input);
            validate(&packed.bvh, &input, 4);
            let rays = if n >= 1000 { 1000 } else { 2000 };
            total_hits += assert_matches_brute_force(&packed, &mut rng, rays);
        }
        assert!(total_hits > 2000, "{total_hits}");
    }

    #[test]
    fn empty_and_single_triangle() {
        let empty = build_bvh(&[], &BvhBuildOptions::default());
        assert!(empty.nodes.is_empty() && empty.triangle_order.is_empty());
        let packed = Packed::new(&[]);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(!closest_hit(&packed.view(), &ray, f32::INFINITY).is_hit());

        let one = [tri(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(1.0, -1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        )];
        let packed = Packed::new(&one);
        assert_eq!(packed.bvh.nodes.len(), 1);
        assert_eq!(packed.bvh.stats.leaf_count, 1);
        assert_eq!(packed.bvh.stats.max_depth, 0);
        validate(&packed.bvh, &one, 4);
        let h = closest_hit(&packed.view(), &ray, f32::INFINITY);
        assert!(h.is_hit() && h.triangle == 0 && (h.t - 2.0).abs() < 1e-6);
        // A single degenerate triangle: a flat or point box, nothing to hit, nothing to break.
        let p = Vec3::new(0.0, 0.0, 2.0);
        let point = [tri(p, p, p)];
        let packed = Packed::new(&point);
        validate(&packed.bvh, &point, 4);
        assert!(!closest_hit(&packed.view(), &ray, f32::INFINITY).is_hit());
    }

    /// Adversarial inputs for the SAH: identical centroids, and centroids on geometric progressions (which
    /// binning can only peel off one at a time). The depth guard keeps the tree within the stack, and
    /// traversal stays exact.
    #[test]
    fn depth_stays_bounded_on_adversarial_input() {
        let mut rng = TestRng(5);
        let mut cases: Vec<Vec<TrianglePositions>> = Vec::new();
        // 20 000 triangles with the same centroid (different shapes and sizes).
        cases.push(
            (0..20_000)
                .map(|_| {
                    // Bounds symmetric about the origin: every centroid is exactly zero.
                    let m = rng.vec(0.1, 1.0);
                    let c = rng.vec(-1.0, 1.0).clamp(-m, m);
                    tri(m, -m, c)
                })
                .collect(),
        );
        // 20 000 copies of one triangle.
        cases.push(vec![tri(Vec3::ZERO, Vec3::X, Vec3::Y); 20_000]);
        // Geometric progressions 2^-i (tiny triangles) and 1.25^i.
        cases.push(
            (0..126)
                .map(|i| {
                    let x = 2f32.powi(-i);
                    tri(
                        Vec3::new(x, 0.0, 0.0),
                        Vec3::new(x, 1.0, 0.0),
                        Vec3::new(x, 0.0, 1.0),
                    )
                })
                .collect(),
        );
        cases.push(
            (0..300)
                .map(|i| {
                    let x = 1.25f32.powi(i);
                    let s = x * 0.01;
                    tri(
                        Vec3::new(x, 0.0, 0.0),
                        Vec3::new(x + s, s, 0.0),
                        Vec3::new(x, 0.0, s),
                    )
                })
                .collect(),
        );
        cases.push(
            (0..4000)
                .map(|i| {
                    let x = 2f32.powf(-(i as f32) * 0.03);
                    tri(
                        Vec3::new(x, -1.0, -1.0),
                        Vec3::new(x, 1.0, -1.0),
                        Vec3::new(x, 0.0, 1.0),
                    )
                })
                .collect(),
        );
        // 1.1^i spans 37 decades: SAH peels off one triangle per level until the depth guard takes over.
        cases.push(
            (0..900)
                .map(|i| {
                    let x = 1.1f32.powi(i);
                    let s = x * 0.01;
                    tri(
                        Vec3::new(x, 0.0, 0.0),
                        Vec3::new(x, s, 0.0),
                        Vec3::new(x, 0.0, s),
                    )
                })
                .collect(),
        );
        // Two bins make binning peel off one progression step per level: a spine as deep as the input is
        // long unless the depth guard steps in.
        let two_bins = BvhBuildOptions {
            bin_count: 2,
            ..BvhBuildOptions::default()
        };
        let mut deepest = 0;
        for (input, options) in cases
            .iter()
            .flat_map(|c| [(c, BvhBuildOptions::default()), (c, two_bins)])
        {
            let packed = Packed::with_options(input, &options);
            validate(&packed.bvh, input, 4);
            deepest = deepest.max(packed.bvh.stats.max_depth);
            assert!((packed.bvh.stats.max_depth as usize) < TRAVERSAL_STACK_SIZE);
            let scene = packed.view();
            for _ in 0..500 {
                let origin = rng.vec(-2.0, 2.0) + Vec3::new(0.5, 0.0, 0.0);
                let ray = Ray::new(origin, rng.unit_vector());
                let expected = brute_force(&packed.triangles, &ray, f32::INFINITY);
                let got = closest_hit(&scene, &ray, f32::INFINITY);
                assert_eq!(got.is_hit(), expected.is_hit());
                assert_eq!(got.t, expected.t);
            }
        }
        // The guard was needed (and used): some tree reached the deepest levels it allows.
        assert!(deepest > MAX_DEPTH - 8, "{deepest}");
    }

    /// Rays from inside a closed, finely tessellated sphere aimed exactly at its vertices and edges never
    /// escape through the BVH either (the conservative slab test keeps the watertight test's hits).
    #[test]
    fn closed_mesh_is_watertight_through_the_bvh() {
        let mut rng = TestRng(9);
        let (rings, segments) = (40usize, 80usize);
        let centre = Vec3::new(3.0, -2.0, 7.5);
        let vertex = |r: usize, s: usize| {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            let phi = 2.0 * std::f32::consts::PI * (s % segments) as f32 / segments as f32;
            if r == 0 || r == rings {
                return centre + Vec3::new(0.0, 0.0, if r == 0 { 2.0 } else { -2.0 });
            }
            centre
                + 2.0
                    * Vec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    )
        };
        let mut mesh = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (
                    vertex(r, s),
                    vertex(r, s + 1),
                    vertex(r + 1, s + 1),
                    vertex(r + 1, s),
                );
                if r != 0 {
                    mesh.push(tri(a, b, d));
                }
                if r != rings - 1 {
                    mesh.push(tri(b, c, d));
                }
            }
        }
        let packed = Packed::new(&mesh);
        validate(&packed.bvh, &mesh, 4);
        let scene = packed.view();
        let mut rays = 0;
        for t in &mesh {
            let v = [vec3_from(t.v0), vec3_from(t.v1), vec3_from(t.v2)];
            for k in 0..3 {
                for target in [
                    v[k],
                    (v[k] + v[(k + 1) % 3]) * 0.5,
                    v[k].lerp(v[(k + 1) % 3], rng.uniform()),
                ] {
                    for origin in [centre, centre + rng.unit_vector() * rng.range(0.0, 1.5)] {
                        let ray = Ray::new(origin, target - origin);
                        assert!(closest_hit(&scene, &ray, f32::INFINITY).is_hit(), "{ray:?}");
                        assert!(any_hit(&scene, &ray, f32::INFINITY));
                        rays += 1;
                    }
                }
            }
        }
        assert!(rays > 50_000);
    }

    #[test]
    fn builds_200k_triangles_quickly() {
        let mut rng = TestRng(77);
        let input = soup(200_000, &mut rng);
        let bvh = build_bvh(&input, &BvhBuildOptions::default());
        eprintln!(
            "200k random triangles: {:.1} ms, {} nodes, {} leaves, depth {}",
            bvh.stats.build_ms, bvh.stats.node_count, bvh.stats.leaf_count, bvh.stats.max_depth
        );
        validate(&bvh, &input, 4);
        // Generous bound (a loaded 2-core machine); the typical time is far lower.
        assert!(bvh.stats.build_ms < 2000.0);
    }
}
