//! Leaf blocks: every leaf's triangles four at a time, in the structure-of-arrays layout traversal tests
//! them in ([`TriangleBlock`]).
use fovea_core::scene::{
    leaf_count, leaf_first, leaf_slot, Bvh4Node, TriangleBlock, TrianglePositions,
    BLOCK_LANE_CUTOUT,
};

/// Triangles per block.
pub const BLOCK_LANES: usize = 4;

/// Blocks a leaf of `triangles` triangles takes.
#[inline]
#[must_use]
pub fn blocks_for(triangles: usize) -> usize {
    triangles.div_ceil(BLOCK_LANES)
}

/// Rewrites every leaf slot of `nodes` (a built BVH, whose leaves name triangles of the leaf-ordered
/// `triangles`) to name the first of the blocks that hold its triangles (the count stays the triangle
/// count), and returns those blocks, in leaf order.
/// `cut_out(i)` says whether triangle `i`'s material has an alpha cut-out ([`BLOCK_LANE_CUTOUT`]).
pub fn pack_leaf_blocks(
    nodes: &mut [Bvh4Node],
    triangles: &[TrianglePositions],
    cut_out: impl Fn(usize) -> bool,
) -> Vec<TriangleBlock> {
    // Leaves are contiguous, disjoint ranges covering the triangles: mark each leaf's length at its
    // first triangle, then number the blocks in one pass in leaf order.
    let mut leaf_length = vec![0u8; triangles.len()];
    for node in nodes.iter() {
        for slot in 0..4 {
            if node.is_leaf_slot(slot) {
                let word = node.slot(slot);
                leaf_length[leaf_first(word) as usize] = leaf_count(word) as u8;
            }
        }
    }
    let mut first_block = vec![0u32; triangles.len()];
    let mut blocks = Vec::new();
    let mut i = 0;
    while i < triangles.len() {
        let count = usize::from(leaf_length[i]).max(1);
        first_block[i] = blocks.len() as u32;
        for (k, t) in triangles[i..i + count].iter().enumerate() {
            if k % BLOCK_LANES == 0 {
                blocks.push(TriangleBlock::EMPTY);
            }
            let index = (i + k) as u32 | if cut_out(i + k) { BLOCK_LANE_CUTOUT } else { 0 };
            let block = blocks.last_mut().expect("a block was just pushed");
            block.set_lane(k % BLOCK_LANES, t, index);
        }
        i += count;
    }
    for node in nodes.iter_mut() {
        for slot in 0..4 {
            if node.is_leaf_slot(slot) {
                let word = node.slot(slot);
                let first = first_block[leaf_first(word) as usize];
                node.slots[slot] = leaf_slot(first, leaf_count(word));
            }
        }
    }
    blocks
}
