//! The CPU's 8-wide BVH ([`Bvh8Node`]) and its closest-hit and any-hit traversal.
//!
//! The GPU traverses the 4-wide tree ([`crate::scene::Bvh4Node`], [`super::traverse`]); the CPU host
//! traverses this one, which the builder (`fovea_scene::bvh`) collapses from the same binary tree: its
//! leaves are the 4-wide tree's leaves, so both name the same [`crate::scene::TriangleBlock`]s and
//! triangles, and a leaf is tested by the same code ([`super::traverse`]'s `test_leaf`). Each node
//! slab-tests its eight child boxes with one 8-lane SIMD test (AVX on x86-64; two SSE halves
//! elsewhere), with the same conservative, NaN-free arithmetic as the 4-wide test (Ize 2013; see
//! [`super::traverse`]), so a box is entered exactly when the 4-wide test enters it. A single-ray
//! traversal's steps are dependent loads, so halving the tree's depth halves its critical path
//! (Wald et al. 2008; Embree's BVH8, Wald et al. 2014).
//!
//! Hit children are visited near to far as in Embree: one hit child is entered without stack traffic,
//! two are ordered by one comparison, and three or more are pushed and sorted by an insertion sort,
//! farthest deepest. Any-hit queries push in slot order, unsorted.
//!
//! Only for targets other than SPIR-V: it uses the `wide` crate's `f32x8`, and the GPU has its own
//! layout.
use ::wide::{f32x8, CmpLe};
use arrayvec::ArrayVec;
use bytemuck::{Pod, Zeroable};

use super::traverse::{test_leaf, Hit, SlabInverses};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::Ray;
use crate::scene::{Features, SceneSource, SceneView, SLOT_EMPTY, SLOT_LEAF};

/// Children per [`Bvh8Node`].
pub const WIDE_ARITY: usize = 8;

/// Depth bound of the 8-wide tree: the builder's depth guard keeps it, like the 4-wide tree, at most
/// `(TRAVERSAL_STACK_SIZE - 4) / 3`.
pub const MAX_WIDE_DEPTH: usize = (super::TRAVERSAL_STACK_SIZE - 4) / 3;

/// Entries of the 8-wide traversal stack: a visit at depth `j` finds at most `7 j` entries below it
/// and writes at most eight above them.
pub const WIDE_STACK_SIZE: usize = 7 * MAX_WIDE_DEPTH + WIDE_ARITY;

/// A node of the CPU's 8-wide BVH (224 bytes, 32-byte aligned), node 0 the root. Boxes are stored
/// structure-of-arrays, one 8-lane vector per bound; `slots` are [`crate::scene::Bvh4Node`] slot words
/// (an interior node's index here, a leaf's blocks, or [`SLOT_EMPTY`] with an inverted box).
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Bvh8Node {
    pub min_x: [f32; 8],
    pub max_x: [f32; 8],
    pub min_y: [f32; 8],
    pub max_y: [f32; 8],
    pub min_z: [f32; 8],
    pub max_z: [f32; 8],
    pub slots: [u32; 8],
}

impl Bvh8Node {
    /// A node with eight empty slots.
    pub const EMPTY: Self = Self {
        min_x: [f32::MAX; 8],
        max_x: [-f32::MAX; 8],
        min_y: [f32::MAX; 8],
        max_y: [-f32::MAX; 8],
        min_z: [f32::MAX; 8],
        max_z: [-f32::MAX; 8],
        slots: [SLOT_EMPTY; 8],
    };

    crate::scene::layout::slot_box_methods!();
}

impl Default for Bvh8Node {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// The per-ray part of the 8-wide slab test (see [`SlabInverses`]).
struct RayBox8 {
    origin: [f32x8; 3],
    inv_near: [f32x8; 3],
    inv_far: [f32x8; 3],
    negative: [bool; 3],
}

impl RayBox8 {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let s = SlabInverses::new(ray);
        let o = ray.origin;
        Self {
            origin: [f32x8::splat(o.x), f32x8::splat(o.y), f32x8::splat(o.z)],
            inv_near: [
                f32x8::splat(s.inv_near.x),
                f32x8::splat(s.inv_near.y),
                f32x8::splat(s.inv_near.z),
            ],
            inv_far: [
                f32x8::splat(s.inv_far.x),
                f32x8::splat(s.inv_far.y),
                f32x8::splat(s.inv_far.z),
            ],
            negative: s.negative,
        }
    }

