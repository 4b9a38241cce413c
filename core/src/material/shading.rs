//! The shading point of a ray hit: position, geometric and shading normals, texture coordinates and the
//! Disney parameters with textures applied.
use glam::{Vec2, Vec3};

use super::alpha::interpolate_uv;
use super::tangent::{decode_tangent, has_tangent, NO_TANGENT};
use super::texture::sample_texture_lod;
use super::vertex_color::interpolate_vertex_color;
use crate::bsdf::DisneyParams;
use crate::geometry::triangle::{scaled_geometric_normal, triangle_vertices};
use crate::geometry::Hit;
use crate::math::{vec3_from, Frame};
use crate::scene::features::{
    FEATURE_BASE_COLOR_TEXTURE, FEATURE_EXTENSION_TEXTURES, FEATURE_LOBE_ANISOTROPY,
    FEATURE_METALLIC_ROUGHNESS_TEXTURE, FEATURE_NORMAL_TEXTURE, FEATURE_SHADING_NORMALS,
    FEATURE_UVS, FEATURE_VOLUME_ABSORPTION,
};
use crate::scene::{
    Features, Material, SceneSource, SceneView, EXTENSION_TEXTURES, INVALID_INDEX,
    MATERIAL_LAMBERTIAN, MATERIAL_THIN_WALLED,
};

/// Everything the integrator needs at a hit point.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position, interpolated from the vertices (more precise than `origin + t · direction`).
    pub position: Vec3,
    /// The triangle's largest absolute vertex coordinate, which scales the ray offsets
    /// ([`crate::geometry::offset::offset_ray_origin`]).
    pub magnitude: f32,
    /// Unit geometric normal of the front face (counter-clockwise winding).
    pub geometric_normal: Vec3,
    /// Shading frame; `z` is the shading normal on the same side as `geometric_normal`.
    pub frame: Frame,
    /// The interpolated vertex normal before the normal map (`frame.z` where there is none), for
    /// views the mapped normal turns away from (`crate::integrator::path`).
    pub unmapped_normal: Vec3,
    pub uv: Vec2,
    /// The width of the ray cone's footprint in texture coordinates, which the textures were read
    /// over (0: mip level 0).
    pub footprint_uv: f32,
    pub params: DisneyParams,
    /// The absorption coefficient of the material's inside ([`Material::absorption`]); zero for scenes
    /// without volume absorption.
    pub absorption: Vec3,
}

/// The Disney parameters of `material`'s factors, before any texture.
#[inline]
#[must_use]
pub fn material_params(material: &Material) -> DisneyParams {
    DisneyParams {
        base_color: vec3_from(material.base_color),
        metallic: material.metallic,
        roughness: material.roughness,
        anisotropic: material.anisotropic,
        specular: material.specular,
        specular_tint: material.specular_tint,
        sheen: material.sheen,
        sheen_tint: material.sheen_tint,
        clearcoat: material.clearcoat,
        clearcoat_gloss: material.clearcoat_gloss,
        lambertian: material.flags & MATERIAL_LAMBERTIAN != 0,
        transmission: material.transmission,
        ior: material.ior,
        thin_walled: material.flags & MATERIAL_THIN_WALLED != 0,
    }
}

/// Builds the shading point for `hit` (which must be a hit), every texture read at mip level 0.
#[must_use]
pub fn surface_point<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    hit: &Hit,
) -> SurfacePoint {
    surface_point_lod(scene, source, hit, Vec3::Z, 0.0)
}

