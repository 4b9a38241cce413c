//! The traversal queries the integrator asks, and which traversal answers them: in the ray-query
//! kernel module the driver's acceleration structures ([`super::hardware`]); on the CPU the 8-wide tree
//! where the scene has one ([`super::wide`]); else the 4-wide tree both backends share
//! ([`super::traverse`]). The choice is made at compile time (and, on the CPU, by whether the 8-wide
//! tree exists), so each backend's code holds one traversal.
use super::traverse::{traverse, Hit};
use crate::geometry::Ray;
use crate::scene::{Features, SceneSlices, SceneSource, SceneView};

/// The closest hit of `ray` with `0 < t < t_max` over the scene's BVH, skipping alpha cut-out holes;
/// [`Hit::miss`] if there is none or the scene has no nodes. On the CPU, the scene's 8-wide tree is
/// traversed where it has one ([`super::wide`]); in the ray-query kernel module, the driver's
/// acceleration structures (`super::hardware`).
#[must_use]
pub fn closest_hit<F: Features>(scene: &SceneView<F>, ray: &Ray, t_max: f32) -> Hit {
    closest_hit_with(scene, &SceneSlices, ray, t_max)
}

/// [`closest_hit`] reading the scene's arrays from `source`.
#[must_use]
pub fn closest_hit_with<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
) -> Hit {
    #[cfg(all(target_arch = "spirv", feature = "ray-query"))]
    return super::hardware::closest_hit(scene, source, ray, t_max);
    #[cfg(not(target_arch = "spirv"))]
    if !scene.geometry.wide_nodes.is_empty() {
        return super::wide::closest_hit_wide(scene, source, ray, t_max);
    }
    #[allow(unreachable_code)]
    traverse(scene, source, ray, t_max, false)
}

/// Whether anything (other than alpha cut-out holes) blocks the open segment `(0, t_max)` of `ray`; for
/// shadow rays. Stops at the first hit found.
#[must_use]
pub fn any_hit<F: Features>(scene: &SceneView<F>, ray: &Ray, t_max: f32) -> bool {
    any_hit_with(scene, &SceneSlices, ray, t_max)
}

/// [`any_hit`] reading the scene's arrays from `source`.
#[must_use]
pub fn any_hit_with<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    ray: &Ray,
    t_max: f32,
) -> bool {
    #[cfg(all(target_arch = "spirv", feature = "ray-query"))]
    return super::hardware::any_hit(scene, source, ray, t_max);
    #[cfg(not(target_arch = "spirv"))]
    if !scene.geometry.wide_nodes.is_empty() {
        return super::wide::any_hit_wide(scene, source, ray, t_max);
    }
    #[allow(unreachable_code)]
    traverse(scene, source, ray, t_max, true).is_hit()
}
