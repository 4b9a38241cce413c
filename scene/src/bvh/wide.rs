//! The CPU's 8-wide BVH ([`Bvh8Node`]), collapsed from the packed 4-wide tree.
//!
//! Each 8-wide node starts from the (up to four) children of a 4-wide node and greedily opens the
//! interior child of largest surface area, replacing it by its own children, while the result still
//! fits in eight slots (the collapse of Wald, Benthin, Boulos 2008 one level up; Embree builds its BVH8
//! the same way from a binary tree). Leaf slot words are copied unchanged, so both trees name the same
//! triangle blocks: the GPU traverses the 4-wide tree, the CPU this one, and a leaf is the same leaf in
//! both. Every 8-wide node consumes at least one 4-wide level, so the 8-wide tree is no deeper than
//! the 4-wide one (which `fovea_core::bvh::wide::WIDE_STACK_SIZE` relies on).
use fovea_core::bvh::wide::{Bvh8Node, WIDE_ARITY};
use fovea_core::scene::Bvh4Node;

/// One child of a node under construction: its box and its 4-wide slot word.
#[derive(Clone, Copy)]
struct Child {
    min: [f32; 3],
    max: [f32; 3],
    word: u32,
}

impl Child {
    fn is_interior(&self) -> bool {
        self.word & fovea_core::scene::SLOT_LEAF == 0
    }

    fn half_area(&self) -> f32 {
        let d = [
            (self.max[0] - self.min[0]).max(0.0),
            (self.max[1] - self.min[1]).max(0.0),
            (self.max[2] - self.min[2]).max(0.0),
        ];
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
}

/// The non-empty children of 4-wide node `index`, in slot order.
fn children_of(nodes: &[Bvh4Node], index: u32) -> Vec<Child> {
    let node = &nodes[index as usize];
    (0..4)
        .filter(|&slot| !node.is_empty_slot(slot))
        .map(|slot| {
            let (min, max) = node.slot_bounds(slot);
            Child {
                min,
                max,
                word: node.slot(slot),
            }
        })
        .collect()
}

/// Collapses the packed 4-wide tree `nodes` (root 0) into an 8-wide tree with the same leaves
/// (root 0); empty for an empty tree.
#[must_use]
pub fn collapse_to_wide(nodes: &[Bvh4Node]) -> Vec<Bvh8Node> {
    let mut wide = Vec::with_capacity(nodes.len() / 2 + 1);
    if nodes.is_empty() {
        return wide;
    }
    wide.push(Bvh8Node::EMPTY);
    // (8-wide node to fill, 4-wide node it starts from); explicit, as trees may be deep.
    let mut pending = vec![(0usize, 0u32)];
    while let Some((target, source)) = pending.pop() {
        let mut children = children_of(nodes, source);
        loop {
            // The interior child of largest area whose children still fit.
            let mut best: Option<(usize, f32, Vec<Child>)> = None;
            for (i, child) in children.iter().enumerate() {
                if !child.is_interior() {
                    continue;
                }
                let area = child.half_area();
                if best.as_ref().is_some_and(|(_, a, _)| *a >= area) {
                    continue;
                }
                let grandchildren = children_of(nodes, child.word);
                if children.len() - 1 + grandchildren.len() <= WIDE_ARITY {
                    best = Some((i, area, grandchildren));
                }
            }
            let Some((i, _, grandchildren)) = best else {
                break;
            };
            children.splice(i..=i, grandchildren);
        }
        let mut node = Bvh8Node::EMPTY;
        for (slot, child) in children.iter().enumerate() {
            node.set_slot_bounds(slot, child.min, child.max);
            node.slots[slot] = if child.is_interior() {
                let index = wide.len();
                wide.push(Bvh8Node::EMPTY);
                pending.push((index, child.word));
                index as u32
            } else {
                child.word
            };
        }
        wide[target] = node;
    }
    wide
}