    /// The entry distances into `node`'s eight boxes within `[0, t_max]` and the mask of the boxes
    /// entered (bit `i` for slot `i`): the 4-wide test's arithmetic, eight lanes at a time.
    #[inline(always)]
    fn intersect(&self, node: &Bvh8Node, t_max: f32) -> ([f32; 8], u32) {
        let axis = |min: &[f32; 8], max: &[f32; 8], k: usize| -> (f32x8, f32x8) {
            let (near, far) = if self.negative[k] {
                (max, min)
            } else {
                (min, max)
            };
            (
                (f32x8::new(*near) - self.origin[k]) * self.inv_near[k],
                (f32x8::new(*far) - self.origin[k]) * self.inv_far[k],
            )
        };
        let (tn_x, tf_x) = axis(&node.min_x, &node.max_x, 0);
        let (tn_y, tf_y) = axis(&node.min_y, &node.max_y, 1);
        let (tn_z, tf_z) = axis(&node.min_z, &node.max_z, 2);
        let near = tn_x.fast_max(tn_y).fast_max(tn_z.fast_max(f32x8::ZERO));
        let far = tf_x
            .fast_min(tf_y)
            .fast_min(tf_z.fast_min(f32x8::splat(t_max.min(f32::MAX))));
        (near.to_array(), near.cmp_le(far).move_mask() as u32)
    }
}

/// The traversal stack: slot words with their entry distances. Entries are written as they are
/// pushed; the array is never zeroed as a whole.
struct Stack {
    entries: ArrayVec<(u32, f32), WIDE_STACK_SIZE>,
}

impl Stack {
    #[inline(always)]
    fn push(&mut self, item: u32, t: f32) {
        self.entries.push((item, t));
    }

    /// Sorts the entries from `start` up by decreasing distance, so the nearest is on top (an
    /// insertion sort: at most eight entries).
    #[inline(always)]
    fn sort_from(&mut self, start: usize) {
        let run = &mut self.entries[start..];
        for i in 1..run.len() {
            let entry = run[i];
            let mut j = i;
            while j > 0 && run[j - 1].1 < entry.1 {
                run[j] = run[j - 1];
                j -= 1;
            }
            run[j] = entry;
        }
    }

    /// Pops the next entry whose box may still hold a hit nearer than `closest`.
    #[inline(always)]
    fn pop_nearer(&mut self, closest: f32) -> Option<u32> {
        while let Some((item, t)) = self.entries.pop() {
            if t <= closest {
                return Some(item);
            }
        }
        None
    }
}

/// The shared loop of [`closest_hit_wide`] and [`any_hit_wide`].
#[inline(always)]
fn traverse_wide<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
    any: bool,
) -> Hit {
    let nodes = scene.wide_nodes;
    let mut best = Hit::miss();
    if nodes.is_empty() {
        return best;
    }
    let watertight = WatertightRay::new(ray);
    let ray_box = RayBox8::new(ray);
    let mut closest = t_max;
    let mut stack = Stack {
        entries: ArrayVec::new(),
    };
    let mut item = 0u32;
    loop {
        if item & SLOT_LEAF == 0 {
            let node = &nodes[item as usize];
            let (t, mut mask) = ray_box.intersect(node, closest);
            if mask != 0 {
                let first = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if mask == 0 {
                    item = node.slots[first];
                    continue;
                }
                let second = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let (a, b) = (
                    (node.slots[first], t[first]),
                    (node.slots[second], t[second]),
                );
                if mask == 0 {
                    // Two: continue with the nearer (the lower slot on a tie).
                    let (near, far) = if any || a.1 <= b.1 { (a, b) } else { (b, a) };
                    stack.push(far.0, far.1);
                    item = near.0;
                    continue;
                }
                let start = stack.entries.len();
                stack.push(a.0, a.1);
                stack.push(b.0, b.1);
                while mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push(node.slots[i], t[i]);
                }
                if !any {
                    stack.sort_from(start);
                }
                // The nearest, just pushed: nearer than `closest`.
                item = stack.entries.pop().map_or(item, |(next, _)| next);
                continue;
            }
        } else if test_leaf(
            scene,
            source,
            &watertight,
            item,
            any,
            &mut closest,
            &mut best,
        ) {
            return best;
        }
        match stack.pop_nearer(closest) {
            Some(next) => item = next,
            None => return best,
        }
    }
}

