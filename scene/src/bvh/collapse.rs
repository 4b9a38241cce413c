//! Collapsing the binary BVH into the 4-wide [`Bvh4Node`] layout both backends traverse, and into the
//! CPU's 8-wide [`Bvh8Node`] layout.
//!
//! Each wide node starts from the two children of a binary node and greedily opens the interior
//! candidate with the largest surface area (replacing it by its two children) until it has four (eight)
//! children or only leaves are left (Wald, Benthin, Boulos 2008; Pharr, "collapsing" a binary BVH;
//! Embree builds its BVH8 the same way). Leaves stay the binary leaves, so the triangles keep their leaf
//! order and both trees have the very same leaves.
//!
//! **Depth guard.** Traversal's stack bounds the depth of the 4-wide tree (see
//! [`fovea_core::bvh::TRAVERSAL_STACK_SIZE`]). Let `h` be a binary node's height (leaf = 0) and `d` the
//! depth of the 4-wide node made from it. The collapse keeps `d + ceil(h / 2) <= ceil(MAX_DEPTH / 2)`:
//! a greedy choice is taken only if every interior child satisfies it; otherwise the node first opens
//! every interior child of its binary node (so every interior child is at least two binary levels down,
//! `h' <= h - 2`, and the bound carries over), then continues greedily. Interior nodes have `h >= 1`, so
//! 4-wide node depths stay below `ceil(MAX_DEPTH / 2) = MAX_NODE_DEPTH + 1`. The same guard holds for the
//! 8-wide tree (opening more candidates only lowers their heights), whose depth is then within
//! [`fovea_core::bvh::wide::MAX_WIDE_DEPTH`] too.
use fovea_core::scene::Bvh8Node;
use fovea_core::scene::{leaf_slot, Bvh4Node, BvhNode};

use super::{BvhStats, MAX_DEPTH};

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

/// `ceil(h / 2)`.
#[inline]
fn half_up(h: u32) -> u32 {
    h.div_ceil(2)
}

/// The binary arena of [`super::binary::build_node`]: slot 0 the root; an interior node at slot `s`
/// stores the offset `r` of its right child in `left_or_first`: its children sit at `s + 1` and
/// `s + r`.
struct Arena<'a> {
    nodes: &'a [BvhNode],
    /// Height of each used slot's subtree (leaf = 0).
    heights: Vec<u8>,
}

impl<'a> Arena<'a> {
    fn new(nodes: &'a [BvhNode]) -> Self {
        let mut arena = Self {
            nodes,
            heights: vec![0; nodes.len()],
        };
        arena.compute_height(0);
        arena
    }

    /// Fills `heights` for the subtree at `slot` and returns its height (recursion depth is bounded by
    /// the binary builder's depth guard).
    fn compute_height(&mut self, slot: usize) -> u32 {
        if self.nodes[slot].is_leaf() {
            return 0;
        }
        let (l, r) = self.children(slot);
        let h = 1 + self.compute_height(l).max(self.compute_height(r));
        self.heights[slot] = h as u8;
        h
    }

    #[inline]
    fn children(&self, slot: usize) -> (usize, usize) {
        (slot + 1, slot + self.nodes[slot].left_or_first as usize)
    }

    #[inline]
    fn height(&self, slot: usize) -> u32 {
        u32::from(self.heights[slot])
    }

    #[inline]
    fn half_area(&self, slot: usize) -> f32 {
        let n = &self.nodes[slot];
        let d = [
            (n.bounds_max[0] - n.bounds_min[0]).max(0.0),
            (n.bounds_max[1] - n.bounds_min[1]).max(0.0),
            (n.bounds_max[2] - n.bounds_min[2]).max(0.0),
        ];
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
}

/// A wide node layout the collapse writes: slots each holding a box and a slot word.
pub(super) trait WideNode: Copy {
    const EMPTY: Self;
    fn set_slot(&mut self, i: usize, min: [f32; 3], max: [f32; 3], word: u32);
}

macro_rules! impl_wide_node {
    ($($node:ty),*) => {$(
        impl WideNode for $node {
            const EMPTY: Self = <$node>::EMPTY;
            fn set_slot(&mut self, i: usize, min: [f32; 3], max: [f32; 3], word: u32) {
                self.set_slot_bounds(i, min, max);
                self.slots[i] = word;
            }
        }
    )*};
}
impl_wide_node!(Bvh4Node, Bvh8Node);

/// Up to `N` binary slots that become one `N`-wide node's children, in leaf order.
#[derive(Clone, Copy)]
struct Candidates<const N: usize> {
    slots: [usize; N],
    len: usize,
}

impl<const N: usize> Candidates<N> {
    /// Replaces candidate `i` by its two binary children (in place, keeping the leaf order).
    fn open(&mut self, arena: &Arena, i: usize) {
        let (l, r) = arena.children(self.slots[i]);
        for k in (i + 1..self.len).rev() {
            self.slots[k + 1] = self.slots[k];
        }
        self.slots[i] = l;
        self.slots[i + 1] = r;
        self.len += 1;
    }

