//! Closest-hit and any-hit traversal of the 4-wide BVH ([`Bvh4Node`]) with a fixed-size stack.
//!
//! Each visited node slab-tests its four child boxes at once: the node stores its boxes
//! structure-of-arrays, so every bound is one `Vec4` (SSE on the CPU, a plain `vec4` in SPIR-V) and the
//! test is a dozen vector operations (Wald, Benthin, Boulos 2008, "Getting rid of packets"). The hit
//! children are then visited near to far: all but the nearest are pushed with their entry distances, the
//! farthest deepest, and a popped entry is skipped if a closer hit was found meanwhile. Leaves are stack
//! entries like nodes, so they are tested in the same near-to-far order; an entry is the child's slot
//! word ([`Bvh4Node::slots`]: a node index, or a leaf's first triangle and count), one `u32` plus its
//! distance.
//!
//! The near and far planes of each axis are picked by the sign of the ray's (clamped) inverse direction,
//! not by a per-box min/max of the two slab distances; an inverted box (the builder's empty slots) thus
//! always gives `near > far` and is never entered.
//!
//! The slab test is made conservative so that it never culls a hit the watertight triangle test
//! ([`WatertightRay`]) reports (Woop et al. 2013, Sec. 4, "conservative traversal"): the entry and exit
//! distances are widened by `1 ± 2γ₃` (Ize 2013, "Robust BVH Ray Traversal"), and the boxes written by the
//! builder are themselves a few ulps larger than their triangles. Zero direction components are handled
//! without infinities or NaNs: their inverse is clamped to `±f32::MAX`, so `(bound - origin) * inv` is a
//! huge (or infinite) finite-signed number, and never `0 * ∞`.
use glam::{UVec4, Vec3, Vec4};

use crate::geometry::triangle::{BlockTest, WatertightRay};
use crate::geometry::Ray;
use crate::material::alpha::is_cut_out;
use crate::math::lane_mask::{eq_mask, gt_mask, lane_u32, le_mask};
use crate::scene::features::FEATURE_ALPHA_CUTOUT;
use crate::scene::{
    leaf_count, leaf_first, Bvh4Node, Features, SceneSource, SceneView, TriangleBlock,
    BLOCK_LANE_CUTOUT, SLOT_LEAF,
};

/// Entries of the traversal stack. A node visit pushes its (up to four) hit children and pops the nearest,
/// so while a node of depth `j` (root = 0) is visited the stack holds at most `3 j` entries, and at most
/// `3 D + 4` are ever written (a visit writes all four children above the top) for trees whose deepest
/// node has depth `D`. `fovea_scene::bvh::build_bvh` keeps
/// `D <= (TRAVERSAL_STACK_SIZE - 4) / 3 = 20`.
pub const TRAVERSAL_STACK_SIZE: usize = 64;

/// Trees must have fewer nodes than this: an interior slot word holds the node's index below
/// [`SLOT_LEAF`].
pub const MAX_NODE_COUNT: usize = SLOT_LEAF as usize;

/// γ₃ = 3u / (1 - 3u) with the unit roundoff u = 2⁻²⁴ (pbrt-v3 Sec. 3.9.1).
const GAMMA3: f32 = 3.0 * (f32::EPSILON * 0.5) / (1.0 - 3.0 * (f32::EPSILON * 0.5));
/// Scales the exit distance of a slab test up to cover its rounding errors (Ize 2013).
const ROUND_UP: f32 = 1.0 + 2.0 * GAMMA3;
/// Scales the (non-negative) entry distance of a slab test down.
const ROUND_DOWN: f32 = 1.0 - 2.0 * GAMMA3;

/// A ray's hit on a triangle (a geometry concept, used by shading and the G-buffer too).
pub use crate::geometry::hit::Hit;

/// `1 / d`, clamped to `±f32::MAX` for zero and tiny `d` (whose true inverse overflows).
#[inline]
#[must_use]
fn safe_inverse(d: f32) -> f32 {
    if d.abs() >= f32::MIN_POSITIVE {
        1.0 / d
    } else if d < 0.0 {
        -f32::MAX
    } else {
        f32::MAX
    }
}