/// The closest hit of `ray` with `0 < t < t_max` over the scene's 8-wide tree
/// ([`SceneView::wide_nodes`]), skipping alpha cut-out holes: what the 4-wide traversal finds over the
/// tree it was collapsed from, up to which of two equally near triangles is reported. Misses
/// everything if the scene has no 8-wide tree.
#[must_use]
pub fn closest_hit_wide<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
) -> Hit {
    traverse_wide(scene, source, ray, t_max, false)
}

/// Whether anything (other than alpha cut-out holes) blocks the open segment `(0, t_max)` of `ray`,
/// over the scene's 8-wide tree.
#[must_use]
pub fn any_hit_wide<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
) -> bool {
    traverse_wide(scene, source, ray, t_max, true).is_hit()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Empty slots (inverted boxes) are never entered, whatever the ray, and no distance is NaN.
    #[test]
    fn empty_slots_are_never_entered() {
        let node = Bvh8Node::EMPTY;
        crate::test_support::for_each_slab_stress_ray(|ray| {
            let rb = RayBox8::new(&ray);
            for t_max in [f32::INFINITY, f32::MAX, 1.0, 0.0] {
                let (t, mask) = rb.intersect(&node, t_max);
                assert_eq!(mask, 0, "{ray:?} {t_max}");
                assert!(t.iter().all(|t| !t.is_nan()));
            }
        });
    }

    /// Each of the eight slots is tested on its own lane: a unit cube moved to `x = 2 i` in slot `i`
    /// is entered by a ray along `z` through its centre, and only by that ray, at the conservative
    /// entry distance.
    #[test]
    fn each_lane_tests_its_own_box() {
        let mut node = Bvh8Node::EMPTY;
        for i in 0..8 {
            let x = 2.0 * i as f32;
            node.set_slot_bounds(i, [x, 0.0, 0.0], [x + 1.0, 1.0, 1.0]);
        }
        for i in 0..8 {
            let origin = Vec3::new(2.0 * i as f32 + 0.5, 0.5, -2.0);
            let (t, mask) =
                RayBox8::new(&Ray::new(origin, Vec3::Z)).intersect(&node, f32::INFINITY);
            assert_eq!(mask, 1 << i);
            assert!(t[i] <= 2.0 && t[i] > 2.0 - 1e-5);
            let (_, mask) = RayBox8::new(&Ray::new(origin, Vec3::Z)).intersect(&node, 1.9);
            assert_eq!(mask, 0, "box beyond t_max");
            let (_, mask) =
                RayBox8::new(&Ray::new(origin, -Vec3::Z)).intersect(&node, f32::INFINITY);
            assert_eq!(mask, 0, "box behind the ray");
        }
    }

    /// The stack sorts a pushed run nearest on top and skips entries beyond the closest hit.
    #[test]
    fn stack_sorts_runs_and_skips_farther_entries() {
        let mut stack = Stack {
            entries: ArrayVec::new(),
        };
        stack.push(100, 0.5);
        let start = stack.entries.len();
        for (item, t) in [(1, 3.0), (2, 1.0), (3, 4.0), (4, 2.0)] {
            stack.push(item, t);
        }
        stack.sort_from(start);
        assert_eq!(stack.pop_nearer(f32::INFINITY), Some(2));
        assert_eq!(stack.pop_nearer(2.5), Some(4));
        // 1 (t = 3) and 3 (t = 4) lie beyond 2.5.
        assert_eq!(stack.pop_nearer(2.5), Some(100));
        assert_eq!(stack.pop_nearer(2.5), None);
    }
}
