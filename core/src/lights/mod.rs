//! Light sources and next-event estimation: picking a light in proportion to its power, sampling a point
//! or direction on it, and the densities multiple importance sampling needs when a BSDF-sampled ray finds an
//! emitter by itself.
//!
//! Kinds: emissive triangles ([`triangle`]), the environment, constant or an HDR map ([`environment`]), and
//! KHR_lights_punctual point, spot and directional lights ([`punctual`]). [`power`] holds the power estimates
//! the host uses to build the selection table.
pub mod environment;
pub mod power;
pub mod punctual;
pub mod sample;
pub mod triangle;

pub use sample::{LightSample, INFINITE_DISTANCE};

use glam::{Vec2, Vec3};

use crate::sampling::distribution::sample_cdf;
use crate::scene::features::{
    FEATURE_EMISSIVE_TRIANGLES, FEATURE_ENVIRONMENT_CONSTANT, FEATURE_ENVIRONMENT_MAP,
    FEATURE_PUNCTUAL_LIGHTS,
};
use crate::scene::{
    Features, SceneSource, SceneView, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_POINT,
    LIGHT_SPOT, LIGHT_TRIANGLE,
};

/// Picks a light with probability proportional to its power (`u_select`) and samples it from the shading
/// point `p` (`u`).
#[must_use]
pub fn sample_light<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    p: Vec3,
    u_select: f32,
    u: Vec2,
) -> LightSample {
    let count = scene.globals.light_count;
    if count == 0 {
        return LightSample::none();
    }
    let choice = sample_cdf(scene.lights.cdf, 0, count, u_select);
    let light = scene.lights.list[choice.index as usize];
    // Light kinds the scene lacks (by its feature set) are never tested for.
    let features = scene.features;
    let mut sample = if features.has(FEATURE_EMISSIVE_TRIANGLES) && light.kind == LIGHT_TRIANGLE {
        triangle::sample(scene, source, light.index, p, u)
    } else if features.has(FEATURE_ENVIRONMENT_CONSTANT | FEATURE_ENVIRONMENT_MAP)
        && light.kind == LIGHT_ENVIRONMENT
    {
        environment::sample(scene, u)
    } else if features.has(FEATURE_PUNCTUAL_LIGHTS)
        && (light.kind == LIGHT_POINT || light.kind == LIGHT_SPOT)
    {
        punctual::sample_point_or_spot(&light, p)
    } else if features.has(FEATURE_PUNCTUAL_LIGHTS) && light.kind == LIGHT_DIRECTIONAL {
        punctual::sample_directional(&light)
    } else {
        LightSample::none()
    };
    sample.pdf *= choice.pmf;
    sample
}

/// Power heuristic with β = 2 (Veach 1997, eq. 9.13) for a sample drawn from the strategy with density
/// `pdf_a`, combined with one sample of a strategy with density `pdf_b`.
#[inline]
#[must_use]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let a = pdf_a * pdf_a;
    let b = pdf_b * pdf_b;
    if a + b > 0.0 && crate::math::float::is_finite(a + b) {
        a / (a + b)
    } else if crate::math::float::is_finite(a) {
        // b overflowed (a near-delta strategy on the other side) or both are zero.
        if b > 0.0 {
            0.0
        } else {
            1.0
        }
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for &(a, b) in &[(1.0f32, 1.0f32), (0.3, 7.0), (1e-20, 3.0), (5.0, 0.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(1e30, 1e-30), 1.0);
    }
}