/// The per-ray inverses of the slab test, with the rounding-error widening of Ize (2013) folded in
/// (see [`RayBox4`]); shared by the 4-wide test and the CPU's 8-wide one ([`super::wide`]).
#[derive(Clone, Copy)]
pub(crate) struct SlabInverses {
    /// `1 / d` scaled by `1 - 2γ₃`, for entry distances.
    pub inv_near: Vec3,
    /// `1 / d` scaled by `1 + 2γ₃` and clamped to finite values, for exit distances.
    pub inv_far: Vec3,
    /// Whether the inverse direction is negative along x, y, z (the near plane is then `max`).
    pub negative: [bool; 3],
}

impl SlabInverses {
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let inv = Vec3::new(
            safe_inverse(ray.direction.x),
            safe_inverse(ray.direction.y),
            safe_inverse(ray.direction.z),
        );
        // Clamped so that an inverse of ±f32::MAX stays finite (and never turns `0 * ∞` into NaN).
        let inv_far = (inv * ROUND_UP).clamp(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
        let inv_near = inv * ROUND_DOWN;
        Self {
            inv_near,
            inv_far,
            negative: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
        }
    }
}

/// The per-ray part of the 4-wide slab test: origin and inverse direction splatted per axis, and which
/// bound of each axis is the near plane.
///
/// The rounding-error widening of Ize (2013) is folded into the inverse: entry distances use
/// `inv * (1 - 2γ₃)` and exit distances `inv * (1 + 2γ₃)`. The computed `(b - o) * inv'` then carries
/// at most four roundings (subtraction, division, scaling, product), so its relative error is
/// within `(1 ± u)⁴`, which the `∓6u` scale more than covers: entries only shrink and exits only
/// grow. (Signs are exact: a rounded difference or product has the sign of the exact one.)
#[derive(Clone, Copy)]
struct RayBox4 {
    origin_x: Vec4,
    origin_y: Vec4,
    origin_z: Vec4,
    inv_near_x: Vec4,
    inv_near_y: Vec4,
    inv_near_z: Vec4,
    inv_far_x: Vec4,
    inv_far_y: Vec4,
    inv_far_z: Vec4,
    /// Whether the inverse direction is negative along x, y, z (the near plane is then `max`).
    negative: [bool; 3],
}

impl RayBox4 {
    #[inline]
    fn new(ray: &Ray) -> Self {
        let SlabInverses {
            inv_near,
            inv_far,
            negative,
        } = SlabInverses::new(ray);
        Self {
            origin_x: Vec4::splat(ray.origin.x),
            origin_y: Vec4::splat(ray.origin.y),
            origin_z: Vec4::splat(ray.origin.z),
            inv_near_x: Vec4::splat(inv_near.x),
            inv_near_y: Vec4::splat(inv_near.y),
            inv_near_z: Vec4::splat(inv_near.z),
            inv_far_x: Vec4::splat(inv_far.x),
            inv_far_y: Vec4::splat(inv_far.y),
            inv_far_z: Vec4::splat(inv_far.z),
            negative,
        }
    }

    /// The (conservative) entry distances of the ray into `node`'s four child boxes within
    /// `[0, t_max]`, and a bit mask of the boxes it enters (bit `i` for slot `i`); distances of
    /// missed boxes are meaningless.
    #[inline(always)]
    fn intersect(&self, node: &Bvh4Node, t_max: f32) -> (Vec4, u32) {
        // Load the bounds as vectors first, then pick near and far planes per axis: the choice is
        // per ray, so the branches are perfectly predicted (and the SPIR-V is plain selects).
        let (near_x, far_x) = near_far(node.min_x, node.max_x, self.negative[0]);
        let (near_y, far_y) = near_far(node.min_y, node.max_y, self.negative[1]);
        let (near_z, far_z) = near_far(node.min_z, node.max_z, self.negative[2]);
        // No NaN can arise: bounds are finite and the inverses are finite and non-zero.
        let tn_x = (near_x - self.origin_x) * self.inv_near_x;
        let tn_y = (near_y - self.origin_y) * self.inv_near_y;
        let tn_z = (near_z - self.origin_z) * self.inv_near_z;
        let tf_x = (far_x - self.origin_x) * self.inv_far_x;
        let tf_y = (far_y - self.origin_y) * self.inv_far_y;
        let tf_z = (far_z - self.origin_z) * self.inv_far_z;
        let near = tn_x.max(tn_y).max(tn_z.max(Vec4::ZERO));
        // `t_max` is clamped to a finite value so that an infinite entry distance (a ray parallel to
        // and outside a slab) is always a miss.
        let far = tf_x
            .min(tf_y)
            .min(tf_z)
            .min(Vec4::splat(t_max.min(f32::MAX)));
        (near, le_mask(near, far))
    }
}

