//! Alpha cut-outs: whether a hit point on a cut-out material is a hole that rays pass through.
use glam::Vec2;

use super::texture::sample_texture;
use super::vertex_color::interpolate_vertex_color;
use crate::scene::features::{FEATURE_ALPHA_CUTOUT, FEATURE_UVS};
use crate::scene::{Features, SceneSource, SceneView, INVALID_INDEX, MATERIAL_ALPHA_CUTOUT};

/// Interpolated texture coordinates of `triangle` at barycentrics (`b1`, `b2`); zero when the scene has no
/// texture coordinates.
#[inline]
#[must_use]
pub fn interpolate_uv<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    b1: f32,
    b2: f32,
) -> Vec2 {
    if !scene.features.has(FEATURE_UVS) || scene.geometry.uvs.is_empty() {
        return Vec2::ZERO;
    }
    let v = source.triangle_info(scene, triangle).vertices;
    let t0 = Vec2::from(source.uv(scene, v[0]));
    let t1 = Vec2::from(source.uv(scene, v[1]));
    let t2 = Vec2::from(source.uv(scene, v[2]));
    t0 * (1.0 - b1 - b2) + t1 * b1 + t2 * b2
}

/// Whether the point at barycentrics (`b1`, `b2`) of `triangle` is cut out (its opacity is below the
/// material's cutoff): the base colour's alpha times the texture's and the vertex colours' (glTF
/// `COLOR_0`). Materials without [`MATERIAL_ALPHA_CUTOUT`] are never cut out.
#[must_use]
pub fn is_cut_out<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    b1: f32,
    b2: f32,
) -> bool {
    let material = &source.material(scene, source.triangle_info(scene, triangle).material);
    if !scene.features.has(FEATURE_ALPHA_CUTOUT) || material.flags & MATERIAL_ALPHA_CUTOUT == 0 {
        return false;
    }
    let mut alpha = material.base_color[3];
    if material.alpha_texture != INVALID_INDEX || material.base_color_texture != INVALID_INDEX {
        let uv = interpolate_uv(scene, source, triangle, b1, b2);
        let texture = if material.alpha_texture != INVALID_INDEX {
            material.alpha_texture
        } else {
            material.base_color_texture
        };
        alpha *= sample_texture(scene, source, texture, uv).w;
    }
    alpha *= interpolate_vertex_color(scene, source, triangle, b1, b2).w;
    alpha < material.alpha_cutoff
}
