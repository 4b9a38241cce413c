//! BVH construction: a binned-SAH binary tree, built in parallel, collapsed into the 4-wide nodes
//! ([`Bvh4Node`]) that traversal reads.
//!
//! - [`binary`]: the binary builder (Wald 2007), with a depth guard that bounds leaf depth by
//!   [`MAX_DEPTH`].
//! - [`collapse`]: greedy collapse into 4-wide nodes (largest surface area opened first), with a depth
//!   guard that bounds node depth by [`MAX_NODE_DEPTH`], so traversal's fixed stack
//!   ([`TRAVERSAL_STACK_SIZE`] entries, at most `3 D + 4` of them used) cannot overflow.
//!
//! Boxes are widened by a few ulps so that they strictly contain their triangles; leaves keep the binary
//! builder's leaf order, which is the order of the packed triangle arrays.
mod binary;
pub mod blocks;
mod collapse;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use fovea_core::bvh::{MAX_NODE_COUNT, TRAVERSAL_STACK_SIZE};
use fovea_core::scene::Bvh8Node;
use fovea_core::scene::{
    leaf_count, Bvh4Node, BvhNode, TrianglePositions, MAX_LEAF_TRIANGLES, MAX_LEAF_TRIANGLE_INDEX,
};
use glam::Vec3A;
use rayon::prelude::*;

use binary::{build_node, Aabb, Bins, Context, PrimRef, Side, MAX_BINS, PARALLEL_SUBTREE};

const _: () = assert!(MAX_TRIANGLES <= PrimRef::MAX_INDEX as u64);

/// The deepest 4-wide node (root = 0) [`build_bvh`] produces: traversal then needs at most
/// `3 * MAX_NODE_DEPTH + 4 <= TRAVERSAL_STACK_SIZE` stack entries.
pub const MAX_NODE_DEPTH: u32 = (TRAVERSAL_STACK_SIZE as u32 - 4) / 3;

/// The deepest leaf (root = 0) of the intermediate binary tree. The collapse keeps 4-wide node depths
/// below `ceil(MAX_DEPTH / 2)`, hence within [`MAX_NODE_DEPTH`].
pub const MAX_DEPTH: u32 = 2 * (MAX_NODE_DEPTH + 1);

/// Scenes must have fewer triangles than this (134 M): a leaf's slot word keeps its first triangle in 27
/// bits ([`fovea_core::scene::leaf_slot`]). The loaders refuse bigger scenes with an error
/// ([`crate::mesh::LoadOptions::check_size`]).
pub const MAX_TRIANGLES: u64 = MAX_LEAF_TRIANGLE_INDEX as u64;

/// Builder settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhBuildOptions {
    /// Leaves hold at most this many triangles (1 to 16), except when all centroids of a node coincide
    /// (then up to four times this many, since no split can separate them, but never more than a leaf's
    /// slot word can count, [`fovea_core::scene::MAX_LEAF_TRIANGLES`] = 16).
    pub max_leaf_size: u32,
    /// SAH bins per axis (2 to 32).
    pub bin_count: u32,
    /// SAH cost of visiting an interior node.
    pub traversal_cost: f32,
    /// SAH cost of one ray-triangle test.
    pub intersection_cost: f32,
    /// Also collapse the CPU's 8-wide tree ([`Bvh::wide_nodes`]).
    pub wide: bool,
}

impl Default for BvhBuildOptions {
    fn default() -> Self {
        Self {
            max_leaf_size: 4,
            bin_count: 32,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            wide: true,
        }
    }
}

/// What a build produced and how long it took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    pub build_ms: f64,
    /// 4-wide nodes.
    pub node_count: usize,
    pub leaf_count: usize,
    /// Depth of the deepest 4-wide node; the root alone has depth 0 (its leaves hang below it).
    pub max_depth: u32,
    /// Depth of the deepest leaf of the intermediate binary tree (root = 0).
    pub binary_max_depth: u32,
    /// Bytes of the node arrays (4-wide and 8-wide).
    pub memory_bytes: usize,
    /// Nodes of the CPU's 8-wide tree ([`Bvh::wide_nodes`]); 0 when it was not built.
    pub wide_node_count: usize,
    /// SAH cost of the 4-wide tree (see [`sah_cost`]) with the build's traversal and intersection costs:
    /// the expected cost of a random ray through the root, for comparing builder settings.
    pub sah_cost: f64,
}