    /// Opens the interior candidate of largest surface area until there are `N` or none is left.
    fn open_greedily(&mut self, arena: &Arena) {
        while self.len < N {
            let mut best = usize::MAX;
            let mut best_area = f32::NEG_INFINITY;
            for i in 0..self.len {
                let s = self.slots[i];
                if !arena.nodes[s].is_leaf() && arena.half_area(s) > best_area {
                    best = i;
                    best_area = arena.half_area(s);
                }
            }
            if best == usize::MAX {
                return;
            }
            self.open(arena, best);
        }
    }

    /// The children of the `N`-wide node made from binary `slot` at depth `depth` (see the module
    /// documentation for the depth guard).
    fn of(arena: &Arena, slot: usize, depth: u32) -> Self {
        let mut slots = [0; N];
        slots[0] = slot;
        let mut c = Self { slots, len: 1 };
        if arena.nodes[slot].is_leaf() {
            // Only a root can be a leaf: a one-leaf tree.
            return c;
        }
        c.open(arena, 0);
        let start = c;
        c.open_greedily(arena);
        let limit = half_up(MAX_DEPTH);
        let within = (0..c.len).all(|i| {
            let s = c.slots[i];
            arena.nodes[s].is_leaf() || depth + 1 + half_up(arena.height(s)) <= limit
        });
        if within {
            return c;
        }
        // Depth guard: every interior child two binary levels down (at most two opens, four slots).
        c = start;
        let mut i = 0;
        while i < c.len {
            if arena.nodes[c.slots[i]].is_leaf() {
                i += 1;
            } else {
                c.open(arena, i);
                i += 2;
            }
        }
        c.open_greedily(arena);
        c
    }
}

/// Collapses the binary tree in `arena` (see [`super::binary::build_node`]) into 4-wide nodes and, with
/// `wide`, 8-wide nodes as well (else an empty array): node 0 is the root, the interior children of a
/// node are stored next to each other and after it (depth first). Leaf slot words name the binary
/// leaves' triangle ranges. Fills the node, leaf and depth fields of `stats` (of the 4-wide tree).
pub(super) fn collapse(
    arena: &[BvhNode],
    leaf_count: usize,
    wide: bool,
    stats: &mut BvhStats,
) -> (Vec<Bvh4Node>, Vec<Bvh8Node>) {
    let arena = Arena::new(arena);
    stats.binary_max_depth = arena.height(0);
    // The two collapses read the same arena; on two threads the 8-wide one costs no extra time.
    let ((nodes, leaves, depth), wide_nodes) = rayon::join(
        || collapse_to::<Bvh4Node, 4>(&arena, leaf_count),
        || {
            if wide {
                collapse_to::<Bvh8Node, 8>(&arena, leaf_count).0
            } else {
                Vec::new()
            }
        },
    );
    stats.leaf_count = leaves;
    stats.max_depth = depth;
    (nodes, wide_nodes)
}

/// The `N`-wide tree of `T` nodes (`T` must have `N` slots) over `arena`, its leaf count and its
/// deepest node's depth.
fn collapse_to<T: WideNode, const N: usize>(
    arena: &Arena,
    leaf_count: usize,
) -> (Vec<T>, usize, u32) {
    // An N-wide tree over `n` leaves has at most `n - 1` nodes, typically about `n / (N - 1.5)`.
    let mut nodes = Vec::with_capacity(leaf_count / (N / 2) + 1);
    nodes.push(T::EMPTY);
    let (mut leaves, mut max_depth) = (0, 0);
    let mut stack = vec![(0usize, 0usize, 0u32)];
    while let Some((slot, position, depth)) = stack.pop() {
        let c = Candidates::<N>::of(arena, slot, depth);
        max_depth = max_depth.max(depth);
        let mut node = T::EMPTY;
        let first_child = nodes.len();
        let mut interior = 0;
        for i in 0..c.len {
            let b = &arena.nodes[c.slots[i]];
            let (min, max) = (b.bounds_min.map(widen_down), b.bounds_max.map(widen_up));
            if b.is_leaf() {
                node.set_slot(i, min, max, leaf_slot(b.left_or_first, b.triangle_count));
                leaves += 1;
            } else {
                node.set_slot(i, min, max, (first_child + interior) as u32);
                interior += 1;
            }
        }
        nodes[position] = node;
        nodes.resize(first_child + interior, T::EMPTY);
        // Push in reverse so the first child's subtree is written first (depth-first order).
        let mut k = interior;
        for i in (0..c.len).rev() {
            if !arena.nodes[c.slots[i]].is_leaf() {
                k -= 1;
                stack.push((c.slots[i], first_child + k, depth + 1));
            }
        }
    }
    (nodes, leaves, max_depth)
}
