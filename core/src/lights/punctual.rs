//! KHR_lights_punctual point, spot and directional lights: delta lights that next-event estimation
//! samples deterministically and BSDF sampling never hits.
use glam::Vec3;

use crate::lights::sample::LightSample;
use crate::math::vec3_from;
use crate::scene::{Light, LIGHT_SPOT};

/// Spot cone attenuation as the KHR_lights_punctual spec recommends: a squared linear ramp between the
/// cosines of the outer and inner cone angles.
#[inline]
#[must_use]
pub fn spot_attenuation(cos_angle: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    let range = (cos_inner - cos_outer).max(1e-4);
    let t = ((cos_angle - cos_outer) / range).clamp(0.0, 1.0);
    t * t
}

/// Point or spot light seen from `p`: intensity / distance², times the spot cone attenuation.
#[must_use]
pub fn sample_point_or_spot(light: &Light, p: Vec3) -> LightSample {
    let position = vec3_from(light.position);
    let to_light = position - p;
    let dist2 = to_light.length_squared();
    if !(dist2 > 0.0) {
        return LightSample::none();
    }
    let direction = to_light / crate::math::float::sqrt(dist2);
    let mut radiance = vec3_from(light.intensity) / dist2;
    if light.kind == LIGHT_SPOT {
        let cos_angle = vec3_from(light.direction).dot(-direction);
        radiance *= spot_attenuation(cos_angle, light.position[3], light.intensity[3]);
    }
    LightSample {
        direction,
        target: position,
        is_infinite: false,
        radiance,
        pdf: 1.0,
        is_delta: true,
    }
}

/// Directional light: irradiance along `-direction`.
#[must_use]
pub fn sample_directional(light: &Light) -> LightSample {
    LightSample {
        direction: -vec3_from(light.direction),
        target: Vec3::ZERO,
        is_infinite: true,
        radiance: vec3_from(light.intensity),
        pdf: 1.0,
        is_delta: true,
    }
}
