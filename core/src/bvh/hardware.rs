//! Hardware traversal: the closest-hit and any-hit questions of [`super::traverse`] answered by the
//! driver's acceleration structures through `VK_KHR_ray_query`, in the kernel module built with the
//! `RayQueryKHR` capability and this crate's `ray-query` feature (the host picks that module for
//! `--traversal hardware`). A thin adapter:
//! the acceleration structure finds candidate triangles; which triangle a candidate is, whether an
//! alpha cut-out lets the ray through ([`is_cut_out`], the software traversal's own test) and what a
//! hit reports ([`Hit`]) stay core's.
//!
//! The bottom-level structure holds the scene's triangles in two geometries, the opaque ones first
//! (flagged opaque, so the hardware commits them without asking) and the ones whose material has a cut-out
//! second (not opaque, so each candidate comes back to [`closest_hit`] and [`any_hit`] for the alpha
//! test). The binding [`crate::kernel_abi::BINDING_HARDWARE_TRAVERSAL`] holds the words of
//! [`HardwareHeader`] followed by, for each triangle of the structure in its order, the index of the
//! scene triangle (BVH leaf order) it is. Vertices are stored in the triangle's own order (`v0, v1, v2`),
//! so the barycentrics the hardware reports are those of `v1` and `v2`, as [`Hit`]'s are.
use spirv_std::glam::UVec2;
use spirv_std::ray_tracing::{
    AccelerationStructure, CandidateIntersection, CommittedIntersection, RayFlags, RayQuery,
};

use super::traverse::Hit;
use crate::geometry::Ray;
use crate::material::alpha::is_cut_out;
use crate::scene::features::FEATURE_ALPHA_CUTOUT;
use crate::scene::{Features, SceneSource, SceneView};

/// Words before the triangle map in the hardware-traversal binding: the top-level structure's device
/// address (low, high), the number of opaque triangles, and one unused word.
pub const HARDWARE_HEADER_WORDS: usize = 4;

/// The scene triangle of primitive `primitive` of geometry `geometry` (0 opaque, 1 cut-out).
#[inline]
fn scene_triangle(map: &[u32], geometry: u32, primitive: u32) -> u32 {
    let offset = if geometry == 0 { 0 } else { map[2] };
    map[HARDWARE_HEADER_WORDS + (offset + primitive) as usize]
}

/// The nearest hit (or, with `any`, the first one found) of `ray` in `(0, t_max)`, cut-out holes
/// skipped.
#[inline]
fn query<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
    any: bool,
) -> Hit {
    let map = scene.geometry.hardware;
    let flags = if any {
        RayFlags::TERMINATE_ON_FIRST_HIT
    } else {
        RayFlags::NONE
    };
    // SAFETY: the acceleration structure's address comes from the host, which built it for this scene
    // and keeps it alive while the kernel runs; the candidate getters are called only while `proceed`
    // reports a candidate, the committed ones only after a committed triangle.
    unsafe {
        let accel = AccelerationStructure::from_vec(UVec2::new(map[0], map[1]));
        spirv_std::ray_query!(let mut rq);
        rq.initialize(&accel, flags, 0xFF, ray.origin, 0.0, ray.direction, t_max);
        while rq.proceed() {
            // Only the cut-out geometry's triangles come back here.
            if rq.get_candidate_intersection_type() == CandidateIntersection::Triangle {
                let triangle = scene_triangle(
                    map,
                    rq.get_candidate_intersection_geometry_index(),
                    rq.get_candidate_intersection_primitive_index(),
                );
                let b = rq.get_candidate_intersection_barycentrics();
                if !(scene.features.has(FEATURE_ALPHA_CUTOUT)
                    && is_cut_out(scene, source, triangle, b.x, b.y))
                {
                    rq.confirm_intersection();
                }
            }
        }
        if rq.get_committed_intersection_type() == CommittedIntersection::Triangle {
            let b = rq.get_committed_intersection_barycentrics();
            Hit {
                t: rq.get_committed_intersection_t(),
                triangle: scene_triangle(
                    map,
                    rq.get_committed_intersection_geometry_index(),
                    rq.get_committed_intersection_primitive_index(),
                ),
                b1: b.x,
                b2: b.y,
            }
        } else {
            Hit::miss()
        }
    }
}

/// [`super::closest_hit_with`] on the hardware.
#[inline]
#[must_use]
pub fn closest_hit<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
) -> Hit {
    query(scene, source, ray, t_max, false)
}

/// [`super::any_hit_with`] on the hardware.
#[inline]
#[must_use]
pub fn any_hit<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
) -> bool {
    query(scene, source, ray, t_max, true).is_hit()
}