/// The surface area heuristic cost of a 4-wide tree (MacDonald and Booth 1990) of a built BVH (leaves
/// name triangles): every node visit costs `traversal_cost` and every test of a leaf block (up to four
/// triangles at once) `intersection_cost`, each weighted by the probability that
/// a random ray through the root's box enters the box of the node or leaf (ratio of surface areas). The
/// root is always visited; an empty tree costs 0.
#[must_use]
pub fn sah_cost(nodes: &[Bvh4Node], traversal_cost: f64, intersection_cost: f64) -> f64 {
    let Some(root) = nodes.first() else {
        return 0.0;
    };
    let half_area = |node: &Bvh4Node, slot: usize| -> f64 {
        let d = [
            f64::from(node.max_x[slot] - node.min_x[slot]),
            f64::from(node.max_y[slot] - node.min_y[slot]),
            f64::from(node.max_z[slot] - node.min_z[slot]),
        ];
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    };
    let mut lo = [f32::MAX; 3];
    let mut hi = [-f32::MAX; 3];
    for slot in (0..4).filter(|&s| !root.is_empty_slot(s)) {
        lo = [
            lo[0].min(root.min_x[slot]),
            lo[1].min(root.min_y[slot]),
            lo[2].min(root.min_z[slot]),
        ];
        hi = [
            hi[0].max(root.max_x[slot]),
            hi[1].max(root.max_y[slot]),
            hi[2].max(root.max_z[slot]),
        ];
    }
    let d = [0, 1, 2].map(|k| f64::from(hi[k] - lo[k]).max(0.0));
    let root_area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    if root_area <= 0.0 {
        return traversal_cost;
    }
    let mut weighted = 0.0;
    for node in nodes {
        for slot in (0..4).filter(|&s| !node.is_empty_slot(s)) {
            let cost = if node.is_leaf_slot(slot) {
                intersection_cost * blocks::blocks_for(leaf_count(node.slot(slot)) as usize) as f64
            } else {
                traversal_cost
            };
            weighted += half_area(node, slot) * cost;
        }
    }
    traversal_cost + weighted / root_area
}

/// A built BVH in traversal layout (see [`Bvh4Node`]).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<Bvh4Node>,
    /// The CPU's 8-wide tree over the same leaves (empty unless [`BvhBuildOptions::wide`]).
    pub wide_nodes: Vec<Bvh8Node>,
    /// `triangle_order[i]` is the input index of the triangle stored at position `i` of the leaf-ordered
    /// triangle arrays.
    pub triangle_order: Vec<u32>,
    pub stats: BvhStats,
}

/// Builds a BVH over `triangles` with binned SAH and collapses it to 4-wide nodes (see the module
/// documentation). An empty input gives an empty node array; degenerate triangles are accepted (their
/// boxes are flat or points).
#[must_use]
pub fn build_bvh(triangles: &[TrianglePositions], options: &BvhBuildOptions) -> Bvh {
    build_over_bounds(
        triangles.len(),
        |i| {
            let t = &triangles[i];
            triangle_bounds(
                Vec3A::from_vec4(t.v0),
                Vec3A::from_vec4(t.v1),
                Vec3A::from_vec4(t.v2),
            )
        },
        options,
    )
}

/// [`build_bvh`] over an indexed mesh: triangle `i` has the vertices `positions[triangles[i][k]]`. The
/// same tree as `build_bvh` over the mesh's [`TrianglePositions`], without that 48-byte-per-triangle copy
/// (the packer's peak memory is the build's).
///
/// # Panics
/// If a vertex index is out of bounds (the loaders validate them).
#[must_use]
pub fn build_bvh_indexed(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    options: &BvhBuildOptions,
) -> Bvh {
    build_over_bounds(
        triangles.len(),
        |i| {
            let [a, b, c] = triangles[i].map(|v| Vec3A::from_array(positions[v as usize]));
            triangle_bounds(a, b, c)
        },
        options,
    )
}

