//! The shading point of a ray hit: position, geometric and shading normals, texture coordinates and the
//! Disney parameters with textures applied.
use glam::{Vec2, Vec3};

use super::alpha::interpolate_uv;
use super::texture::sample_texture;
use crate::bsdf::DisneyParams;
use crate::bvh::traverse::Hit;
use crate::lights::triangle::{scaled_geometric_normal, triangle_vertices};
use crate::math::{vec3_from, Frame};
use crate::scene::{SceneView, INVALID_INDEX};

/// Everything the integrator needs at a hit point.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position, interpolated from the vertices (more precise than `origin + t · direction`).
    pub position: Vec3,
    /// Unit geometric normal of the front face (counter-clockwise winding).
    pub geometric_normal: Vec3,
    /// Shading frame; `z` is the shading normal on the same side as `geometric_normal`.
    pub frame: Frame,
    pub uv: Vec2,
    pub params: DisneyParams,
}

/// Builds the shading point for `hit` (which must be a hit).
#[must_use]
pub fn surface_point(scene: &SceneView, hit: &Hit) -> SurfacePoint {
    let triangle = hit.triangle;
    let (b1, b2) = (hit.b1, hit.b2);
    let b0 = 1.0 - b1 - b2;
    let v = triangle_vertices(scene, triangle);
    let position = v[0] * b0 + v[1] * b1 + v[2] * b2;
    let ng = scaled_geometric_normal(&v).normalize_or(Vec3::Z);
    let info = scene.triangle_info[triangle as usize];
    let material = scene.materials[info.material as usize];
    let uv = interpolate_uv(scene, triangle, b1, b2);

    // Interpolated vertex normal, if the scene has them for all three vertices.
    let mut ns = ng;
    if !scene.normals.is_empty() {
        let n0 = vec3_from(scene.normals[info.vertices[0] as usize]);
        let n1 = vec3_from(scene.normals[info.vertices[1] as usize]);
        let n2 = vec3_from(scene.normals[info.vertices[2] as usize]);
        if n0 != Vec3::ZERO && n1 != Vec3::ZERO && n2 != Vec3::ZERO {
            let n = (n0 * b0 + n1 * b1 + n2 * b2).normalize_or(ng);
            ns = if n.dot(ng) < 0.0 { -n } else { n };
        }
    }

    // Tangent from the texture parameterisation (pbrt-v4 §6.5.3); used by normal maps and anisotropy.
    let mut tangent = Vec3::ZERO;
    if !scene.uvs.is_empty() {
        let t0 = Vec2::from(scene.uvs[info.vertices[0] as usize]);
        let t1 = Vec2::from(scene.uvs[info.vertices[1] as usize]);
        let t2 = Vec2::from(scene.uvs[info.vertices[2] as usize]);
        let duv1 = t1 - t0;
        let duv2 = t2 - t0;
        let det = duv1.x * duv2.y - duv1.y * duv2.x;
        if det.abs() > 1e-20 {
            tangent = ((v[1] - v[0]) * duv2.y - (v[2] - v[0]) * duv1.y) / det;
        }
    }

    let mut frame = Frame::from_normal_tangent(ns, tangent);
    if material.normal_texture != INVALID_INDEX && tangent != Vec3::ZERO {
        let t = sample_texture(scene, material.normal_texture, uv);
        let m = Vec3::new(
            (2.0 * t.x - 1.0) * material.normal_scale,
            (2.0 * t.y - 1.0) * material.normal_scale,
            2.0 * t.z - 1.0,
        );
        let mapped = frame.to_world(m).normalize_or(ns);
        let mapped = if mapped.dot(ng) < 0.0 { ns } else { mapped };
        frame = Frame::from_normal_tangent(mapped, tangent);
    }

    let mut base_color = vec3_from(material.base_color);
    if material.base_color_texture != INVALID_INDEX {
        base_color *= sample_texture(scene, material.base_color_texture, uv).truncate();
    }
    let mut metallic = material.metallic;
    let mut roughness = material.roughness;
    if material.metallic_roughness_texture != INVALID_INDEX {
        let t = sample_texture(scene, material.metallic_roughness_texture, uv);
        roughness *= t.y;
        metallic *= t.z;
    }
    let params = DisneyParams {
        base_color,
        metallic,
        roughness,
        anisotropic: material.anisotropic,
        specular: material.specular,
        specular_tint: material.specular_tint,
        sheen: material.sheen,
        sheen_tint: material.sheen_tint,
        clearcoat: material.clearcoat,
        clearcoat_gloss: material.clearcoat_gloss,
    };
    SurfacePoint {
        position,
        geometric_normal: ng,
        frame,
        uv,
        params,
    }
}
