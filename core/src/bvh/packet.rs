//! Closest hits of a packet of up to eight coherent rays (a block's camera rays) over the CPU's 8-wide
//! tree, traversed once for all of them.
//!
//! The samples of one foveated block start at the camera's pinhole and pass within the block's
//! footprint (at most 4x4 pixels), so their rays cross nearly the same boxes. Traversed one by one, each
//! repeats the others' node tests. Traversed as a packet, a node is tested once for all of them by
//! interval arithmetic (Boulos, Wald et al. 2006; Wald, Boulos, Shirley 2007): with a shared origin and,
//! per axis, the smallest and largest of the rays' (rounded, [`SlabInverses`]) inverse directions, the
//! nearest entry and farthest exit over the packet are each a product at one end of that range, the
//! very float another ray's own slab test computes. So the packet enters every box that one of its
//! rays' own tests enters (and a few more), and each ray tests the leaves with its own watertight test
//! ([`test_leaf`], within its own closest hit): each finds the hit that
//! [`super::wide::closest_hit_wide`] finds for it, the same distance, and the same triangle unless two
//! triangles are hit at exactly that distance (an edge or vertex), where the packet's visiting order
//! may pick the other one.
//!
//! Rays that do not share their origin, or whose direction changes sign along an axis within the
//! packet, are traced one by one, and so are the rays of a scene without an 8-wide tree (over the
//! 4-wide one, [`closest_hit_with`]).
use ::wide::{f32x8, CmpLe};
use arrayvec::ArrayVec;

use super::query::closest_hit_with;
use super::traverse::{test_leaf, Hit, SlabInverses};
use super::wide::{Bvh8Node, Entry, Stack};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::Ray;
use crate::scene::{Features, SceneSource, SceneView, SLOT_LEAF};

/// Most rays in a packet.
pub const PACKET_SIZE: usize = 8;

/// The packet's part of the interval slab test: the shared origin and, per axis, the two extreme
/// inverse directions for entry and for exit distances.
struct PacketBox {
    origin: [f32x8; 3],
    /// `[axis][0 / 1]`: the smallest and largest of the rays' `inv_near` along the axis.
    inv_near: [[f32x8; 2]; 3],
    /// The same for `inv_far`.
    inv_far: [[f32x8; 2]; 3],
    /// Per axis, the bound row of the near planes (see [`Bvh8Node::bound_rows`]).
    near_row: [usize; 3],
}

impl PacketBox {
    /// The packet's box, or `None` if its rays do not share their origin or a direction sign.
    fn new(rays: &[Ray]) -> Option<Self> {
        let first = SlabInverses::new(&rays[0]);
        let o = rays[0].origin;
        let (mut near_lo, mut near_hi) = (first.inv_near, first.inv_near);
        let (mut far_lo, mut far_hi) = (first.inv_far, first.inv_far);
        for ray in &rays[1..] {
            let s = SlabInverses::new(ray);
            if ray.origin.to_array().map(f32::to_bits) != o.to_array().map(f32::to_bits)
                || s.negative != first.negative
            {
                return None;
            }
            near_lo = near_lo.min(s.inv_near);
            near_hi = near_hi.max(s.inv_near);
            far_lo = far_lo.min(s.inv_far);
            far_hi = far_hi.max(s.inv_far);
        }
        let splat = f32x8::splat;
        Some(Self {
            origin: [splat(o.x), splat(o.y), splat(o.z)],
            inv_near: [
                [splat(near_lo.x), splat(near_hi.x)],
                [splat(near_lo.y), splat(near_hi.y)],
                [splat(near_lo.z), splat(near_hi.z)],
            ],
            inv_far: [
                [splat(far_lo.x), splat(far_hi.x)],
                [splat(far_lo.y), splat(far_hi.y)],
                [splat(far_lo.z), splat(far_hi.z)],
            ],
            near_row: first.negative.map(usize::from),
        })
    }

