//! Power estimates that set how often next-event estimation picks each light (host side builds the table
//! from these, so the same numbers hold on both backends).
use glam::Vec3;

use crate::math::color::luminance;
use crate::math::float::PI;

/// Emitted power of a Lambertian emitting triangle: `π · L · area` per emitting side.
#[inline]
#[must_use]
pub fn triangle_power(radiance: Vec3, area: f32, double_sided: bool) -> f32 {
    let sides = if double_sided { 2.0 } else { 1.0 };
    PI * luminance(radiance) * area * sides
}

/// Power of an isotropic point light of intensity `intensity`: `4π I`.
#[inline]
#[must_use]
pub fn point_power(intensity: Vec3) -> f32 {
    4.0 * PI * luminance(intensity)
}

/// Power of a spot light: `2π I (1 - (cos_inner + cos_outer) / 2)` (pbrt-v4 `SpotLight::Phi`).
#[inline]
#[must_use]
pub fn spot_power(intensity: Vec3, cos_inner: f32, cos_outer: f32) -> f32 {
    2.0 * PI * luminance(intensity) * (1.0 - 0.5 * (cos_inner + cos_outer))
}

/// Power a directional light of irradiance `e` delivers to a scene of bounding radius `scene_radius`.
#[inline]
#[must_use]
pub fn directional_power(irradiance: Vec3, scene_radius: f32) -> f32 {
    PI * scene_radius * scene_radius * luminance(irradiance)
}

/// Power an environment of mean radiance `mean_radiance` delivers to a scene of bounding radius
/// `scene_radius`: `4π · π r² · L` (pbrt-v4 `UniformInfiniteLight::Phi`).
#[inline]
#[must_use]
pub fn environment_power(mean_radiance: Vec3, scene_radius: f32) -> f32 {
    4.0 * PI * PI * scene_radius * scene_radius * luminance(mean_radiance)
}