/// The near and far planes of one axis for four boxes: `(min, max)`, swapped when the ray runs towards
/// `-axis`.
#[inline(always)]
fn near_far(min: Vec4, max: Vec4, negative: bool) -> (Vec4, Vec4) {
    if negative {
        (max, min)
    } else {
        (min, max)
    }
}

/// Candidate lane `k` of a leaf block (`lane` its [`TriangleBlock::index`] word): if it is hit in
/// `(0, closest)` outside any cut-out hole, records the hit in `best` and `closest` and returns `true`.
/// Triangles of opaque materials skip the cut-out test with one bit test ([`BLOCK_LANE_CUTOUT`]);
/// scenes without cut-outs (by their feature set) with none.
#[inline(always)]
fn test_block_lane<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    watertight: &WatertightRay,
    block: &TriangleBlock,
    test: &BlockTest,
    k: usize,
    lane: u32,
    closest: &mut f32,
    best: &mut Hit,
) -> bool {
    let h = watertight.block_lane_hit(block, test, k, *closest);
    if !h.hit {
        return false;
    }
    let triangle = lane & !BLOCK_LANE_CUTOUT;
    if scene.features.has(FEATURE_ALPHA_CUTOUT)
        && lane & BLOCK_LANE_CUTOUT != 0
        && is_cut_out(scene, source, triangle, h.b1, h.b2)
    {
        return false;
    }
    *closest = h.t;
    *best = Hit {
        t: h.t,
        triangle,
        b1: h.b1,
        b2: h.b2,
    };
    true
}

/// Where each of a node's four children goes when its hit children are pushed: child `i`'s rank is
/// the number of hit children to be visited after it, so the one visited next (the nearest) has rank
/// `hits - 1` and the farthest rank 0, the bottom of the pushed run. Ties go to the higher slot first.
/// Any-hit queries visit in slot order, highest slot first (order does not matter to them, and not
/// sorting is cheaper). Missed children get rank 3, which only ever lands at or above the new top.
///
/// Branch-free (compares and bit counts, no loops): the stack is written at computed positions
/// instead of shifting entries as an insertion sort does, which matters on SIMD-per-lane GPUs
/// (lavapipe), where every dynamically indexed stack access is a loop over the lanes.
#[inline(always)]
#[must_use]
fn child_ranks(entry: Vec4, mask: u32, any: bool) -> UVec4 {
    // `farther(i)`: the hit children visited after child `i`.
    let farther = |t_i: f32, below_i: u32| -> u32 {
        let (greater, equal) = if any {
            (0, 0xF)
        } else {
            let t = Vec4::splat(t_i);
            (gt_mask(entry, t), eq_mask(entry, t))
        };
        (greater | (equal & below_i)) & mask
    };
    let rank = |i: u32, t_i: f32| -> u32 {
        if mask & (1 << i) != 0 {
            farther(t_i, (1 << i) - 1).count_ones()
        } else {
            3
        }
    };
    UVec4::new(
        rank(0, entry.x),
        rank(1, entry.y),
        rank(2, entry.z),
        rank(3, entry.w),
    )
}

/// The slot of the lowest set bit of a non-zero 4-bit mask (no intrinsics, for the GPU's sake).
#[inline]
#[must_use]
fn lowest_slot(mask: u32) -> usize {
    if mask & 1 != 0 {
        0
    } else if mask & 2 != 0 {
        1
    } else if mask & 4 != 0 {
        2
    } else {
        3
    }
}

/// Pushes one child of a visited node (see [`child_ranks`]): if it was `hit`, the child of rank
/// `hits - 1` becomes the next `item`, and any other goes to `stack_len + rank`; `top` is
/// `(stack_len, hits)`.
#[inline(always)]
fn push_child(
    stack_item: &mut [u32; TRAVERSAL_STACK_SIZE],
    stack_t: &mut [f32; TRAVERSAL_STACK_SIZE],
    item: &mut u32,
    top: (usize, u32),
    hit: bool,
    rank: u32,
    t: f32,
    slot: u32,
) {
    let (stack_len, hits) = top;
    if hit {
        if rank + 1 == hits {
            *item = slot;
        } else {
            stack_item[stack_len + rank as usize] = slot;
            stack_t[stack_len + rank as usize] = t;
        }
    }
}