/// The bounds of the triangle `a b c`.
#[inline]
fn triangle_bounds(a: Vec3A, b: Vec3A, c: Vec3A) -> Aabb {
    Aabb {
        min: a.min(b).min(c),
        max: a.max(b).max(c),
    }
}

/// The build over `n` triangles whose bounds `bounds(i)` gives.
fn build_over_bounds(
    n: usize,
    bounds: impl Fn(usize) -> Aabb + Sync,
    options: &BvhBuildOptions,
) -> Bvh {
    let start = Instant::now();
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
        n < MAX_TRIANGLES as usize,
        "too many triangles for the BVH builder (the loaders stop at MAX_TRIANGLES)"
    );
    // A leaf's slot word can count up to MAX_LEAF_TRIANGLES triangles.
    let limit = MAX_LEAF_TRIANGLES as usize;
    let max_leaf = (options.max_leaf_size as usize).clamp(1, limit);
    let ctx = Context {
        bins: (options.bin_count as usize).clamp(2, MAX_BINS),
        max_leaf,
        coincident_leaf: (4 * max_leaf).min(limit),
        traversal_cost: options.traversal_cost.max(0.0),
        intersection_cost: options.intersection_cost.max(1e-6),
        leaves: AtomicUsize::new(0),
    };

    let mut prims: Vec<PrimRef> = (0..n)
        .into_par_iter()
        .map(|i| PrimRef::new(bounds(i), i as u32))
        .collect();
    let root = Side::of(&prims);
    // Zeroed by the allocator, not written: the pages `build_node` never touches cost no memory.
    let mut arena: Vec<BvhNode> = bytemuck::zeroed_vec(2 * n - 1);
    let mut bins = Bins::empty();
    let span = build_node(&ctx, &mut prims, &mut arena, 0, root, 0, &mut bins);
    // A tree built sequentially throughout is packed: its 2L - 1 nodes fill the arena's first slots.
    let leaves = ctx.leaves.load(Ordering::Relaxed);
    debug_assert!(
        n > PARALLEL_SUBTREE || span == 2 * leaves - 1,
        "{span} slots, {leaves} leaves"
    );

    let mut stats = BvhStats::default();
    let (nodes, wide_nodes) = collapse::collapse(&arena, leaves, options.wide, &mut stats);
    drop(arena);
    assert!(
        nodes.len() < MAX_NODE_COUNT,
        "too many BVH nodes for traversal's stack entries"
    );
    let triangle_order: Vec<u32> = prims.par_iter().map(PrimRef::index).collect();

    stats.node_count = nodes.len();
    stats.wide_node_count = wide_nodes.len();
    stats.memory_bytes = std::mem::size_of_val(&nodes[..]) + std::mem::size_of_val(&wide_nodes[..]);
    stats.sah_cost = sah_cost(
        &nodes,
        f64::from(ctx.traversal_cost),
        f64::from(ctx.intersection_cost),
    );
    stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
    Bvh {
        nodes,
        wide_nodes,
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
    use fovea_core::scene::Bvh8Node;
    use fovea_core::scene::{leaf_first, leaf_slot, SLOT_EMPTY};
    use fovea_core::scene::{
        GeometryArrays, Material, MaterialArrays, SceneView, TriangleBlock, TriangleInfo,
    };
    use glam::{UVec4, Vec3, Vec4};

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
            v0: a.extend(0.0),
            v1: b.extend(0.0),
            v2: c.extend(0.0),
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

    /// A built BVH (leaves name triangles, as [`validate`] checks) and its packed traversal form.
    struct Packed {
        bvh: Bvh,
        nodes: Vec<Bvh4Node>,
        /// The CPU's 8-wide tree over the same leaves as `nodes`.
        wide_nodes: Vec<Bvh8Node>,
        /// Positions in leaf order (what the blocks hold).
        triangles: Vec<TrianglePositions>,
        blocks: Vec<TriangleBlock>,
        triangle_lanes: Vec<u32>,
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
            let mut nodes = bvh.nodes.clone();
            let packed =
                blocks::pack_leaf_blocks(&mut nodes, triangles.len(), |i| triangles[i], |_| false);
            let mut wide_nodes = bvh.wide_nodes.clone();
            blocks::name_wide_leaf_blocks(&mut wide_nodes, &packed.triangle_lanes);
            validate_wide(&nodes, &wide_nodes);
            Self {
                bvh,
                nodes,
                wide_nodes,
                triangles,
                blocks: packed.blocks,
                triangle_lanes: packed.triangle_lanes,
                info,
                materials: vec![Material::default()],
            }
        }

        fn view(&self) -> SceneView<'_> {
            SceneView {
                geometry: GeometryArrays {
                    nodes: &self.nodes,
                    triangle_lanes: &self.triangle_lanes,
                    blocks: &self.blocks,
                    triangle_info: &self.info,
                    ..GeometryArrays::default()
                },
                materials: MaterialArrays {
                    list: &self.materials,
                    ..MaterialArrays::default()
                },
                ..SceneView::empty()
            }
        }

        /// [`Self::view`] with the 8-wide tree, which traversal then takes instead.
        fn wide_view(&self) -> SceneView<'_> {
            let view = self.view();
            SceneView {
                geometry: GeometryArrays {
                    wide_nodes: &self.wide_nodes,
                    ..view.geometry
                },
                ..view
            }
        }
    }

    /// Checks a packed 8-wide tree against the packed 4-wide tree of the same build: the same leaf
    /// words, each once; every interior slot's box contains its node's boxes; no node deeper than
    /// traversal's stack allows; every node reached once; and fewer nodes.
    fn validate_wide(nodes: &[Bvh4Node], wide_nodes: &[Bvh8Node]) {
        use fovea_core::bvh::wide::MAX_WIDE_DEPTH;
        let mut leaves4: Vec<u32> = nodes
            .iter()
            .flat_map(|n| (0..4).filter(|&s| n.is_leaf_slot(s)).map(|s| n.slot(s)))
            .collect();
        assert_eq!(nodes.is_empty(), wide_nodes.is_empty());
        if nodes.is_empty() {
            return;
        }
        assert!(wide_nodes.len() <= nodes.len());
        let mut leaves8 = Vec::new();
        let mut reached = vec![false; wide_nodes.len()];
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            assert!(!reached[i], "node {i} reached twice");
            reached[i] = true;
            assert!(depth <= MAX_WIDE_DEPTH, "depth {depth}");
            let node = &wide_nodes[i];
            for slot in 0..8 {
                let word = node.slots[slot];
                if word == SLOT_EMPTY {
                    let (lo, hi) = node.slot_bounds(slot);
                    assert!((0..3).all(|k| lo[k] > hi[k]), "empty slot with a box");
                } else if fovea_core::scene::is_leaf_word(word) {
                    leaves8.push(word);
                } else {
                    let child = &wide_nodes[word as usize];
                    let (lo, hi) = node.slot_bounds(slot);
                    for k in 0..3 {
                        let (mut clo, mut chi) = (f32::MAX, -f32::MAX);
                        for s in (0..8).filter(|&s| child.slots[s] != SLOT_EMPTY) {
                            let (a, b) = child.slot_bounds(s);
                            clo = clo.min(a[k]);
                            chi = chi.max(b[k]);
                        }
                        assert!(lo[k] <= clo && chi <= hi[k], "child box outside its slot");
                    }
                    stack.push((word as usize, depth + 1));
                }
            }
        }
        assert!(reached.iter().all(|&r| r), "unreachable 8-wide nodes");
        leaves4.sort_unstable();
        leaves8.sort_unstable();
        assert_eq!(leaves4, leaves8);
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

    /// What [`validate`]'s walk has seen so far.
    struct Walk<'a> {
        bvh: &'a Bvh,
        input: &'a [TrianglePositions],
        max_leaf: usize,
        reached: Vec<bool>,
        next_expected_child: usize,
        next_triangle: usize,
        leaves: usize,
        max_depth: u32,
    }

    impl Walk<'_> {
        /// Checks node `i` and, slot by slot, its subtrees (recursively, so leaves are met in leaf
        /// order).
        fn node(&mut self, i: usize, depth: u32) {
            assert!(!self.reached[i], "node {i} reached twice");
            self.reached[i] = true;
            self.max_depth = self.max_depth.max(depth);
            let node = self.bvh.nodes[i];
            let used = (0..4).take_while(|&s| !node.is_empty_slot(s)).count();
            assert!(
                used >= 1 && (i == 0 || used >= 2),
                "node {i} has {used} children"
            );
            // The builder allocates a node's interior children together when it writes the node,
            // depth first.
            for slot in 0..used {
                if node.is_interior_slot(slot) {
                    assert_eq!(node.slot(slot) as usize, self.next_expected_child);
                    self.next_expected_child += 1;
                }
            }
            for slot in 0..4 {
                let (lo, hi) = node.slot_bounds(slot);
                let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
                if slot >= used {
                    assert!(node.is_empty_slot(slot), "empty slots come last");
                    assert!(lo.cmpgt(hi).all(), "empty slots are inverted");
                } else if node.is_leaf_slot(slot) {
                    let word = node.slot(slot);
                    self.leaf(leaf_first(word) as usize, leaf_count(word) as usize, lo, hi);
                } else {
                    let c = node.slot(slot) as usize;
                    let child = self.bvh.nodes[c];
                    for s in 0..4 {
                        if !child.is_empty_slot(s) {
                            let (clo, chi) = child.slot_bounds(s);
                            assert!(
                                Vec3::from(clo).cmpge(lo).all() && Vec3::from(chi).cmple(hi).all()
                            );
                        }
                    }
                    self.node(c, depth + 1);
                }
            }
        }

        fn leaf(&mut self, first: usize, count: usize, lo: Vec3, hi: Vec3) {
            self.leaves += 1;
            let range = first..first + count;
            assert_eq!(range.start, self.next_triangle, "leaves out of leaf order");
            self.next_triangle = range.end;
            let centroid = |k: usize| {
                let t = &self.input[self.bvh.triangle_order[k] as usize];
                let (a, b, c) = (t.v0.truncate(), t.v1.truncate(), t.v2.truncate());
                a.min(b).min(c) + a.max(b).max(c)
            };
            let coincident = range.clone().all(|k| centroid(k) == centroid(range.start));
            assert!(
                count >= 1
                    && count <= MAX_LEAF_TRIANGLES as usize
                    && (count <= self.max_leaf || (coincident && count <= 4 * self.max_leaf))
            );
            for k in range {
                let t = &self.input[self.bvh.triangle_order[k] as usize];
                for v in [t.v0, t.v1, t.v2] {
                    let v = v.truncate();
                    assert!(
                        v.cmpgt(lo).all() && v.cmplt(hi).all(),
                        "{v:?} not strictly in {lo:?}..{hi:?}"
                    );
                }
            }
        }
    }

    /// Checks the layout invariants: every node reached exactly once, interior children stored together
    /// (depth first), empty slots inverted and after the used ones, leaf ranges met in leaf order and
    /// together covering all triangles once, every box strictly containing its triangles and its child
    /// node's boxes, leaf sizes bounded, and the reported depths and counts exact and within the stack
    /// bound.
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
        assert_eq!(
            bvh.stats.memory_bytes,
            bvh.nodes.len() * std::mem::size_of::<Bvh4Node>()
                + bvh.wide_nodes.len() * std::mem::size_of::<Bvh8Node>()
        );
        let mut walk = Walk {
            bvh,
            input,
            max_leaf,
            reached: vec![false; bvh.nodes.len()],
            next_expected_child: 1,
            next_triangle: 0,
            leaves: 0,
            max_depth: 0,
        };
        walk.node(0, 0);
        assert_eq!(walk.next_triangle, n, "leaves do not cover all triangles");
        assert!(walk.reached.iter().all(|&r| r), "unreachable nodes");
        assert_eq!(walk.leaves, bvh.stats.leaf_count);
        assert_eq!(walk.max_depth, bvh.stats.max_depth);
        assert!(bvh.stats.max_depth <= MAX_NODE_DEPTH);
        assert!(3 * bvh.stats.max_depth as usize + 4 <= TRAVERSAL_STACK_SIZE);
        assert!(bvh.stats.binary_max_depth <= MAX_DEPTH);
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
                    t.v0.truncate() * (1.0 - b1 - b2) + t.v1.truncate() * b1 + t.v2.truncate() * b2;
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
            // The 8-wide tree finds the same.
            let wide = closest_hit(&packed.wide_view(), &ray, t_max);
            assert_eq!(wide.is_hit(), expected.is_hit(), "{ray:?} {t_max}");
            assert_eq!(wide.t, expected.t, "{ray:?}");
            if wide.triangle != expected.triangle {
                let other = WatertightRay::new(&ray)
                    .intersect(&packed.triangles[wide.triangle as usize], f32::INFINITY);
                assert!(other.hit && other.t == expected.t);
            }
            assert_eq!(any_hit(&packed.wide_view(), &ray, t_max), expected.is_hit());
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
    fn sah_cost_of_known_trees() {
        // Two stacked triangles stay one leaf, one block (SAH: a split costs 1 + (1 + 1) / 2 = 2, more
        // than the leaf's one block test), so the tree costs one root visit plus one block test.
        let tri = |z: f32| TrianglePositions {
            v0: Vec4::new(0.0, 0.0, z, 0.0),
            v1: Vec4::new(1.0, 0.0, z, 0.0),
            v2: Vec4::new(0.0, 1.0, z, 0.0),
        };
        let two = build_bvh(&[tri(0.0), tri(0.5)], &BvhBuildOptions::default());
        let cost = two.stats.sah_cost;
        assert!((cost - 2.0).abs() < 1e-6, "{cost}");
        let mut root = Bvh4Node::EMPTY;
        root.min_x = Vec4::new(0.0, 0.0, f32::MAX, f32::MAX);
        root.max_x = Vec4::new(1.0, 1.0, -f32::MAX, -f32::MAX);
        root.min_y = Vec4::new(0.0, 0.0, f32::MAX, f32::MAX);
        root.max_y = Vec4::new(1.0, 1.0, -f32::MAX, -f32::MAX);
        root.min_z = Vec4::new(0.0, 0.5, f32::MAX, f32::MAX);
        root.max_z = Vec4::new(0.5, 1.0, -f32::MAX, -f32::MAX);
        root.slots = UVec4::new(leaf_slot(0, 3), leaf_slot(3, 5), SLOT_EMPTY, SLOT_EMPTY);
        // Unit cube root (half area 3); two leaves of half area 1 + 0.5 + 0.5 = 2 each, of one block (3
        // triangles) and two blocks (5).
        let expected = 1.0 + (2.0 * 1.0 + 2.0 * 2.0) / 3.0;
        assert!((sah_cost(&[root], 1.0, 1.0) - expected).abs() < 1e-9);
        assert_eq!(sah_cost(&[], 1.0, 1.0), 0.0);
        // The metric ranks builder settings: 32 bins beat 2 on a random soup.
        let mut rng = TestRng(9);
        let input = soup(2000, &mut rng);
        let fine = build_bvh(&input, &BvhBuildOptions::default())
            .stats
            .sah_cost;
        let coarse = build_bvh(
            &input,
            &BvhBuildOptions {
                bin_count: 2,
                ..BvhBuildOptions::default()
            },
        )
        .stats
        .sah_cost;
        assert!(fine < coarse, "32 bins {fine} vs 2 bins {coarse}");
    }

    /// Every triangle sits in exactly one block lane, which `triangle_lanes` names and whose `index`
    /// word names the triangle back; shading reads the same positions the builder was given.
    #[test]
    fn triangle_lanes_name_each_triangle_s_block_lane() {
        use fovea_core::scene::{block_and_lane, SceneSlices, SceneSource, BLOCK_LANE_CUTOUT};
        let mut rng = TestRng(21);
        let packed = Packed::new(&soup(3000, &mut rng));
        let view = packed.view();
        for (i, t) in packed.triangles.iter().enumerate() {
            assert_eq!(SceneSlices.triangle(&view, i as u32), *t);
            let (block, lane) = block_and_lane(packed.triangle_lanes[i]);
            let word = packed.blocks[block as usize].index[lane];
            assert_eq!(word & !BLOCK_LANE_CUTOUT, i as u32);
        }
        let mut lanes = packed.triangle_lanes.clone();
        lanes.sort_unstable();
        lanes.dedup();
        assert_eq!(lanes.len(), packed.triangles.len());
    }

    /// The indexed build gives the same tree as the build over copied triangle positions, on a mesh
    /// whose triangles share vertices.
    #[test]
    fn indexed_build_matches_positions_build() {
        let mut rng = TestRng(31);
        let positions: Vec<[f32; 3]> = (0..600).map(|_| rng.vec(-10.0, 10.0).to_array()).collect();
        let pick = |rng: &mut TestRng| (rng.next_u64() % positions.len() as u64) as u32;
        let triangles: Vec<[u32; 3]> = (0..1500)
            .map(|_| [pick(&mut rng), pick(&mut rng), pick(&mut rng)])
            .collect();
        let copied: Vec<TrianglePositions> = triangles
            .iter()
            .map(|t| {
                let [v0, v1, v2] = t.map(|i| Vec3::from(positions[i as usize]).extend(0.0));
                TrianglePositions { v0, v1, v2 }
            })
            .collect();
        let options = BvhBuildOptions::default();
        let indexed = build_bvh_indexed(&positions, &triangles, &options);
        let reference = build_bvh(&copied, &options);
        assert_eq!(indexed.triangle_order, reference.triangle_order);
        assert_eq!(indexed.nodes, reference.nodes);
        assert!(build_bvh_indexed(&positions, &[], &options)
            .nodes
            .is_empty());
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
        assert_eq!(packed.bvh.stats.binary_max_depth, 0);
        assert!(packed.bvh.nodes[0].is_leaf_slot(0));
        assert!((1..4).all(|s| packed.bvh.nodes[0].is_empty_slot(s)));
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
        let mut deepest4 = 0;
        for (input, options) in cases
            .iter()
            .flat_map(|c| [(c, BvhBuildOptions::default()), (c, two_bins)])
        {
            let packed = Packed::with_options(input, &options);
            validate(&packed.bvh, input, 4);
            deepest = deepest.max(packed.bvh.stats.binary_max_depth);
            deepest4 = deepest4.max(packed.bvh.stats.max_depth);
            let scene = packed.view();
            for _ in 0..500 {
                let origin = rng.vec(-2.0, 2.0) + Vec3::new(0.5, 0.0, 0.0);
                let ray = Ray::new(origin, rng.unit_vector());
                let expected = brute_force(&packed.triangles, &ray, f32::INFINITY);
                let got = closest_hit(&scene, &ray, f32::INFINITY);
                assert_eq!(got.is_hit(), expected.is_hit());
                assert_eq!(got.t, expected.t);
                let wide = closest_hit(&packed.wide_view(), &ray, f32::INFINITY);
                assert_eq!(wide.t, expected.t);
            }
        }
        // The guards were needed (and used): some tree reached the deepest levels they allow.
        assert!(deepest > MAX_DEPTH - 8, "{deepest}");
        assert!(deepest4 > MAX_NODE_DEPTH - 4, "{deepest4}");
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
        let wide = packed.wide_view();
        let mut rays = 0;
        for t in &mesh {
            let v = [t.v0.truncate(), t.v1.truncate(), t.v2.truncate()];
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
                        assert!(closest_hit(&wide, &ray, f32::INFINITY).is_hit(), "{ray:?}");
                        assert!(any_hit(&wide, &ray, f32::INFINITY));
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
            "200k random triangles: {:.1} ms, {} nodes, {} leaves, depth {} (binary {})",
            bvh.stats.build_ms,
            bvh.stats.node_count,
            bvh.stats.leaf_count,
            bvh.stats.max_depth,
            bvh.stats.binary_max_depth
        );
        validate(&bvh, &input, 4);
        // Generous bound (a loaded 2-core machine); the typical time is far lower.
        assert!(bvh.stats.build_ms < 2000.0);
    }
}
