//! Emissive triangles: uniform area sampling converted to solid angle, and the emitted radiance seen along
//! a ray.
use glam::{Vec2, Vec3};

use super::LightSample;
use crate::geometry::offset::offset_ray_origin;
use crate::material::alpha::interpolate_uv;
use crate::material::texture::sample_texture;
use crate::math::vec3_from;
use crate::sampling::warp::square_to_uniform_triangle;
use crate::scene::{SceneView, INVALID_INDEX, MATERIAL_DOUBLE_SIDED_EMISSION};

/// Vertex positions of `triangle`.
#[inline]
#[must_use]
pub fn triangle_vertices(scene: &SceneView, triangle: u32) -> [Vec3; 3] {
    let t = scene.triangles[triangle as usize];
    [vec3_from(t.v0), vec3_from(t.v1), vec3_from(t.v2)]
}

/// The unnormalised geometric normal `(v1 - v0) × (v2 - v0)` (its length is twice the area); the front
/// face is the side it points to (counter-clockwise winding).
#[inline]
#[must_use]
pub fn scaled_geometric_normal(v: &[Vec3; 3]) -> Vec3 {
    (v[1] - v[0]).cross(v[2] - v[0])
}

/// Radiance emitted by `triangle` at barycentrics (`b1`, `b2`) towards direction `w` (unit, pointing away
/// from the surface). Zero on the back face of one-sided emitters.
#[must_use]
pub fn emitted_radiance(
    scene: &SceneView,
    triangle: u32,
    b1: f32,
    b2: f32,
    w: Vec3,
    ng: Vec3,
) -> Vec3 {
    let material = &scene.materials[scene.triangle_info[triangle as usize].material as usize];
    if !material.is_emissive() {
        return Vec3::ZERO;
    }
    if material.flags & MATERIAL_DOUBLE_SIDED_EMISSION == 0 && ng.dot(w) <= 0.0 {
        return Vec3::ZERO;
    }
    let mut radiance = vec3_from(material.emission);
    if material.emission_texture != INVALID_INDEX {
        let uv = interpolate_uv(scene, triangle, b1, b2);
        radiance *= sample_texture(scene, material.emission_texture, uv).truncate();
    }
    radiance
}

/// Solid-angle density, without the light-selection probability, of sampling point `q` on `triangle`
/// from `p` by uniform area sampling: `|p - q|² / (|cos θ_q| · area)`.
#[inline]
#[must_use]
pub fn solid_angle_pdf(scene: &SceneView, triangle: u32, p: Vec3, q: Vec3) -> f32 {
    let v = triangle_vertices(scene, triangle);
    let n2 = scaled_geometric_normal(&v);
    let double_area = n2.length();
    let to_p = p - q;
    let dist2 = to_p.length_squared();
    // |cos θ_q| · area = |n2 · to_p| / (2 |to_p|).
    let cos_area = n2.dot(to_p).abs() * 0.5 / crate::math::float::sqrt(dist2);
    if !(double_area > 0.0) || !(cos_area > 0.0) {
        return 0.0;
    }
    dist2 / cos_area
}

/// Samples a point on `triangle` uniformly by area, as seen from `p`.
#[must_use]
pub fn sample(scene: &SceneView, triangle: u32, p: Vec3, u: Vec2) -> LightSample {
    let v = triangle_vertices(scene, triangle);
    let n2 = scaled_geometric_normal(&v);
    let b = square_to_uniform_triangle(u);
    let q = v[0] * (1.0 - b.x - b.y) + v[1] * b.x + v[2] * b.y;
    let to_p = p - q;
    let dist2 = to_p.length_squared();
    let double_area = n2.length();
    if !(dist2 > 0.0) || !(double_area > 0.0) {
        return LightSample::none();
    }
    let dist = crate::math::float::sqrt(dist2);
    let w = to_p / dist;
    let ng = n2 / double_area;
    let cos_q = ng.dot(w);
    let radiance = emitted_radiance(scene, triangle, b.x, b.y, w, ng);
    let cos_area = cos_q.abs() * 0.5 * double_area;
    if !(cos_area > 0.0) || radiance == Vec3::ZERO {
        return LightSample::none();
    }
    // Leave the light's surface on the side of p so the shadow ray can end exactly there.
    let side = if cos_q >= 0.0 { ng } else { -ng };
    LightSample {
        direction: -w,
        target: offset_ray_origin(q, side),
        is_infinite: false,
        radiance,
        pdf: dist2 / cos_area,
        is_delta: false,
    }
}
