//! The environment: light from infinitely far away, either a constant radiance or an equirectangular HDR
//! map importance-sampled by its luminance × sin θ (pbrt-v4 §12.5).
//!
//! Map convention: `+y` is up; texel row `v = θ / π` (θ from `+y`), column `u = (φ + π) / 2π` with
//! `φ = atan2(z, x)`; row 0 is the top of the image.
use glam::{Vec2, Vec3};

use super::{LightSample, INFINITE_DISTANCE};
use crate::math::float::{atan2, cos, safe_sqrt, sin, INV_2PI, INV_PI, PI};
use crate::math::vec3_from;
use crate::sampling::distribution::{pdf_2d, sample_2d};
use crate::sampling::warp::{square_to_uniform_sphere, UNIFORM_SPHERE_PDF};
use crate::scene::{SceneView, ENVIRONMENT_CONSTANT, ENVIRONMENT_MAP};

/// Map coordinates in [0, 1)² of unit direction `d`.
#[inline]
#[must_use]
pub fn direction_to_uv(d: Vec3) -> Vec2 {
    let u = (atan2(d.z, d.x) + PI) * INV_2PI;
    // atan2 rather than acos: acos(y) loses precision near the poles, where sin θ (the Jacobian) is small.
    let v = atan2(safe_sqrt(d.x * d.x + d.z * d.z), d.y) * INV_PI;
    Vec2::new(u.clamp(0.0, 0.999_999_9), v.clamp(0.0, 0.999_999_9))
}

/// Unit direction of map coordinates `uv` (inverse of [`direction_to_uv`]).
#[inline]
#[must_use]
pub fn uv_to_direction(uv: Vec2) -> Vec3 {
    let phi = uv.x * 2.0 * PI - PI;
    let theta = uv.y * PI;
    let s = sin(theta);
    Vec3::new(s * cos(phi), cos(theta), s * sin(phi))
}

/// Radiance arriving from direction `d` (unit, pointing away from the scene).
#[must_use]
pub fn radiance(scene: &SceneView, d: Vec3) -> Vec3 {
    let g = &scene.globals;
    let scale = vec3_from(g.environment_radiance);
    if g.environment_kind == ENVIRONMENT_CONSTANT {
        scale
    } else if g.environment_kind == ENVIRONMENT_MAP {
        let uv = direction_to_uv(d);
        let x = ((uv.x * g.environment_width as f32) as u32).min(g.environment_width - 1);
        let y = ((uv.y * g.environment_height as f32) as u32).min(g.environment_height - 1);
        let texel = scene.environment_texels[(y * g.environment_width + x) as usize];
        scale * Vec3::new(texel[0], texel[1], texel[2])
    } else {
        Vec3::ZERO
    }
}

/// Solid-angle density of [`sample`] for direction `d`, without the light-selection probability.
#[must_use]
pub fn pdf(scene: &SceneView, d: Vec3) -> f32 {
    let g = &scene.globals;
    if g.environment_kind == ENVIRONMENT_CONSTANT {
        UNIFORM_SPHERE_PDF
    } else if g.environment_kind == ENVIRONMENT_MAP {
        let uv = direction_to_uv(d);
        let sin_theta = sin(uv.y * PI);
        if !(sin_theta > 0.0) {
            return 0.0;
        }
        let p = pdf_2d(
            scene.environment_marginal_cdf,
            scene.environment_conditional_cdf,
            g.environment_width,
            g.environment_height,
            uv,
        );
        p / (2.0 * PI * PI * sin_theta)
    } else {
        0.0
    }
}

/// Samples a direction towards the environment (pdf without the light-selection probability).
#[must_use]
pub fn sample(scene: &SceneView, u: Vec2) -> LightSample {
    let g = &scene.globals;
    let (direction, pdf) = if g.environment_kind == ENVIRONMENT_CONSTANT {
        (square_to_uniform_sphere(u), UNIFORM_SPHERE_PDF)
    } else if g.environment_kind == ENVIRONMENT_MAP {
        let s = sample_2d(
            scene.environment_marginal_cdf,
            scene.environment_conditional_cdf,
            g.environment_width,
            g.environment_height,
            u,
        );
        let sin_theta = sin(s.uv.y * PI);
        if !(sin_theta > 0.0) || !(s.pdf > 0.0) {
            return LightSample::none();
        }
        (uv_to_direction(s.uv), s.pdf / (2.0 * PI * PI * sin_theta))
    } else {
        return LightSample::none();
    };
    LightSample {
        direction,
        target: direction * INFINITE_DISTANCE,
        is_infinite: true,
        radiance: radiance(scene, direction),
        pdf,
        is_delta: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_mapping_round_trips() {
        for &(u, v) in &[(0.1f32, 0.2f32), (0.5, 0.5), (0.9, 0.95), (0.25, 0.01)] {
            let uv = direction_to_uv(uv_to_direction(Vec2::new(u, v)));
            assert!((uv - Vec2::new(u, v)).length() < 1e-4, "{uv:?} vs {u} {v}");
        }
        assert!(direction_to_uv(Vec3::Y).y < 1e-6, "up is the top row");
    }
}