/// Tests the triangles of the leaf whose slot word is `item` ([`leaf_first`], [`leaf_count`]) for hits
/// in `(0, closest)`, updating `closest` and `best`; returns `true` if `any` is set and a hit was
/// found (the query is then answered). Shared by the 4-wide traversal and the CPU's 8-wide one
/// ([`super::wide`]).
///
/// The leaf's blocks are tested four triangles per SIMD test; the lanes of a block are then finished
/// in order, so the first of equally near hits wins, as one by one.
#[inline(always)]
pub(crate) fn test_leaf<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    watertight: &WatertightRay,
    item: u32,
    any: bool,
    closest: &mut f32,
    best: &mut Hit,
) -> bool {
    let mut b = leaf_first(item);
    // Triangles not yet tested; a block's lanes beyond them are unused.
    let mut left = leaf_count(item);
    while left > 0 {
        let block = source.block(scene, b);
        let mut test = watertight.test_block(&block, *closest);
        if left < 4 {
            test.candidates &= (1 << left) - 1;
        }
        if test.candidates != 0 {
            let lanes = source.block_lanes(scene, b);
            // One lane at a time, lowest first. A loop rather than four unrolled calls: a GPU
            // that runs both sides of every branch (lavapipe before Mesa 24.3) then runs the
            // lane's finishing code and cut-out test once per candidate, not four times.
            let mut pending = test.candidates;
            while pending != 0 {
                let k = lowest_slot(pending);
                pending &= pending - 1;
                let word = lane_u32(lanes, k);
                if test_block_lane(
                    scene, source, watertight, &block, &test, k, word, closest, best,
                ) && any
                {
                    return true;
                }
            }
        }
        b += 1;
        left -= left.min(4);
    }
    false
}