/// [`surface_point`] for a ray along `direction` whose cone is `cone_width` wide at the hit (0: mip level
/// 0): the textures are read at the level of the cone's footprint (`crate::material::texture`).
///
/// Long because it evaluates each material input in turn (base colour, alpha, normal map,
/// metallic-roughness, emission, the extensions' values) from one hit and its texture coordinates,
/// which every piece would need.
#[must_use]
pub fn surface_point_lod<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    hit: &Hit,
    direction: Vec3,
    cone_width: f32,
) -> SurfacePoint {
    let triangle = hit.triangle;
    let (b1, b2) = (hit.b1, hit.b2);
    let b0 = 1.0 - b1 - b2;
    let v = triangle_vertices(scene, source, triangle);
    let position = v[0] * b0 + v[1] * b1 + v[2] * b2;
    let magnitude = crate::geometry::offset::triangle_magnitude(&v);
    let ng = scaled_geometric_normal(&v).normalize_or(Vec3::Z);
    let info = source.triangle_info(scene, triangle);
    let material = source.material(scene, info.material);
    let uv = interpolate_uv(scene, source, triangle, b1, b2);
    // The cone's footprint in texture coordinates: width / |cos| on the surface, times the triangle's
    // texture-to-surface scale sqrt(A_uv / A_world) (Akenine-Möller et al. 2019). Only textured
    // materials need it.
    let mut footprint_uv = 0.0;
    if cone_width > 0.0 && scene.features.has(FEATURE_UVS) && !scene.geometry.uvs.is_empty() {
        let t0 = Vec2::from(source.uv(scene, info.vertices[0]));
        let t1 = Vec2::from(source.uv(scene, info.vertices[1]));
        let t2 = Vec2::from(source.uv(scene, info.vertices[2]));
        let uv_area = (t1 - t0).perp_dot(t2 - t0).abs();
        let world_area = scaled_geometric_normal(&v).length();
        let cos = ng.dot(direction.normalize_or_zero()).abs().max(0.01);
        let scale = crate::math::float::sqrt(uv_area / world_area);
        if scale.is_finite() {
            footprint_uv = cone_width / cos * scale;
        }
    }

    // Interpolated vertex normal, if the scene has them for all three vertices.
    let mut ns = ng;
    // The vertices' encoded tangents, which ride in the normals' `w` (`super::tangent`).
    let mut tangent_words = (NO_TANGENT, NO_TANGENT, NO_TANGENT);
    // Whether the interpolated normal was turned to the geometric normal's side (which turns the
    // bitangent `n × t` of the vertex tangents' handedness too).
    let mut normal_flipped = false;
    if scene.features.has(FEATURE_SHADING_NORMALS) && !scene.geometry.normals.is_empty() {
        let r0 = source.normal(scene, info.vertices[0]);
        let r1 = source.normal(scene, info.vertices[1]);
        let r2 = source.normal(scene, info.vertices[2]);
        tangent_words = (r0[3], r1[3], r2[3]);
        let n0 = vec3_from(r0);
        let n1 = vec3_from(r1);
        let n2 = vec3_from(r2);
        if n0 != Vec3::ZERO && n1 != Vec3::ZERO && n2 != Vec3::ZERO {
            let n = (n0 * b0 + n1 * b1 + n2 * b2).normalize_or(ng);
            normal_flipped = n.dot(ng) < 0.0;
            ns = if normal_flipped { -n } else { n };
        }
    }

    // The tangent, for the materials that need one (normal maps and anisotropy): the vertices' own
    // (glTF `TANGENT`, or MikkTSpace's at load) where all three have one, else the triangle's from its
    // texture parameterisation (pbrt-v4 §6.5.3). `handedness` is the bitangent's side (glTF
    // `TANGENT`'s `w`: the normal map's y points along `handedness · (n × t)`), −1 where the texture is
    // mirrored. Other materials are isotropic, so any tangent serves and the normal's own frame is used
    // (cheaper, and independent of whether the scene has texture coordinates).
    let needs_tangent = (scene.features.has(FEATURE_NORMAL_TEXTURE)
        && material.normal_texture != INVALID_INDEX)
        || (scene.features.has(FEATURE_LOBE_ANISOTROPY) && !(material.anisotropic == 0.0));
    let mut tangent = Vec3::ZERO;
    let mut handedness = 1.0;
    let (w0, w1, w2) = tangent_words;
    if needs_tangent && has_tangent(w0) && has_tangent(w1) && has_tangent(w2) {
        let (t0, s0) = decode_tangent(w0);
        let (t1, _) = decode_tangent(w1);
        let (t2, _) = decode_tangent(w2);
        tangent = (t0 * b0 + t1 * b1 + t2 * b2).normalize_or_zero();
        handedness = if normal_flipped { -s0 } else { s0 };
    } else if needs_tangent && scene.features.has(FEATURE_UVS) && !scene.geometry.uvs.is_empty() {
        let t0 = Vec2::from(source.uv(scene, info.vertices[0]));
        let t1 = Vec2::from(source.uv(scene, info.vertices[1]));
        let t2 = Vec2::from(source.uv(scene, info.vertices[2]));
        let duv1 = t1 - t0;
        let duv2 = t2 - t0;
        let det = duv1.x * duv2.y - duv1.y * duv2.x;
        if det.abs() > 1e-20 {
            // Only the directions are used: multiply by the determinant's sign and normalise instead
            // of dividing by it, which overflows for tiny determinants (zero if the length over- or
            // underflows, and then the frame falls back to `Frame::from_normal`).
            let e1 = v[1] - v[0];
            let e2 = v[2] - v[0];
            tangent = ((e1 * duv2.y - e2 * duv1.y) * det.signum()).normalize_or_zero();
            // glTF's v runs down the image and a normal map's y up it (its "+Y is up"): a texture
            // that shows upright has ∂p/∂v = −(n × t), and a mirrored one the opposite.
            let dp_dv = (e2 * duv1.x - e1 * duv2.x) * det.signum();
            if ns.cross(tangent).dot(dp_dv) > 0.0 {
                handedness = -1.0;
            }
        }
    }

    let mut frame = Frame::from_normal_tangent(ns, tangent);
    if scene.features.has(FEATURE_NORMAL_TEXTURE)
        && material.normal_texture != INVALID_INDEX
        && tangent != Vec3::ZERO
    {
        let t = sample_texture_lod(scene, source, material.normal_texture, uv, footprint_uv);
        let m = Vec3::new(
            (2.0 * t.x - 1.0) * material.normal_scale,
            (2.0 * t.y - 1.0) * material.normal_scale * handedness,
            2.0 * t.z - 1.0,
        );
        let mapped = frame.to_world(m).normalize_or(ns);
        let mapped = if mapped.dot(ng) < 0.0 { ns } else { mapped };
        frame = Frame::from_normal_tangent(mapped, tangent);
    }

    let base_color = base_color_at(
        scene,
        source,
        triangle,
        &material,
        uv,
        [b1, b2],
        footprint_uv,
    );
    let mut metallic = material.metallic;
    let mut roughness = material.roughness;
    if scene.features.has(FEATURE_METALLIC_ROUGHNESS_TEXTURE)
        && material.metallic_roughness_texture != INVALID_INDEX
    {
        let t = sample_texture_lod(
            scene,
            source,
            material.metallic_roughness_texture,
            uv,
            footprint_uv,
        );
        roughness *= t.y;
        metallic *= t.z;
    }
    let mut params = DisneyParams {
        base_color,
        metallic,
        roughness,
        ..material_params(&material)
    };
    if scene.features.has(FEATURE_EXTENSION_TEXTURES) && material.has_extension_texture() {
        apply_extension_textures(scene, source, &material, uv, footprint_uv, &mut params);
    }
    // Only a refracting interface (transmissive, not a thin wall) encloses a volume.
    let absorption = if scene.features.has(FEATURE_VOLUME_ABSORPTION)
        && params.transmission > 0.0
        && !params.thin_walled
    {
        Vec3::from(material.absorption)
    } else {
        Vec3::ZERO
    };
    SurfacePoint {
        position,
        magnitude,
        geometric_normal: ng,
        frame,
        unmapped_normal: ns,
        uv,
        footprint_uv,
        params,
        absorption,
    }
}

