//! Small math helpers shared by all of core: float functions that work on both targets, orthonormal
//! frames and colour helpers.
pub mod color;
pub mod float;
pub mod frame;
pub mod lane_mask;
pub mod transcendental;

pub use frame::Frame;

use glam::Vec3;

/// `xyz` of a packed `[f32; 4]`.
#[inline]
#[must_use]
pub fn vec3_from(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// Packs a [`Vec3`] into `[f32; 4]` with `w`.
#[inline]
#[must_use]
pub fn pack_vec3(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}
