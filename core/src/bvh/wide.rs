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
//! two to four are ordered by a branch-free sorting network on stack entries that compare as integers
//! (distance, then slot word), five or more are pushed and sorted by an insertion sort, farthest
//! deepest. Any-hit queries push in slot order, unsorted. Of equally near boxes the one with the higher
//! slot word is visited first.
//!
//! Only for targets other than SPIR-V: it uses the `wide` crate's `f32x8`, and the GPU has its own
//! layout.
use ::wide::{f32x8, i32x8, CmpLe};
use arrayvec::ArrayVec;

use super::traverse::{test_leaf, Hit, SlabInverses};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::Ray;
use crate::scene::{Features, SceneSource, SceneView, SLOT_LEAF};

/// Children per [`Bvh8Node`].
pub const WIDE_ARITY: usize = 8;

/// Depth bound of the 8-wide tree: the builder's depth guard keeps it, like the 4-wide tree, at most
/// `(TRAVERSAL_STACK_SIZE - 4) / 3`.
pub const MAX_WIDE_DEPTH: usize = (super::TRAVERSAL_STACK_SIZE - 4) / 3;

/// Entries of the 8-wide traversal stack: a visit at depth `j` finds at most `7 j` entries below it
/// and writes at most eight above them.
pub const WIDE_STACK_SIZE: usize = 7 * MAX_WIDE_DEPTH + WIDE_ARITY;

/// The 8-wide node lives with the scene's other layouts.
pub use crate::scene::layout::Bvh8Node;

/// The per-ray part of the 8-wide slab test (see [`SlabInverses`]).
struct RayBox8 {
    origin: [f32x8; 3],
    inv_near: [f32x8; 3],
    inv_far: [f32x8; 3],
    /// Per axis, which bound array of a node is the near plane: 1 (`max`) where the ray runs
    /// towards `-axis`, else 0 (`min`); see [`Bvh8Node::bound_rows`].
    near_row: [usize; 3],
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
            near_row: s.negative.map(usize::from),
        }
    }

    /// The entry distances into `node`'s eight boxes within `[0, t_max]` and the mask of the boxes
    /// entered (bit `i` for slot `i`): the 4-wide test's arithmetic, eight lanes at a time.
    ///
    /// Two details keep the per-node dependency chain short (as in Embree's BVH8 traversal): each
    /// axis's near and far bounds are loaded by a per-ray row index instead of picked by a branch,
    /// and the entry distance is the integer maximum of the float bits, which equals the float
    /// maximum once it includes 0 (non-negative floats order as their bits do; a negative one, as a
    /// negative integer, loses to 0).
    #[inline(always)]
    fn intersect(&self, node: &Bvh8Node, t_max: f32) -> ([f32; 8], u32) {
        let rows = node.bound_rows();
        let axis = |k: usize| -> (f32x8, f32x8) {
            let near = 2 * k + (self.near_row[k] & 1);
            let far = 2 * k + 1 - (self.near_row[k] & 1);
            (
                (f32x8::new(rows[near]) - self.origin[k]) * self.inv_near[k],
                (f32x8::new(rows[far]) - self.origin[k]) * self.inv_far[k],
            )
        };
        let (tn_x, tf_x) = axis(0);
        let (tn_y, tf_y) = axis(1);
        let (tn_z, tf_z) = axis(2);
        let bits = |v: f32x8| -> i32x8 { bytemuck::cast(v) };
        let near: f32x8 =
            bytemuck::cast(bits(tn_x).max(bits(tn_y)).max(bits(tn_z).max(i32x8::ZERO)));
        let far = tf_x
            .fast_min(tf_y)
            .fast_min(tf_z.fast_min(f32x8::splat(t_max.min(f32::MAX))));
        (near.to_array(), near.cmp_le(far).move_mask() as u32)
    }
}

/// A traversal stack entry: the complement of a slot word below its entry distance's bits, so that
/// entries compare as integers by distance (entry distances are never negative, and non-negative floats
/// order as their bits), and of equally near entries the one with the higher slot word is the nearer.
/// That tie order is the 4-wide traversal's (the higher slot first), and it matters for rays through
/// shared edges and vertices, which hit two triangles at the same distance: with it the CPU and GPU
/// report different triangles for 21 of the 8,192 probe rays of `tests/cross_backend_probe.rs`, with the
/// opposite order for 42.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Entry(u64);

impl Entry {
    #[inline(always)]
    pub(super) fn new(item: u32, t: f32) -> Self {
        Self(u64::from(t.to_bits()) << 32 | u64::from(!item))
    }

    #[inline(always)]
    pub(super) fn item(self) -> u32 {
        !(self.0 as u32)
    }

    /// Whether the entry's box may still hold a hit nearer than `closest` (`closest >= 0`).
    #[inline(always)]
    pub(super) fn nearer_than(self, closest: f32) -> bool {
        (self.0 >> 32) as u32 <= closest.to_bits()
    }
}