/// Shared traversal loop (inlined into both callers, so each gets a copy specialised for `any`): the
/// closest hit in `(0, t_max)`, or (with `any`) the first one found.
///
/// The current item is a node index or a leaf slot word ([`SLOT_LEAF`] set); stack entries are items
/// with their entry distances. A visited node writes all four children at their ranks above the stack
/// top ([`child_ranks`]), keeps the hit ones below the nearest and continues with the nearest.
// Index loops over local arrays: rust-gpu does not compile iterators over them.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(crate) fn traverse<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
    any: bool,
) -> Hit {
    let mut best = Hit::miss();
    if scene.geometry.nodes.is_empty() {
        return best;
    }
    let watertight = WatertightRay::new(ray);
    let ray_box = RayBox4::new(ray);
    let mut closest = t_max;

    let mut stack_item = [0u32; TRAVERSAL_STACK_SIZE];
    let mut stack_t = [0.0f32; TRAVERSAL_STACK_SIZE];
    let mut stack_len = 0usize;
    let mut item = 0u32;
    loop {
        let mut next = false;
        if item & SLOT_LEAF == 0 {
            let node = source.node(scene, item);
            let (entry, mask) = ray_box.intersect(&node, closest);
            if mask != 0 {
                next = true;
                if mask & (mask - 1) == 0 {
                    // One child hit: continue with it, no stack traffic.
                    item = node.slot(lowest_slot(mask));
                } else {
                    // Push the hit children below the nearest, farthest deepest, and continue with
                    // the nearest.
                    let hits = mask.count_ones();
                    let rank = child_ranks(entry, mask, any);
                    // Unrolled by hand: the GPU compilers keep a loop over the four slots as a loop,
                    // which then indexes the ranks and distances dynamically.
                    let (items, ts) = (&mut stack_item, &mut stack_t);
                    let top = (stack_len, hits);
                    let s = node.slots;
                    push_child(
                        items,
                        ts,
                        &mut item,
                        top,
                        mask & 1 != 0,
                        rank.x,
                        entry.x,
                        s.x,
                    );
                    push_child(
                        items,
                        ts,
                        &mut item,
                        top,
                        mask & 2 != 0,
                        rank.y,
                        entry.y,
                        s.y,
                    );
                    push_child(
                        items,
                        ts,
                        &mut item,
                        top,
                        mask & 4 != 0,
                        rank.z,
                        entry.z,
                        s.z,
                    );
                    push_child(
                        items,
                        ts,
                        &mut item,
                        top,
                        mask & 8 != 0,
                        rank.w,
                        entry.w,
                        s.w,
                    );
                    stack_len += hits as usize - 1;
                }
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
        if !next {
            // Pop the next item that may still hold a closer hit.
            let mut found = false;
            while stack_len > 0 && !found {
                stack_len -= 1;
                if stack_t[stack_len] <= closest {
                    item = stack_item[stack_len];
                    found = true;
                }
            }
            if !found {
                return best;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::bvh::query::{any_hit, closest_hit};
    use crate::scene::INVALID_INDEX;
    use crate::scene::{
        leaf_slot, GeometryArrays, Material, MaterialArrays, TriangleBlock, TriangleInfo,
        TrianglePositions, MATERIAL_ALPHA_CUTOUT,
    };
    use crate::test_support::one_triangle_per_block;
    use glam::Vec3;

    fn tri(a: Vec3, b: Vec3, c: Vec3) -> TrianglePositions {
        TrianglePositions {
            v0: a.extend(0.0),
            v1: b.extend(0.0),
            v2: c.extend(0.0),
        }
    }

    /// Traversal reads nodes, blocks and (for cut-outs) triangle info and materials, never
    /// `triangle_lanes`.
    fn view<'a>(
        nodes: &'a [Bvh4Node],
        blocks: &'a [TriangleBlock],
        info: &'a [TriangleInfo],
        materials: &'a [Material],
    ) -> SceneView<'a> {
        SceneView {
            geometry: GeometryArrays {
                nodes,
                blocks,
                triangle_info: info,
                ..GeometryArrays::default()
            },
            materials: MaterialArrays {
                list: materials,
                ..MaterialArrays::default()
            },
            ..SceneView::empty()
        }
    }

    /// Slot `slot` of `node` becomes a box around z-layer `z` (as the builder writes it, slightly larger
    /// than its triangle) with slot word `word`.
    fn set_layer(node: &mut Bvh4Node, slot: usize, z: f32, word: u32) {
        node.set_slot_bounds(slot, [-1.001, -1.001, z - 0.001], [3.001, 3.001, z + 0.001]);
        node.slots[slot] = word;
    }

    /// Two big triangles at z = 1 (material 1) and z = 2 (material 0). The root holds the far triangle as
    /// a leaf in slot 3 and, in slot 1, an interior node whose slot 2 is the near triangle's leaf; the other
    /// slots are empty. Near-first ordering must not depend on slot order.
    fn two_layers() -> ([Bvh4Node; 2], [TrianglePositions; 2], [TriangleInfo; 2]) {
        let near = tri(
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(3.0, -1.0, 1.0),
            Vec3::new(-1.0, 3.0, 1.0),
        );
        let far = tri(
            Vec3::new(-1.0, -1.0, 2.0),
            Vec3::new(-1.0, 3.0, 2.0),
            Vec3::new(3.0, -1.0, 2.0),
        );
        let mut root = Bvh4Node::EMPTY;
        set_layer(&mut root, 3, 2.0, leaf_slot(0, 1));
        set_layer(&mut root, 1, 1.0, 1);
        let mut inner = Bvh4Node::EMPTY;
        set_layer(&mut inner, 2, 1.0, leaf_slot(1, 1));
        let info = [
            TriangleInfo {
                vertices: [0, 1, 2],
                material: 0,
            },
            TriangleInfo {
                vertices: [3, 4, 5],
                material: 1,
            },
        ];
        ([root, inner], [far, near], info)
    }

    #[test]
    fn empty_scene_has_no_hits() {
        let materials = [Material::default()];
        let scene = view(&[], &[], &[], &materials);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(!closest_hit(&scene, &ray, f32::INFINITY).is_hit());
        assert!(!any_hit(&scene, &ray, f32::INFINITY));
        assert_eq!(Hit::miss().triangle, INVALID_INDEX);
    }

    #[test]
    fn closest_and_any_hit_on_two_layers() {
        let (nodes, triangles, info) = two_layers();
        let materials = [Material::default(), Material::default()];
        let blocks = one_triangle_per_block(&triangles, &[]).0;
        let scene = view(&nodes, &blocks, &info, &materials);
        // Axis-aligned rays (two zero direction components) through the interior, an edge and a vertex.
        for origin in [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(-1.0, 0.5, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(-1.0, 3.0, 0.0),
        ] {
            let ray = Ray::new(origin, Vec3::Z);
            let h = closest_hit(&scene, &ray, f32::INFINITY);
            assert!(h.is_hit());
            assert_eq!(h.triangle, 1);
            assert!((h.t - 1.0).abs() < 1e-6);
        }
        let ray = Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z);
        let h = closest_hit(&scene, &ray, f32::INFINITY);
        assert!((h.b1 - 0.3125).abs() < 1e-6 && (h.b2 - 0.375).abs() < 1e-6);
        assert!(any_hit(&scene, &ray, 1.5));
        assert!(!any_hit(&scene, &ray, 1.0));
        assert!(!closest_hit(&scene, &ray, 0.5).is_hit());
        // From between the layers, looking either way.
        let up = Ray::new(Vec3::new(0.0, 0.0, 1.5), Vec3::Z);
        assert_eq!(closest_hit(&scene, &up, f32::INFINITY).triangle, 0);
        let down = Ray::new(Vec3::new(0.0, 0.0, 1.5), -Vec3::Z);
        assert_eq!(closest_hit(&scene, &down, f32::INFINITY).triangle, 1);
        // From beyond both layers, looking back: the far layer is now the nearer one.
        let back = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        let h = closest_hit(&scene, &back, f32::INFINITY);
        assert_eq!(h.triangle, 0);
        assert!((h.t - 3.0).abs() < 1e-6);
        // Missing everything.
        let away = Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::Z);
        assert!(!closest_hit(&scene, &away, f32::INFINITY).is_hit());
        assert!(!any_hit(&scene, &away, f32::INFINITY));
    }

    #[test]
    fn alpha_cut_out_triangles_are_skipped() {
        let (nodes, triangles, info) = two_layers();
        // Triangle 1 (the near layer) has material 1, which the packer marks in its block lane.
        let blocks = one_triangle_per_block(&triangles, &[1]).0;
        let hole = Material {
            flags: MATERIAL_ALPHA_CUTOUT,
            base_color: [0.8, 0.8, 0.8, 0.0],
            ..Material::default()
        };
        let materials = [Material::default(), hole];
        let scene = view(&nodes, &blocks, &info, &materials);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::Z);
        let h = closest_hit(&scene, &ray, f32::INFINITY);
        assert_eq!(h.triangle, 0);
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!(!any_hit(&scene, &ray, 1.5));
        assert!(any_hit(&scene, &ray, 2.5));

        // Opaque enough: alpha above the cutoff blocks again.
        let solid = Material {
            base_color: [0.8, 0.8, 0.8, 0.9],
            ..hole
        };
        let materials = [Material::default(), solid];
        let scene = view(&nodes, &blocks, &info, &materials);
        assert_eq!(closest_hit(&scene, &ray, f32::INFINITY).triangle, 1);
    }

    /// A node whose slot 1 is the unit cube and whose other slots are empty.
    fn unit_cube_node() -> Bvh4Node {
        let mut node = Bvh4Node::EMPTY;
        node.set_slot_bounds(1, [0.0; 3], [1.0; 3]);
        node.slots[1] = leaf_slot(0, 1);
        node
    }

    #[test]
    fn slab_test_has_no_nan_for_zero_directions() {
        let node = unit_cube_node();
        let cases = [
            (Vec3::new(0.0, 0.5, 0.5), Vec3::X, true),
            (Vec3::new(-1.0, 0.0, 0.0), Vec3::X, true),
            // (A ray exactly in a box's max plane and parallel to it may miss the box; no triangle can be
            // hit there because built boxes strictly contain their triangles.)
            (Vec3::new(-1.0, 0.999, 0.999), Vec3::X, true),
            (Vec3::new(-1.0, 1.5, 0.5), Vec3::X, false),
            (Vec3::new(0.5, 0.5, 0.5), Vec3::ZERO, true),
            (Vec3::new(2.0, 0.5, 0.5), Vec3::ZERO, false),
            (Vec3::new(2.0, 0.5, 0.5), Vec3::new(-0.0, 0.0, -1.0), false),
            (Vec3::new(0.5, 0.5, 2.0), Vec3::new(-0.0, 0.0, -1.0), true),
            (Vec3::new(0.5, 2.0, 0.5), Vec3::new(0.0, -1.0, 0.0), true),
            (Vec3::new(0.5, 2.0, 0.5), Vec3::new(0.0, 1.0, 0.0), false),
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE, true),
            (Vec3::new(2.0, 2.0, 2.0), -Vec3::ONE, true),
            (Vec3::new(2.0, 2.0, 2.0), Vec3::ONE, false),
        ];
        for (origin, dir, expect) in cases {
            let rb = RayBox4::new(&Ray::new(origin, dir));
            assert!(
                rb.inv_near_x.is_finite() && rb.inv_near_y.is_finite() && rb.inv_near_z.is_finite()
            );
            assert!(
                rb.inv_far_x.is_finite() && rb.inv_far_y.is_finite() && rb.inv_far_z.is_finite()
            );
            for t_max in [f32::INFINITY, 100.0] {
                let (t, mask) = rb.intersect(&node, t_max);
                assert!(!t.is_nan_mask().any());
                assert_eq!(mask, if expect { 2 } else { 0 }, "{origin:?} {dir:?}");
            }
        }
        // Entry distances are conservative (slightly below the true ones) and zero from inside.
        let rb = RayBox4::new(&Ray::new(Vec3::new(0.5, 0.5, -2.0), Vec3::Z));
        let (t, mask) = rb.intersect(&node, f32::INFINITY);
        assert_eq!(mask, 2);
        assert!(t.y <= 2.0 && t.y > 2.0 - 1e-5);
        let (_, mask) = rb.intersect(&node, 1.9);
        assert_eq!(mask, 0, "box beyond t_max");
        let rb = RayBox4::new(&Ray::new(Vec3::splat(0.5), Vec3::Y));
        assert_eq!(rb.intersect(&node, f32::INFINITY).0.y, 0.0);
    }

    /// Empty slots (inverted boxes) are missed by every ray, including rays with zero, negative-zero and
    /// huge or tiny direction components and rays starting at extreme coordinates.
    #[test]
    fn empty_slots_are_never_entered() {
        let node = Bvh4Node::EMPTY;
        crate::test_support::for_each_slab_stress_ray(|ray| {
            let rb = RayBox4::new(&ray);
            for t_max in [f32::INFINITY, f32::MAX, 1.0, 0.0] {
                let (_, mask) = rb.intersect(&node, t_max);
                assert_eq!(mask, 0, "{ray:?} {t_max}");
            }
        });
    }

    /// A deep chain of nodes, each with four hit children (three leaves pushed per level), exercises the
    /// stack at its documented bound: depth `(TRAVERSAL_STACK_SIZE - 4) / 3`.
    #[test]
    fn stack_bound_holds_for_the_deepest_allowed_tree() {
        let depth = (TRAVERSAL_STACK_SIZE - 4) / 3;
        // Leaves with a triangle behind the ray's origin, so every box is entered but nothing is hit
        // until the last level's far triangle.
        let behind = tri(
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(3.0, -1.0, -1.0),
            Vec3::new(-1.0, 3.0, -1.0),
        );
        let target = tri(
            Vec3::new(-1.0, -1.0, 5.0),
            Vec3::new(3.0, -1.0, 5.0),
            Vec3::new(-1.0, 3.0, 5.0),
        );
        let triangles = [behind, target];
        let info = [TriangleInfo::default(); 2];
        let materials = [Material::default()];
        let big = ([-2.0, -2.0, -2.0], [4.0, 4.0, 6.0]);
        let mut nodes = std::vec::Vec::new();
        for level in 0..=depth {
            let mut node = Bvh4Node::EMPTY;
            for slot in 0..4 {
                node.set_slot_bounds(slot, big.0, big.1);
                node.slots[slot] = leaf_slot(0, 1);
            }
            if level < depth {
                // All four boxes tie; the highest slot is visited first, so the three leaves of every
                // level stay on the stack until the chain's end.
                node.slots[3] = level as u32 + 1;
            } else {
                node.slots[0] = leaf_slot(1, 1);
            }
            nodes.push(node);
        }
        let blocks = one_triangle_per_block(&triangles, &[]).0;
        let scene = view(&nodes, &blocks, &info, &materials);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::Z);
        let h = closest_hit(&scene, &ray, f32::INFINITY);
        assert_eq!(h.triangle, 1);
        assert!((h.t - 5.0).abs() < 1e-6);
        assert!(any_hit(&scene, &ray, f32::INFINITY));
    }
}
