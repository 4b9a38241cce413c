//! Leaf blocks: every leaf's triangles four at a time, in the structure-of-arrays layout traversal tests
//! them in ([`TriangleBlock`]).
use fovea_core::scene::Bvh8Node;
use fovea_core::scene::{
    block_and_lane, is_leaf_word, leaf_count, leaf_first, leaf_slot, triangle_lane, Bvh4Node,
    TriangleBlock, TrianglePositions, BLOCK_LANE_CUTOUT,
};

/// Triangles per block.
pub const BLOCK_LANES: usize = 4;

/// Blocks a leaf of `triangles` triangles takes.
#[inline]
#[must_use]
pub fn blocks_for(triangles: usize) -> usize {
    triangles.div_ceil(BLOCK_LANES)
}

/// The leaf slots of `node` in slot order, each as `(slot, first, count)`: its slot index and
/// [`leaf_first`] and [`leaf_count`] of its word (triangles in a built BVH, blocks once packed). The
/// iterator holds a copy of the node, so the caller may rewrite the slots it names.
pub fn leaf_slots(node: &Bvh4Node) -> impl Iterator<Item = (usize, usize, usize)> {
    let node = *node;
    (0..4)
        .filter(move |&slot| node.is_leaf_slot(slot))
        .map(move |slot| {
            let word = node.slot(slot);
            (slot, leaf_first(word) as usize, leaf_count(word) as usize)
        })
}

/// The leaves' triangles in blocks, and where each triangle went.
#[derive(Clone, Debug, Default)]
pub struct LeafBlocks {
    /// Every leaf's triangles, four to a block, in leaf order.
    pub blocks: Vec<TriangleBlock>,
    /// For each triangle, its block and lane ([`triangle_lane`]): `GeometryArrays::triangle_lanes`.
    pub triangle_lanes: Vec<u32>,
}

/// Rewrites every leaf slot of `nodes` (a built BVH, whose leaves name the leaf-ordered triangles
/// `0 .. triangle_count`) to name the first of the blocks that hold its triangles (the count stays the
/// triangle count), and returns those blocks. `triangle(i)` gives triangle `i`'s positions and
/// `cut_out(i)` says whether its material has an alpha cut-out ([`BLOCK_LANE_CUTOUT`]).
pub fn pack_leaf_blocks(
    nodes: &mut [Bvh4Node],
    triangle_count: usize,
    triangle: impl Fn(usize) -> TrianglePositions,
    cut_out: impl Fn(usize) -> bool,
) -> LeafBlocks {
    // Leaves are contiguous, disjoint ranges covering the triangles: mark each leaf's length at its
    // first triangle, then number the blocks in one pass in leaf order.
    let mut leaf_length = vec![0u8; triangle_count];
    for node in nodes.iter() {
        for (_, first, count) in leaf_slots(node) {
            leaf_length[first] = count as u8;
        }
    }
    let block_count = leaf_length.iter().map(|&n| blocks_for(n.into())).sum();
    let mut blocks = Vec::with_capacity(block_count);
    let mut triangle_lanes = Vec::with_capacity(triangle_count);
    let mut i = 0;
    while i < triangle_count {
        let count = usize::from(leaf_length[i]).max(1);
        for k in 0..count {
            if k % BLOCK_LANES == 0 {
                blocks.push(TriangleBlock::EMPTY);
            }
            let index = (i + k) as u32 | if cut_out(i + k) { BLOCK_LANE_CUTOUT } else { 0 };
            let lane = k % BLOCK_LANES;
            let block = blocks.last_mut().expect("a block was just pushed");
            block.set_lane(lane, &triangle(i + k), index);
            triangle_lanes.push(triangle_lane(blocks.len() as u32 - 1, lane as u32));
        }
        i += count;
    }
    for node in nodes.iter_mut() {
        for (slot, _, _) in leaf_slots(node) {
            node.slots[slot] = leaf_word_naming_blocks(node.slot(slot), &triangle_lanes);
        }
    }
    LeafBlocks {
        blocks,
        triangle_lanes,
    }
}

/// Rewrites the leaf slots of the 8-wide tree `wide_nodes` (built over the same leaves as the 4-wide tree
/// that [`pack_leaf_blocks`] packed) to name their first blocks, as `pack_leaf_blocks` did for the
/// 4-wide tree: a leaf's first triangle sits in lane 0 of its first block.
pub fn name_wide_leaf_blocks(wide_nodes: &mut [Bvh8Node], triangle_lanes: &[u32]) {
    for node in wide_nodes.iter_mut() {
        for word in node.slots.iter_mut().filter(|w| is_leaf_word(**w)) {
            *word = leaf_word_naming_blocks(*word, triangle_lanes);
        }
    }
}

/// The packed form of the leaf slot word `word` of a built tree (which names the leaf's first triangle):
/// the same count, from the leaf's first block. A leaf's first triangle sits in lane 0 of its first
/// block.
fn leaf_word_naming_blocks(word: u32, triangle_lanes: &[u32]) -> u32 {
    let (first_block, _) = block_and_lane(triangle_lanes[leaf_first(word) as usize]);
    leaf_slot(first_block, leaf_count(word))
}