    /// The nearest entry distance of any of the packet's rays into each of `node`'s boxes, and the
    /// mask of the boxes that one of them may enter within `[0, t_max]`.
    #[inline(always)]
    fn intersect(&self, node: &Bvh8Node, t_max: f32) -> ([f32; 8], u32) {
        let rows = node.bound_rows();
        let axis = |k: usize| -> (f32x8, f32x8) {
            let near = 2 * k + self.near_row[k];
            let far = 2 * k + 1 - self.near_row[k];
            let d_near = f32x8::new(rows[near]) - self.origin[k];
            let d_far = f32x8::new(rows[far]) - self.origin[k];
            let [n_lo, n_hi] = self.inv_near[k];
            let [f_lo, f_hi] = self.inv_far[k];
            (
                (d_near * n_lo).fast_min(d_near * n_hi),
                (d_far * f_lo).fast_max(d_far * f_hi),
            )
        };
        let (tn_x, tf_x) = axis(0);
        let (tn_y, tf_y) = axis(1);
        let (tn_z, tf_z) = axis(2);
        let near = tn_x.fast_max(tn_y).fast_max(tn_z.fast_max(f32x8::ZERO));
        let far = tf_x
            .fast_min(tf_y)
            .fast_min(tf_z.fast_min(f32x8::splat(t_max.min(f32::MAX))));
        (near.to_array(), near.cmp_le(far).move_mask() as u32)
    }
}

/// The closest hit in `(0, t_max)` of each of `rays` (at most [`PACKET_SIZE`]) over the scene's
/// 8-wide tree, written to `hits[i]` for `rays[i]`; see the module documentation for how it relates to
/// [`super::wide::closest_hit_wide`]; without an 8-wide tree, what [`closest_hit_with`] finds.
///
/// # Panics
/// If there are more than [`PACKET_SIZE`] rays or fewer hits than rays.
pub fn closest_hits_packet<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    rays: &[Ray],
    t_max: f32,
    hits: &mut [Hit],
) {
    assert!(rays.len() <= PACKET_SIZE && hits.len() >= rays.len());
    let count = rays.len();
    let packet = if count == 0 || scene.geometry.wide_nodes.is_empty() {
        None
    } else {
        PacketBox::new(rays)
    };
    let Some(packet) = packet else {
        for (ray, hit) in rays.iter().zip(hits.iter_mut()) {
            *hit = closest_hit_with(scene, source, ray, t_max);
        }
        return;
    };
    for hit in hits.iter_mut().take(count) {
        *hit = Hit::miss();
    }
    let nodes = scene.geometry.wide_nodes;
    let mut watertight: ArrayVec<WatertightRay, PACKET_SIZE> = ArrayVec::new();
    for ray in rays {
        watertight.push(WatertightRay::new(ray));
    }
    let mut closest = [t_max; PACKET_SIZE];
    // The farthest of the rays' closest hits: boxes beyond it hold nothing nearer for any of them.
    let mut farthest = t_max;
    let mut stack = Stack::new();
    let mut item = 0u32;
    loop {
        if item & SLOT_LEAF == 0 {
            let node = &nodes[item as usize];
            let (t, mut mask) = packet.intersect(node, farthest);
            if mask != 0 {
                // The hit children pushed and sorted farthest first; the nearest, on top, is next.
                let start = stack.len();
                while mask != 0 {
                    let c = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    stack.push(Entry::new(node.slots[c], t[c]));
                }
                stack.sort_from(start);
                item = stack.pop().unwrap_or(item);
                continue;
            }
        } else {
            for i in 0..count {
                test_leaf(
                    scene,
                    source,
                    &watertight[i],
                    item,
                    false,
                    &mut closest[i],
                    &mut hits[i],
                );
            }
            farthest = closest[..count].iter().copied().fold(0.0, f32::max);
        }
        // The next entry that may hold a hit nearer than one of the rays' closest.
        match stack.pop_nearer(farthest) {
            Some(next) => item = next,
            None => return,
        }
    }
}