/// A compare-exchange of a sorting network: the farther entry into `a`, the nearer into `b`, without
/// a branch (which child is nearer is what a branch predictor cannot know).
#[inline(always)]
fn order(a: &mut Entry, b: &mut Entry) {
    let (x, y) = (*a, *b);
    *a = x.max(y);
    *b = x.min(y);
}

/// Sorts three entries farthest first (a sorting network of three compare-exchanges).
#[inline(always)]
fn order3(a: &mut Entry, b: &mut Entry, c: &mut Entry) {
    order(a, b);
    order(b, c);
    order(a, b);
}

/// Sorts four entries farthest first (a sorting network of five compare-exchanges).
#[inline(always)]
fn order4(a: &mut Entry, b: &mut Entry, c: &mut Entry, d: &mut Entry) {
    order(a, b);
    order(c, d);
    order(a, c);
    order(b, d);
    order(b, c);
}

/// The traversal stack (also the camera-ray packets', [`super::packet`]). Entries are written as they
/// are pushed; the array is never zeroed as a whole.
pub(super) struct Stack {
    entries: ArrayVec<Entry, WIDE_STACK_SIZE>,
}

impl Stack {
    /// An empty stack.
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            entries: ArrayVec::new(),
        }
    }

    #[inline(always)]
    pub(super) fn push(&mut self, entry: Entry) {
        self.entries.push(entry);
    }

    /// Pushes `sorted` (farthest first) but its last entry, the nearest, whose slot word it returns.
    #[inline(always)]
    fn push_all_but_nearest<const N: usize>(&mut self, sorted: [Entry; N]) -> u32 {
        for &entry in &sorted[..N - 1] {
            self.push(entry);
        }
        sorted[N - 1].item()
    }

    /// The number of entries.
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        self.entries.len()
    }

    /// Pops the top entry's slot word (the one just pushed).
    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<u32> {
        self.entries.pop().map(Entry::item)
    }

    /// Sorts the entries from `start` up by decreasing distance, so the nearest is on top (an
    /// insertion sort: at most eight entries).
    #[inline(always)]
    pub(super) fn sort_from(&mut self, start: usize) {
        let run = &mut self.entries[start..];
        for i in 1..run.len() {
            let entry = run[i];
            let mut j = i;
            while j > 0 && run[j - 1] < entry {
                run[j] = run[j - 1];
                j -= 1;
            }
            run[j] = entry;
        }
    }

    /// Pops the next entry whose box may still hold a hit nearer than `closest`.
    #[inline(always)]
    pub(super) fn pop_nearer(&mut self, closest: f32) -> Option<u32> {
        while let Some(entry) = self.entries.pop() {
            if entry.nearer_than(closest) {
                return Some(entry.item());
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
    let nodes = scene.geometry.wide_nodes;
    let mut best = Hit::miss();
    if nodes.is_empty() {
        return best;
    }
    let watertight = WatertightRay::new(ray);
    let ray_box = RayBox8::new(ray);
    let mut closest = t_max;
    let mut stack = Stack::new();
    let mut item = 0u32;
    loop {
        if item & SLOT_LEAF == 0 {
            let node = &nodes[item as usize];
            let (t, mut mask) = ray_box.intersect(node, closest);
            if mask != 0 {
                // The entry of the lowest hit child left in `mask`, which it clears.
                let take = |mask: &mut u32| -> Entry {
                    let i = mask.trailing_zeros() as usize;
                    *mask &= *mask - 1;
                    Entry::new(node.slots[i], t[i])
                };
                let mut a = take(&mut mask);
                if mask == 0 {
                    item = a.item();
                    continue;
                }
                // Two to four hit children: ordered by a sorting network (unless `any`), the
                // nearest entered, the others pushed farthest first.
                let mut b = take(&mut mask);
                if mask == 0 {
                    if !any {
                        order(&mut a, &mut b);
                    }
                    item = stack.push_all_but_nearest([a, b]);
                    continue;
                }
                let mut c = take(&mut mask);
                if mask == 0 {
                    if !any {
                        order3(&mut a, &mut b, &mut c);
                    }
                    item = stack.push_all_but_nearest([a, b, c]);
                    continue;
                }
                let mut d = take(&mut mask);
                if mask == 0 {
                    if !any {
                        order4(&mut a, &mut b, &mut c, &mut d);
                    }
                    item = stack.push_all_but_nearest([a, b, c, d]);
                    continue;
                }
                // Five or more: pushed, then sorted in place.
                let start = stack.len();
                for entry in [a, b, c, d] {
                    stack.push(entry);
                }
                while mask != 0 {
                    stack.push(take(&mut mask));
                }
                if !any {
                    stack.sort_from(start);
                }
                // The nearest, just pushed: nearer than `closest`.
                item = stack.pop().unwrap_or(item);
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
/// ([`GeometryArrays::wide_nodes`](crate::scene::GeometryArrays::wide_nodes)), skipping alpha cut-out holes: what the 4-wide traversal finds over the
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

    /// The vector test (integer maximum, row-indexed bounds) decides exactly as the scalar slab test
    /// with float minima and maxima does, with the same entry distances, for boxes that touch or
    /// contain the origin (bounds at the origin's coordinates give zero distances of both signs).
    #[test]
    fn matches_the_scalar_slab_test() {
        let mut rng = crate::test_support::SplitMix64(3);
        let mut nodes = [Bvh8Node::EMPTY; 24];
        for (n, node) in nodes.iter_mut().enumerate() {
            for i in 0..8 {
                let a = rng.in_cube(2.0);
                let b = rng.in_cube(2.0);
                let (mut lo, mut hi) = (a.min(b), a.max(b));
                // Some bounds exactly at the origins used below (0 and the random ones are near 0).
                if (n + i) % 3 == 0 {
                    lo.x = 0.0;
                }
                if (n + i) % 4 == 0 {
                    hi.y = 0.0;
                    lo.y = lo.y.min(0.0);
                }
                node.set_slot_bounds(i, lo.to_array(), hi.to_array());
            }
        }
        let check = |ray: Ray| {
            let s = SlabInverses::new(&ray);
            let rb = RayBox8::new(&ray);
            let (o, dims) = (ray.origin.to_array(), [0usize, 1, 2]);
            let inv_near = s.inv_near.to_array();
            let inv_far = s.inv_far.to_array();
            for node in &nodes {
                for t_max in [f32::INFINITY, 1.0, 0.0] {
                    let (t, mask) = rb.intersect(node, t_max);
                    for (i, &entry) in t.iter().enumerate() {
                        let (lo, hi) = node.slot_bounds(i);
                        let (mut near, mut far) = (0.0f32, t_max.min(f32::MAX));
                        for k in dims {
                            let (n, f) = if s.negative[k] {
                                (hi[k], lo[k])
                            } else {
                                (lo[k], hi[k])
                            };
                            near = near.max((n - o[k]) * inv_near[k]);
                            far = far.min((f - o[k]) * inv_far[k]);
                        }
                        let hit = near <= far;
                        assert_eq!(mask & (1 << i) != 0, hit, "{ray:?} slot {i} t_max {t_max}");
                        if hit {
                            assert_eq!(entry, near, "{ray:?} slot {i}");
                        }
                    }
                }
            }
        };
        crate::test_support::for_each_slab_stress_ray(&check);
        for _ in 0..2000 {
            let origin = if rng.uniform() < 0.3 {
                Vec3::ZERO
            } else {
                rng.in_cube(2.5)
            };
            check(Ray::new(origin, rng.in_cube(1.0)));
        }
    }

    /// Entries order by distance, then by slot word, higher first (leaf words, with their high bit,
    /// before nodes); the sorting networks sort every arrangement of four entries, ties included,
    /// farthest first.
    #[test]
    fn entries_order_by_distance_and_networks_sort() {
        assert!(Entry::new(7, 1.0) < Entry::new(3, 2.0));
        assert!(Entry::new(7, 0.0) < Entry::new(3, 0.0));
        assert!(Entry::new(SLOT_LEAF | 1, 1.0) < Entry::new(5, 1.0));
        assert_eq!(Entry::new(SLOT_LEAF | 1, 1.0).item(), SLOT_LEAF | 1);
        assert!(Entry::new(9, 1e-40) > Entry::new(9, 0.0));
        assert!(Entry::new(1, 2.0).nearer_than(2.0) && !Entry::new(1, 2.0).nearer_than(1.5));
        assert!(Entry::new(1, 3.0e38).nearer_than(f32::INFINITY));
        let values = [
            Entry::new(1, 0.5),
            Entry::new(2, 0.5),
            Entry::new(SLOT_LEAF | 3, 2.0),
            Entry::new(4, 0.0),
        ];
        for p in 0..256usize {
            let pick = |k: usize| values[(p >> (2 * k)) & 3];
            let [mut a, mut b, mut c, mut d] = [pick(0), pick(1), pick(2), pick(3)];
            let mut expected = [a, b, c, d];
            expected.sort_unstable_by(|x, y| y.cmp(x));
            order4(&mut a, &mut b, &mut c, &mut d);
            assert_eq!([a, b, c, d], expected);
            let [mut a, mut b, mut c] = [pick(0), pick(1), pick(2)];
            let mut expected = [a, b, c];
            expected.sort_unstable_by(|x, y| y.cmp(x));
            order3(&mut a, &mut b, &mut c);
            assert_eq!([a, b, c], expected);
        }
    }

    /// The stack sorts a pushed run nearest on top and skips entries beyond the closest hit.
    #[test]
    fn stack_sorts_runs_and_skips_farther_entries() {
        let mut stack = Stack::new();
        stack.push(Entry::new(100, 0.5));
        let start = stack.entries.len();
        for (item, t) in [(1, 3.0), (2, 1.0), (3, 4.0), (4, 2.0)] {
            stack.push(Entry::new(item, t));
        }
        stack.sort_from(start);
        assert_eq!(stack.pop_nearer(f32::INFINITY), Some(2));
        assert_eq!(stack.pop_nearer(2.5), Some(4));
        // 1 (t = 3) and 3 (t = 4) lie beyond 2.5.
        assert_eq!(stack.pop_nearer(2.5), Some(100));
        assert_eq!(stack.pop_nearer(2.5), None);
    }
}