/// The base colour of `material` at barycentrics `b` (of `v1`, `v2`) of `triangle`, where the texture
/// coordinates are `uv`: its factor times its texture, read over `footprint_uv` in texture coordinates
/// (0: mip level 0), times the vertex colour. [`surface_point_lod`]'s, alone:
/// `crate::temporal::gbuffer` averages it over a pixel.
#[inline]
#[must_use]
pub fn base_color_at<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    triangle: u32,
    material: &Material,
    uv: Vec2,
    b: [f32; 2],
    footprint_uv: f32,
) -> Vec3 {
    let mut base_color = vec3_from(material.base_color);
    if scene.features.has(FEATURE_BASE_COLOR_TEXTURE)
        && material.base_color_texture != INVALID_INDEX
    {
        base_color *=
            sample_texture_lod(scene, source, material.base_color_texture, uv, footprint_uv)
                .truncate();
    }
    base_color * interpolate_vertex_color(scene, source, triangle, b[0], b[1]).truncate()
}

/// Multiplies the factors of `params` by the glTF material extensions' textures of `material`, each by
/// the channel its extension's specification names: `KHR_materials_transmission` R,
/// `KHR_materials_clearcoat` R (factor) and G (roughness), `KHR_materials_sheen` RGB (Burley's sheen is a
/// weight: the largest component), `KHR_materials_specular` A (weight) and RGB (colour, largest
/// component), `KHR_materials_anisotropy` B (strength).
///
/// One loop over the slots, so that the kernel holds one inlined texture lookup rather than seven
/// (which made the general kernel's SPIR-V four times larger and lavapipe's pipeline build time out).
fn apply_extension_textures<F: Features, S: SceneSource>(
    scene: &SceneView<F>,
    source: &S,
    material: &Material,
    uv: Vec2,
    footprint_uv: f32,
    params: &mut DisneyParams,
) {
    let mut slot = 0;
    while slot < EXTENSION_TEXTURES {
        let index = material.extension_texture(slot);
        if index != INVALID_INDEX {
            let t = sample_texture_lod(scene, source, index, uv, footprint_uv);
            match slot {
                0 => params.transmission *= t.x,
                1 => params.clearcoat *= t.x,
                2 => params.clearcoat_gloss = 1.0 - (1.0 - params.clearcoat_gloss) * t.y,
                3 => params.sheen *= t.truncate().max_element(),
                4 => params.specular *= t.w,
                5 => params.specular *= t.truncate().max_element(),
                _ => params.anisotropic *= t.z,
            }
        }
        slot += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{GeometryArrays, Material, MaterialArrays, TriangleInfo, TrianglePositions};

    /// Tangent frames stay finite and orthonormal for texture parameterisations whose determinant is
    /// tiny (just above the 1e-20 cut-off) next to large edges, where the squared length of
    /// `edge / det` overflows `f32` (which left a zero tangent axis before).
    #[test]
    fn tangent_frame_is_finite_for_tiny_uv_determinants() {
        let scale = 1.0e10f32;
        let tri = TrianglePositions {
            v0: Vec3::ZERO.extend(0.0),
            v1: Vec3::new(scale, 0.0, 0.0).extend(0.0),
            v2: Vec3::new(0.0, scale, 0.0).extend(0.0),
        };
        let (blocks, lanes) = crate::test_support::one_triangle_per_block(&[tri], &[]);
        let info = TriangleInfo {
            vertices: [0, 1, 2],
            material: 0,
        };
        let materials = [Material {
            anisotropic: 0.9,
            ..Material::default()
        }];
        for d in [1e-19f32, 1.2e-10, 1e-3, 1.0] {
            // det = duv1.x * duv2.y - duv1.y * duv2.x = d * d.
            let uvs = [[0.0, 0.0], [d, 0.0], [0.0, d]];
            let view = SceneView {
                geometry: GeometryArrays {
                    blocks: &blocks,
                    triangle_lanes: &lanes,
                    triangle_info: core::slice::from_ref(&info),
                    uvs: &uvs,
                    ..GeometryArrays::default()
                },
                materials: MaterialArrays {
                    list: &materials,
                    ..MaterialArrays::default()
                },
                ..SceneView::empty()
            };
            let hit = Hit {
                t: 1.0,
                triangle: 0,
                b1: 0.25,
                b2: 0.25,
            };
            let s = surface_point(&view, &crate::scene::SceneSlices, &hit);
            let f = s.frame;
            for v in [f.x, f.y, f.z] {
                assert!(
                    v.is_finite() && (v.length() - 1.0).abs() < 1e-5,
                    "{d}: {f:?}"
                );
            }
            assert!(f.x.dot(f.y).abs() < 1e-5 && f.x.dot(f.z).abs() < 1e-5);
            // For a proper parameterisation the tangent follows +u (here +x).
            if d * d > 1e-20 {
                assert!(f.x.dot(Vec3::X) > 0.999, "{d}: {f:?}");
            }
        }
    }
}
